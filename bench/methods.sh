#!/usr/bin/env bash
# WCSPH against DFSPH on the same scenes, run by turns in one invocation (this machine's speed drifts:
# compare rows of one run only). For each scene and method: wall seconds per simulated second inside the
# run (the headless summary), steps, the time-averaged mean compression max(0, rho/rho0 - 1) from the
# per-step CSV (weighted by dt), and under DFSPH the mean iterations of its two solves.
#   bench/methods.sh [--threads T] [--reps N] [--csv FILE]   (default bench/results/methods.csv)
# Scenes: dam_break_1m (50,653 particles) for 0.5 s; stir (13,322 particles and a scripted paddle) for 1 s.
# WCSPH runs each scene as it is (dam_break_1m at its fixed 0.5 ms step); DFSPH with --set method=dfsph
# and the adaptive step (fixed_dt=0).
set -euo pipefail
cd "$(dirname "$0")/.."
threads=2 reps=2 csv=bench/results/methods.csv
while [ $# -gt 0 ]; do
  case "$1" in
    --threads) threads=$2; shift 2 ;;
    --reps) reps=$2; shift 2 ;;
    --csv) csv=$2; shift 2 ;;
    *) echo "usage: bench/methods.sh [--threads T] [--reps N] [--csv FILE]" >&2; exit 2 ;;
  esac
done
bin=${SPHXR:-build/app/sphxr}
[ -x "$bin" ] || { echo "bench/methods.sh: $bin not built (./scripts/setup.sh)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
machine=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//; s/,/ /g')
echo "machine,threads,scene,method,rep,fluid,simulated_s,wall_s,wall_per_simulated_s,steps,mean_compression_pct,density_iterations,divergence_iterations" > "$csv"
for rep in $(seq 1 "$reps"); do
  for scene in dam_break_1m stir; do
    time=1.0; [ "$scene" = dam_break_1m ] && time=0.5
    for method in wcsph dfsph; do
      extra=(); [ "$method" = dfsph ] && extra=(--set method=dfsph --set fixed_dt=0)
      OMP_WAIT_POLICY=active "$bin" --headless --scene "scenes/$scene.json" --time "$time" --threads "$threads" \
        --no-progress --stats "$tmp/stats.csv" "${extra[@]}" > "$tmp/summary.txt" 2> "$tmp/log.txt"
      /usr/bin/python3 - "$tmp/summary.txt" "$tmp/stats.csv" "$machine" "$threads" "$scene" "$method" "$rep" >> "$csv" <<'PY'
import csv, re, sys
summary, stats, machine, threads, scene, method, rep = sys.argv[1:]
text = open(summary).read()
fluid = re.search(r"particles\s+(\d+) fluid", text).group(1)
sim, wall = re.search(r"simulated time\s+([\d.]+) s in ([\d.]+) s wall", text).groups()
rows = list(csv.DictReader(open(stats)))
dt = [float(r["dt"]) for r in rows]
comp = sum(float(r["mean_density_error"]) * d for r, d in zip(rows, dt)) / sum(dt)
iters = divs = ""
if "density_iterations" in rows[0]:
    iters = "%.2f" % (sum(float(r["density_iterations"]) for r in rows) / len(rows))
    divs = "%.2f" % (sum(float(r["divergence_iterations"]) for r in rows) / len(rows))
print(",".join([machine, threads, scene, method, rep, fluid, sim, wall, "%.3f" % (float(wall) / float(sim)),
                str(len(rows)), "%.4f" % (100 * comp), iters, divs]))
PY
      tail -1 "$csv"
    done
  done
done
