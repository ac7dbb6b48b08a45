#!/usr/bin/env python3
"""Compare `sphxr --headless --stats FILE.csv` runs of a dam-break scene with Martin & Moyce (1952).

Usage: /usr/bin/python3 bench/compare_martin_moyce.py [--data CSV] RUN.csv [RUN.csv ...]

For each run: the relative deviation (%) of the residual column height H at every measured tau <= 3.05,
and of the surge front Z at every measured 1 <= T <= 3.3, with the front's RMS. The same points and the
same linear interpolation in time as tests/validation/dam_break_test.cpp; the stats file's front_Z and
height_H columns are the runner's own measures (app::DamBreakMinPerBin, sim::ConnectedExtent), so the
scene must have a "probe" section. a is read from the data file's header value 0.05715 m.
"""
import csv
import math
import os
import sys

A = 0.05715  # m, the column width of the experiment (the data file's header)
G = 9.81


def read_measured(path):
    out = {"front": [], "height": []}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or line.startswith("series"):
                continue
            series, t, v = line.strip().split(",")
            out[series].append((float(t), float(v)))
    return out


def interpolate(ts, vs, t):
    for i in range(1, len(ts)):
        if ts[i] >= t:
            w = (t - ts[i - 1]) / (ts[i] - ts[i - 1])
            return vs[i - 1] * (1.0 - w) + vs[i] * w
    return float("nan")  # the run ended before t


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    data = os.path.join(here, "..", "..", "shared", "data", "martin_moyce_1952.csv")
    if len(argv) > 1 and argv[0] == "--data":
        data, argv = argv[1], argv[2:]
    if not argv:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    measured = read_measured(data)
    for path in argv:
        with open(path) as f:
            rows = list(csv.DictReader(f))
        if not rows or "front_Z" not in rows[0]:
            print(f"{path}: no front_Z/height_H columns (does the scene have a probe section?)", file=sys.stderr)
            return 1
        t = [float(r["time"]) for r in rows]
        z = [float(r["front_Z"]) for r in rows]
        h = [float(r["height_H"]) for r in rows]
        tau = [x * math.sqrt(G / A) for x in t]
        big_t = [x * math.sqrt(2.0 * G / A) for x in t]
        heights = [(m, 100.0 * (interpolate(tau, h, m) - v) / v) for m, v in measured["height"] if m <= 3.05]
        fronts = [100.0 * (interpolate(big_t, z, m) - v) / v for m, v in measured["front"] if 1.0 <= m <= 3.3]
        rms = math.sqrt(sum(x * x for x in fronts) / len(fronts))
        print(path)
        print("  H  (tau: %):", " ".join(f"{m:.2f}:{d:+.1f}" for m, d in heights))
        print("  Z  (%, T = 1.19 ... 3.11):", " ".join(f"{d:+.1f}" for d in fronts), f"| max {max(fronts, key=abs):+.1f}, RMS {rms:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
