#!/usr/bin/python3
"""The trade table's pressure axis: the wall pressure of Buchner (2002)'s dam break at P1 and P2 for each
solver and density model, with what each costs, run by turns in one invocation.

For each configuration it runs `sphxr --headless --scene scenes/buchner_2002.json --probes F.csv` (the
scene's own sensors, read every 1 ms), averages the readings over 5 ms windows (a dry reading counts as
0, as a sensor in air reads), and judges them as tests/validation/buchner_test.cpp does: P1's first rise
through 0.1 rho g H against the measured one, the RMS of (probe - measured) over t sqrt(g/H) in [2.5, 7]
against the measured maximum at P1 and P2, the RMS change of P1 between consecutive windows over
[3.5, 6] in rho g H beside the measured curve's own (the scatter), the clamps per 1,000 particle-steps,
and the wall seconds per simulated second of the run itself (its summary).

Usage: bench/pressure.py [--threads T] [--csv FILE] [--only NAME,...]
  (default 2 threads, bench/results/pressure.csv; configurations: wcsph_summation, wcsph_delta_sph,
  dfsph, pbf)
Time it with nothing else running: the load before and after each row is in the CSV.
"""
import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
H, G = 0.6, 9.81
WINDOW = 0.005
CONFIGS = [
    ("wcsph_summation", ["--set", "density=summation"]),
    ("wcsph_delta_sph", ["--set", "density=delta_sph"]),
    ("dfsph", ["--set", "method=dfsph"]),
    ("pbf", ["--set", "method=pbf"]),
]


def read_measured(name):
    out = []
    with open(os.path.join(ROOT, "tests", "data", "buchner_2002_%s.csv" % name)) as f:
        for line in f:
            if not line.strip() or line.startswith("#") or line.startswith("time"):
                continue
            t, v = line.split(",")[:2]
            out.append((float(t), float(v)))
    return out


def interpolate(series, t):
    if t <= series[0][0]:
        return series[0][1]
    for (t0, v0), (t1, v1) in zip(series, series[1:]):
        if t1 >= t:
            return v0 + (t - t0) / (t1 - t0) * (v1 - v0)
    return series[-1][1]


def first_crossing(series, level):
    for (t0, v0), (t1, v1) in zip(series, series[1:]):
        if v0 < level <= v1:
            return t0 + (level - v0) / (v1 - v0) * (t1 - t0)
    return float("nan")


def windows(probe_csv):
    """5 ms averages of P1 and P2 in rho g H against t sqrt(g/H) at the window's centre."""
    scale_t, scale_p = math.sqrt(G / H), 1000.0 * G * H
    rows = list(csv.DictReader(open(probe_csv)))
    out = {"P1": [], "P2": []}
    k = 1
    while True:
        inside = [r for r in rows if (k - 1) * WINDOW < float(r["time"]) <= k * WINDOW + 1e-9]
        if not inside:
            break
        for s in out:
            values = [float(r[s + "_p"]) if r[s + "_p"] else 0.0 for r in inside]
            out[s].append(((k - 0.5) * WINDOW * scale_t, sum(values) / len(values) / scale_p))
        k += 1
    return out


def rms_against(sim, measured, lo=2.5, hi=7.0):
    peak = max(v for _, v in measured)
    n, sq, t = 0, 0.0, lo
    while t <= hi + 1e-9:
        d = interpolate(sim, t) - interpolate(measured, t)
        sq += d * d
        n += 1
        t += 0.01
    return math.sqrt(sq / n) / peak


def scatter(series, lo=3.5, hi=6.0, step=None):
    """RMS change between consecutive 5 ms windows over [lo, hi] (t sqrt(g/H))."""
    if step is not None:  # a curve sampled unevenly: resample at the windows' spacing
        grid, t = [], lo
        while t <= hi + 1e-9:
            grid.append(interpolate(series, t))
            t += step
        values = grid
    else:
        values = [v for t, v in series if lo <= t <= hi]
    changes = [b - a for a, b in zip(values, values[1:])]
    return math.sqrt(sum(c * c for c in changes) / len(changes))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--csv", default=os.path.join(ROOT, "bench", "results", "pressure.csv"))
    ap.add_argument("--only", default="")
    args = ap.parse_args()
    binary = os.environ.get("SPHXR", os.path.join(ROOT, "build", "app", "sphxr"))
    if not os.access(binary, os.X_OK):
        sys.exit("bench/pressure.py: %s not built (./scripts/setup.sh)" % binary)
    wanted = set(args.only.split(",")) if args.only else None
    measured = {s: read_measured(s.lower()) for s in ("P1", "P2")}
    step = WINDOW * math.sqrt(G / H)
    measured_scatter = scatter(measured["P1"], step=step)
    with open("/proc/cpuinfo") as f:
        machine = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name")).replace(",", " ")
    header = ["machine", "threads", "config", "simulated_s", "wall_per_simulated_s", "steps", "p1_first_rise",
              "p1_first_rise_measured", "p1_rms_of_max", "p2_rms_of_max", "p1_window_change_rho_g_h",
              "p1_window_change_measured", "clamps_per_1000", "load_before", "load_after"]
    with open(args.csv, "w", newline="") as out, tempfile.TemporaryDirectory() as tmp:
        w = csv.writer(out)
        w.writerow(header)
        for name, extra in CONFIGS:
            if wanted and name not in wanted:
                continue
            probes = os.path.join(tmp, name + ".csv")
            load0 = open("/proc/loadavg").read().split()[0]
            run = subprocess.run([binary, "--headless", "--scene", os.path.join(ROOT, "scenes", "buchner_2002.json"),
                                  "--threads", str(args.threads), "--no-progress", "--probes", probes] + extra,
                                 capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="active"))
            load1 = open("/proc/loadavg").read().split()[0]
            if run.returncode != 0:
                sys.exit("bench/pressure.py: %s failed: %s" % (name, run.stderr.strip().splitlines()[-1:]))
            text = run.stdout
            sim, wall = re.search(r"simulated time\s+([\d.]+) s in ([\d.]+) s wall", text).groups()
            steps = re.search(r"steps\s+(\d+)", text).group(1)
            clamps = re.search(r"([\d.e+-]+) per 1,000 particle-steps", text)
            series = windows(probes)
            row = [machine, args.threads, name, sim, "%.2f" % (float(wall) / float(sim)), steps,
                   "%.3f" % first_crossing(series["P1"], 0.1), "%.3f" % first_crossing(measured["P1"], 0.1),
                   "%.3f" % rms_against(series["P1"], measured["P1"]), "%.3f" % rms_against(series["P2"], measured["P2"]),
                   "%.3f" % scatter(series["P1"]), "%.3f" % measured_scatter,
                   clamps.group(1) if clamps else "0", load0, load1]
            w.writerow(row)
            out.flush()
            print(",".join(str(v) for v in row), flush=True)


if __name__ == "__main__":
    main()
