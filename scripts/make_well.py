"""Makes the synthetic deviated well through the F3 crop that scenes/data/f3-interpretation.toml
draws: its deviation survey (data/seismic/f3-well-survey.csv) and a synthetic gamma-ray log
along it (data/seismic/f3-well-log.csv).

    python3 scripts/make_well.py data/seismic

Not a real well: F3's public wells lie outside the crop. The survey is a build-and-hold
well drilled from the middle of the crop's map area: vertical to 60 m, building 2 degrees
per 10 m toward azimuth 125 to 36 degrees at 240 m, then held to 330 m, surveyed every
15 m (a station where the build ends). Depth in metres below the datum at the top of the
survey, which a layered scene lines up with the survey's time at 1 m per ms (2000 m/s
two-way). The log is a gamma-ray-like curve every 0.5 m of measured depth: shale and sand
beds (a square wave of uneven beds) with a smooth trend and seeded noise, in API units.
Plain Python, no packages; the same files every run.
"""

import math
import random
import sys


def survey():
    rows = []
    md = 0.0
    while md <= 330.0 + 1e-9:
        inc = min(max(0.0, (md - 60.0) * 0.2), 36.0)
        rows.append((md, inc, 125.0 if inc > 0 else 0.0))
        md += 15.0
    rows.append((240.0, 36.0, 125.0))
    return sorted(set(rows))


def log():
    rng = random.Random(57)
    beds, top = [], 0.0
    while top < 340.0:
        thick = rng.uniform(6.0, 28.0)
        beds.append((top, top + thick, rng.choice([35.0, 45.0, 95.0, 120.0])))
        top += thick
    rows = []
    for i in range(int(330.0 / 0.5) + 1):
        md = i * 0.5
        base = next(v for a, b, v in beds if a <= md < b)
        trend = 10.0 * math.sin(md / 45.0)
        rows.append((md, base + trend + rng.gauss(0.0, 4.0)))
    return rows


def main(folder):
    with open(f"{folder}/f3-well-survey.csv", "w") as out:
        out.write("MD,INC,AZI\n")
        for md, inc, azi in survey():
            out.write(f"{md:.1f},{inc:.2f},{azi:.1f}\n")
    with open(f"{folder}/f3-well-log.csv", "w") as out:
        out.write("MD,GR\n")
        for md, gr in log():
            out.write(f"{md:.1f},{gr:.2f}\n")


if __name__ == "__main__":
    main(sys.argv[1])
