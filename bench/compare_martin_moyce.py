#!/usr/bin/env python3
"""Compare `sphxr --headless --stats FILE.csv` runs of a dam-break scene with Martin & Moyce (1952).

Usage: /usr/bin/python3 bench/compare_martin_moyce.py [--data CSV] RUN.csv [RUN.csv ...]

For each run, as tests/validation/dam_break_test.cpp judges it (sim::JudgeMartinMoyce, sim/measure.h):
the experiment's gate lag, one time shift t0 for both series chosen in [0, 22 ms] (the experiment's first
front time) to minimise the summed squared relative deviations, then the relative deviation (%) of the
residual column height H at every measured tau <= 3 and of the surge front Z at every measured
1 <= T <= 3.3, with the front's RMS; the same without the shift for comparison. The same points and the
same linear interpolation in time as the test; the stats file's front_Z and
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
        to_tau, to_big_t = math.sqrt(G / A), math.sqrt(2.0 * G / A)
        t_end = t[-1]
        fronts_m = [(m, v) for m, v in measured["front"] if 1.0 <= m <= 3.3 and m / to_big_t <= t_end]
        heights_m = [(m, v) for m, v in measured["height"] if m <= 3.0 and m / to_tau <= t_end]
        if not fronts_m:
            print(f"{path}: the run ends before T = 1", file=sys.stderr)
            return 1

        def deviations(lag):
            fr = [100.0 * (interpolate(t, z, m / to_big_t - lag) - v) / v for m, v in fronts_m]
            hs = [(m, 100.0 * (interpolate(t, h, m / to_tau - lag) - v) / v) for m, v in heights_m]
            return fr, hs

        limit = measured["front"][0][0] / to_big_t
        steps = math.ceil(limit / 5e-5)
        lag = min((limit * k / steps for k in range(steps + 1)),
                  key=lambda L: sum(x * x for x in deviations(L)[0]) + sum(d * d for _, d in deviations(L)[1]))
        print(path)
        for label, shift in (("no shift", 0.0), (f"gate lag {1e3 * lag:.2f} ms", lag)):
            fronts, heights = deviations(shift)
            rms = math.sqrt(sum(x * x for x in fronts) / len(fronts))
            print(f"  {label}:")
            print("    H  (tau: %):", " ".join(f"{m:.2f}:{d:+.1f}" for m, d in heights))
            print(f"    Z  (%, T = {fronts_m[0][0]:.2f} ... {fronts_m[-1][0]:.2f}):", " ".join(f"{d:+.1f}" for d in fronts),
                  f"| max {max(fronts, key=abs):+.1f}, RMS {rms:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
