"""An irregular survey made from a regular SEG-Y (issue 42, never run by the tests): the
traces of a triangular corner left out (about a tenth of them) and the inline numbers
renumbered to steps of 2, written inline-sorted (the usual order) or crossline-sorted
(`--crossline-sorted`), streamed a trace at a time. Assumes a post-stack file with
inline and crossline at trace bytes 189 and 193, big-endian, no extended headers.

    python3 benches/store/irregular.py REGULAR.sgy OUT.sgy [--crossline-sorted]
"""
import sys

import numpy as np


def main():
    src, out = sys.argv[1], sys.argv[2]
    by_crossline = "--crossline-sorted" in sys.argv[3:]
    raw = np.memmap(src, np.uint8, mode="r")
    ns = int.from_bytes(raw[3220:3222].tobytes(), "big")
    code = int.from_bytes(raw[3224:3226].tobytes(), "big")
    width = {1: 4, 2: 4, 3: 2, 5: 4, 8: 1}[code]
    tl = 240 + ns * width
    traces = raw[3600:].reshape(-1, tl)
    il = traces[:, 188:192].copy().view(">i4").ravel()
    xl = traces[:, 192:196].copy().view(">i4").ravel()
    ki = np.searchsorted(np.unique(il), il)
    jx = np.searchsorted(np.unique(xl), xl)
    nk, nj = ki.max() + 1, jx.max() + 1
    # A triangle off the first inlines' first crosslines: about a tenth of the traces.
    keep = (ki / nk + jx / nj) > 0.45
    order = np.lexsort((ki, jx)) if by_crossline else np.arange(len(ki))
    new_il = (1000 + 2 * ki).astype(">i4")
    with open(out, "wb") as f:
        f.write(raw[:3600].tobytes())
        block = []
        for t in order:
            if not keep[t]:
                continue
            rec = traces[t].copy()
            rec[188:192] = np.frombuffer(new_il[t:t + 1].tobytes(), np.uint8)
            block.append(rec)
            if len(block) == 4096:
                f.write(np.concatenate(block).tobytes())
                block = []
        if block:
            f.write(np.concatenate(block).tobytes())
    print(f"{out}: {int(keep.sum())} of {len(keep)} traces kept ({nk} inlines x {nj} crosslines)")


if __name__ == "__main__":
    main()
