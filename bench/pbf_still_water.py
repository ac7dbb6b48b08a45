#!/usr/bin/python3
"""PBF's still water against the real-time targets (mean compression below 1 %, mean speed below
5 mm/s, 1 s after the lattice): what each of the two costs, in one invocation. No timings.

1. The compression against substeps S and iterations N: `tank_rest` (20 layers of 1 cm) from the lattice
   under PBF at S x N, 1 simulated s; the mean compression (the stats' mean density error) and the mean
   speed. A Jacobi iteration carries a correction about one support, so the steady compression under a
   column should fall as 1 / (S^2 N) (docs/design/pbf.md); the column `s2n_times_compression` shows
   whether it does.
2. The calm against XSPH's c: the same still water at the defaults' 3 x 3 with pbf_xsph = c, and what
   the same c takes from stirred water: `stir` after 4 s, kinetic energy per mass and mean speed, with
   WCSPH's beside it.

Usage: bench/pbf_still_water.py [--threads T] [--csv FILE]
  (default 2 threads, bench/results/pbf_still_water.csv)
"""
import argparse
import csv
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GRID = [(3, 3), (3, 6), (4, 4), (3, 10), (4, 6), (5, 4), (6, 3)]
XSPH = [0.01, 0.02, 0.05, 0.1]
STILL_TIME = 1.0
STIR_TIME = 4.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--csv", default=os.path.join(ROOT, "bench", "results", "pbf_still_water.csv"))
    args = ap.parse_args()
    binary = os.environ.get("SPHXR", os.path.join(ROOT, "build", "app", "sphxr"))
    python_dir = os.path.join(os.path.dirname(os.path.dirname(binary)), "python")
    if not os.path.isdir(python_dir):
        sys.exit("bench/pbf_still_water.py: %s not built (./scripts/setup.sh)" % python_dir)
    sys.path.insert(0, python_dir)
    import numpy as np
    import sphxr
    sphxr.set_log_level("error")
    with open("/proc/cpuinfo") as f:
        machine = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name")).replace(",", " ")
    tank = os.path.join(ROOT, "scenes", "tank_rest.json")

    def still(settings):
        run = sphxr.Run(tank, set=dict({"method": "pbf"}, **settings), threads=args.threads, settle=0)
        run.run_to(STILL_TIME)
        speed = np.linalg.norm(run.particles()["velocities"], axis=1)
        return float(run.stats()["mean_density_error"][-1]), float(np.mean(speed))

    def stirred(settings):
        run = sphxr.Run("stir", set=settings, threads=args.threads, settle=0)
        run.run_to(STIR_TIME)
        speed = np.linalg.norm(run.particles()["velocities"], axis=1)
        return 0.5 * float(np.mean(speed ** 2)), float(np.mean(speed))

    header = ["machine", "threads", "study", "substeps", "iterations", "pbf_xsph", "mean_compression_pct_at_1s",
              "s2n_times_compression", "mean_speed_mm_s_at_1s", "stir_kinetic_energy_mj_per_kg_at_4s",
              "stir_mean_speed_mm_s_at_4s"]
    rows = []
    for s, n in GRID:
        c, v = still({"pbf_substeps": s, "pbf_iterations": n})
        rows.append([machine, args.threads, "substeps_iterations", s, n, 0.01, "%.3f" % (100 * c),
                     "%.1f" % (s * s * n * 100 * c), "%.2f" % (1e3 * v), "", ""])
        print("%d x %d: compression %.2f %%, S^2 N C %.1f %%, mean speed %.1f mm/s" % (s, n, 100 * c, s * s * n * 100 * c,
                                                                                   1e3 * v), flush=True)
    for x in XSPH:
        c, v = still({"pbf_xsph": x})
        e, u = stirred({"method": "pbf", "pbf_xsph": x})
        rows.append([machine, args.threads, "xsph", 3, 3, x, "%.3f" % (100 * c), "", "%.2f" % (1e3 * v),
                     "%.2f" % (1e3 * e), "%.1f" % (1e3 * u)])
        print("xsph %g: still water %.1f mm/s; stir %.1f mJ/kg, %.0f mm/s" % (x, 1e3 * v, 1e3 * e, 1e3 * u), flush=True)
    e, u = stirred({"method": "wcsph"})
    rows.append([machine, args.threads, "wcsph", "", "", "", "", "", "", "%.2f" % (1e3 * e), "%.1f" % (1e3 * u)])
    print("wcsph: stir %.1f mJ/kg, %.0f mm/s" % (1e3 * e, 1e3 * u), flush=True)
    with open(args.csv, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)
    print("wrote " + args.csv)


if __name__ == "__main__":
    main()
