#!/usr/bin/python3
"""PBF's vorticity confinement against what it costs: `stir` under PBF at several pbf_vorticity values,
and WCSPH's water beside them as the reference, in one invocation.

For each epsilon: the step's cost from `sphxr --headless --scene scenes/stir.json --set method=pbf
--set pbf_vorticity=E --settle 0 --time 1 --threads T` (its summary's ms per step and the integrate
stage, which holds XSPH and the confinement), the values alternated over --rounds rounds; then the
water after 4 simulated s (the Python module: kinetic energy per mass and mean speed over the fluid),
and the same for WCSPH. Confinement that pays would bring PBF's water nearer WCSPH's.

Usage: bench/pbf_vorticity.py [--threads T] [--rounds R] [--csv FILE]
  (default 2 threads, 3 rounds, bench/results/pbf_vorticity.csv)
Time it with nothing else running: the load before and after each row is in the CSV.
"""
import argparse
import csv
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EPSILONS = ["0", "0.05", "0.2", "0.5"]
PHYSICS_TIME = 4.0


def load():
    return open("/proc/loadavg").read().split()[0]


def timed_run(binary, epsilon, threads):
    cmd = [binary, "--headless", "--scene", os.path.join(ROOT, "scenes", "stir.json"), "--set", "method=pbf",
           "--set", "pbf_vorticity=" + epsilon, "--settle", "0", "--time", "1", "--threads", str(threads),
           "--no-progress"]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True)
    text = out.stdout + out.stderr
    total = re.search(r"ms per step\s+([0-9.]+) total", text)
    integrate = re.search(r"integrate ([0-9.]+)", text)
    if not total or not integrate:
        sys.exit("bench/pbf_vorticity.py: no 'ms per step' in the summary of " + " ".join(cmd))
    return total.group(1), integrate.group(1)


def water(sphxr, settings, threads):
    import numpy as np
    run = sphxr.Run("stir", set=settings, threads=threads, settle=0)
    run.run_to(PHYSICS_TIME)
    speed = np.linalg.norm(run.particles()["velocities"], axis=1)
    return "%.2f" % (1e3 * 0.5 * float(np.mean(speed ** 2))), "%.1f" % (1e3 * float(np.mean(speed)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--csv", default=os.path.join(ROOT, "bench", "results", "pbf_vorticity.csv"))
    args = ap.parse_args()
    binary = os.environ.get("SPHXR", os.path.join(ROOT, "build", "app", "sphxr"))
    if not os.access(binary, os.X_OK):
        sys.exit("bench/pbf_vorticity.py: %s not built (./scripts/setup.sh)" % binary)
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(binary)), "python"))
    import sphxr
    sphxr.set_log_level("error")
    with open("/proc/cpuinfo") as f:
        machine = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name")).replace(",", " ")
    header = ["machine", "threads", "config", "kind", "round", "ms_per_step", "integrate_ms",
              "kinetic_energy_mj_per_kg_at_4s", "mean_speed_mm_s_at_4s", "load_before", "load_after"]
    rows = []
    for r in range(args.rounds):
        for e in EPSILONS:
            l0 = load()
            total, integrate = timed_run(binary, e, args.threads)
            rows.append([machine, args.threads, "pbf_vorticity_" + e, "cost", r, total, integrate, "", "", l0, load()])
            print("round %d, pbf_vorticity %s: %s ms a step, integrate %s ms" % (r, e, total, integrate), flush=True)
    for e in EPSILONS:
        l0 = load()
        energy, speed = water(sphxr, {"method": "pbf", "pbf_vorticity": float(e)}, args.threads)
        rows.append([machine, args.threads, "pbf_vorticity_" + e, "water", "", "", "", energy, speed, l0, load()])
        print("pbf_vorticity %s: %s mJ/kg, %s mm/s at %.0f s" % (e, energy, speed, PHYSICS_TIME), flush=True)
    l0 = load()
    energy, speed = water(sphxr, {"method": "wcsph"}, args.threads)
    rows.append([machine, args.threads, "wcsph", "water", "", "", "", energy, speed, l0, load()])
    print("wcsph: %s mJ/kg, %s mm/s at %.0f s" % (energy, speed, PHYSICS_TIME), flush=True)
    with open(args.csv, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)
    print("wrote " + args.csv)


if __name__ == "__main__":
    main()
