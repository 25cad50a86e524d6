"""Makes the synthetic fault through the F3 crop that scenes/data/f3-interpretation.toml
draws: a GOCAD TSurf (data/seismic/f3-fault.ts) with the fault's throw at each vertex.

    python3 scripts/make_fault.py data/seismic

Not an interpreted fault: the crop (23 inlines by 18 crosslines) is too small to track
one. A normal fault as an interpreter would save one: a plane striking N30E through the
middle of the crop, dipping 60 degrees toward N120E (at 1 m per ms of two-way time, as
the scene lines depth up with time), from 30 to 270 ms, 500 m along strike; a grid of 21
nodes along strike by 13 down dip, two triangles a cell. Its throw (ms) is largest at the
middle, 18 ms, and falls to nothing at the edges (an elliptical displacement profile,
throw = 18 (1 - r^2), r the distance from the middle in half-lengths), written as the
vertices' `throw` property; a band of nodes near the top edge has no throw picked
(`NO_DATA_VALUES`), as interpreters leave tips. Plain Python, no packages; the same file
every run.
"""

import math
import sys

CENTRE = (620400.0, 6074520.0, 150.0)  # x, y (m), time (ms)
STRIKE, DIP = 30.0, 60.0  # degrees from north; degrees from horizontal
HALF_STRIKE, HALF_TIME = 250.0, 120.0  # m along strike, ms down dip
NS, ND = 21, 13  # nodes along strike and down dip
MAX_THROW = 18.0  # ms
NO_DATA = -99999.0


def nodes():
    s = math.radians(STRIKE)
    along = (math.sin(s), math.cos(s))  # unit vector along strike, (east, north)
    down = (math.sin(s + math.pi / 2), math.cos(s + math.pi / 2))  # dip direction
    run = 1.0 / math.tan(math.radians(DIP))  # horizontal metres per ms down dip
    out = []
    for j in range(ND):
        v = -1.0 + 2.0 * j / (ND - 1)  # -1 at the top, 1 at the bottom
        t = CENTRE[2] + v * HALF_TIME
        for i in range(NS):
            u = -1.0 + 2.0 * i / (NS - 1)
            h = (t - CENTRE[2]) * run
            x = CENTRE[0] + u * HALF_STRIKE * along[0] + h * down[0]
            y = CENTRE[1] + u * HALF_STRIKE * along[1] + h * down[1]
            throw = MAX_THROW * max(0.0, 1.0 - u * u - v * v)
            if j == 0 and abs(u) > 0.5:
                throw = NO_DATA
            out.append((x, y, t, throw))
    return out


def main(folder):
    with open(f"{folder}/f3-fault.ts", "w") as out:
        out.write("GOCAD TSurf 1\nHEADER {\nname:F3 crop, fault F1 (synthetic)\n}\n")
        out.write("GOCAD_ORIGINAL_COORDINATE_SYSTEM\nNAME Default\n")
        out.write('AXIS_NAME "X" "Y" "Z"\nAXIS_UNIT "m" "m" "ms"\nZPOSITIVE Depth\n')
        out.write("END_ORIGINAL_COORDINATE_SYSTEM\n")
        out.write(f"PROPERTIES throw\nNO_DATA_VALUES {NO_DATA:.0f}\nPROPERTY_CLASSES throw\n")
        out.write("UNITS ms\nESIZES 1\nTFACE\n")
        for k, (x, y, t, throw) in enumerate(nodes()):
            out.write(f"PVRTX {k + 1} {x:.2f} {y:.2f} {t:.3f} {throw:.3f}\n")
        for j in range(ND - 1):
            for i in range(NS - 1):
                a = j * NS + i + 1
                b, c, d = a + 1, a + NS + 1, a + NS
                out.write(f"TRGL {a} {b} {c}\nTRGL {a} {c} {d}\n")
        out.write("END\n")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "data/seismic")
