#!/usr/bin/env bash
# solver.density "summation" against "delta_sph" on dam_break_1m (50,653 particles, 0.5 s at its fixed
# 0.5 ms step), run by turns in one invocation (this machine's speed drifts: compare rows of one run
# only): wall seconds per simulated second inside the run and ms per step (the headless summary), the
# density stage's share, the time-averaged mean compression, and the clamps per 1,000 particle-steps.
#   bench/density.sh [--threads T] [--reps N] [--csv FILE]   (default bench/results/density.csv)
set -euo pipefail
cd "$(dirname "$0")/.."
threads=2 reps=1 csv=bench/results/density.csv
while [ $# -gt 0 ]; do
  case "$1" in
    --threads) threads=$2; shift 2 ;;
    --reps) reps=$2; shift 2 ;;
    --csv) csv=$2; shift 2 ;;
    *) echo "usage: bench/density.sh [--threads T] [--reps N] [--csv FILE]" >&2; exit 2 ;;
  esac
done
bin=${SPHXR:-build/app/sphxr}
[ -x "$bin" ] || { echo "bench/density.sh: $bin not built (./scripts/setup.sh)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
machine=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//; s/,/ /g')
echo "machine,threads,scene,density,rep,fluid,simulated_s,wall_per_simulated_s,ms_per_step,density_ms,forces_ms,mean_compression_pct,clamps_per_1000,load_before,load_after" > "$csv"
for rep in $(seq 1 "$reps"); do
  for density in summation delta_sph; do
    load0=$(cut -d' ' -f1 /proc/loadavg)
    OMP_WAIT_POLICY=active "$bin" --headless --scene scenes/dam_break_1m.json --time 0.5 --threads "$threads" \
      --no-progress --stats "$tmp/stats.csv" --set density="$density" > "$tmp/summary.txt" 2> "$tmp/log.txt"
    load1=$(cut -d' ' -f1 /proc/loadavg)
    /usr/bin/python3 - "$tmp/summary.txt" "$tmp/stats.csv" "$machine" "$threads" "$density" "$rep" "$load0" "$load1" >> "$csv" <<'PY'
import csv, re, sys
summary, stats, machine, threads, density, rep, load0, load1 = sys.argv[1:]
text = open(summary).read()
fluid = re.search(r"particles\s+(\d+) fluid", text).group(1)
sim, wall = re.search(r"simulated time\s+([\d.]+) s in ([\d.]+) s wall", text).groups()
ms = re.search(r"ms per step\s+([\d.]+) total:.* density ([\d.]+) forces ([\d.]+)", text).groups()
clamps = re.search(r"([\d.e+-]+) per 1,000 particle-steps", text).group(1)
rows = list(csv.DictReader(open(stats)))
dt = [float(r["dt"]) for r in rows]
comp = sum(float(r["mean_density_error"]) * d for r, d in zip(rows, dt)) / sum(dt)
print(",".join([machine, threads, "dam_break_1m", density, rep, fluid, sim, "%.3f" % (float(wall) / float(sim)),
                ms[0], ms[1], ms[2], "%.4f" % (100 * comp), clamps, load0, load1]))
PY
    tail -1 "$csv"
  done
done
