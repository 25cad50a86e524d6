#!/usr/bin/env python3
"""Whether two PNGs that arbvis wrote hold the same pixels (their image data, decompressed;
the text chunks, which name the scene, may differ).

    python3 same_pixels.py A.png B.png
"""
import struct
import sys
import zlib


def pixels(path):
    data = open(path, "rb").read()
    at, idat = 8, b""
    while at < len(data):
        (n,) = struct.unpack(">I", data[at:at + 4])
        kind = data[at + 4:at + 8]
        if kind in (b"IHDR", b"IDAT"):
            idat += data[at + 8:at + 8 + n]
        at += 12 + n
    # IHDR (size, depth) then the image data, decompressed.
    return idat[:13] + zlib.decompress(idat[13:])


a, b = sys.argv[1], sys.argv[2]
same = pixels(a) == pixels(b)
print(("same pixels: " if same else "DIFFERENT pixels: ") + a + " and " + b)
sys.exit(0 if same else 1)
