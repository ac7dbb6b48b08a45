#!/usr/bin/env bash
# Where each method runs in real time: scenes/stir.json (a tank 0.15 m deep stirred by a scripted paddle,
# no rendering) for 1 simulated second at a sweep of spacings, WCSPH as the scene is and DFSPH with
# --set method=dfsph --set fixed_dt=0, PBF with --set method=pbf (one step per 1/90 s frame, its substeps and
# iterations at their defaults), by turns in one invocation (compare rows of one run only).
# For each run: fluid particles, simulated seconds per wall second inside the run (the headless summary),
# steps, the time-averaged mean compression max(0, rho/rho0 - 1) and DFSPH's mean iterations.
#   bench/realtime.sh [--threads T] [--spacings "0.02 0.016 ..."] [--csv FILE]   (default bench/results/realtime.csv)
# The particle count at which a method runs in real time is where sim_per_wall crosses 1.
set -euo pipefail
cd "$(dirname "$0")/.."
threads=2 csv=bench/results/realtime.csv spacings="0.025 0.02 0.016 0.013 0.01"
while [ $# -gt 0 ]; do
  case "$1" in
    --threads) threads=$2; shift 2 ;;
    --spacings) spacings=$2; shift 2 ;;
    --csv) csv=$2; shift 2 ;;
    *) echo "usage: bench/realtime.sh [--threads T] [--spacings LIST] [--csv FILE]" >&2; exit 2 ;;
  esac
done
bin=${SPHXR:-build/app/sphxr}
[ -x "$bin" ] || { echo "bench/realtime.sh: $bin not built (./scripts/setup.sh)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
machine=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//; s/,/ /g')
load=$(cut -d' ' -f1 /proc/loadavg)
echo "machine,threads,load_avg_start,scene,method,spacing_m,fluid,simulated_s,wall_s,sim_per_wall,steps,mean_compression_pct,density_iterations,divergence_iterations" > "$csv"
for spacing in $spacings; do
  for method in wcsph dfsph pbf; do
    extra=(); [ "$method" = dfsph ] && extra=(--set method=dfsph --set fixed_dt=0)
    [ "$method" = pbf ] && extra=(--set method=pbf)
    env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "$bin" --headless --scene scenes/stir.json --spacing "$spacing" --time 1 --threads "$threads" \
      --no-progress --stats "$tmp/stats.csv" "${extra[@]}" > "$tmp/summary.txt" 2> "$tmp/log.txt"
    /usr/bin/python3 - "$tmp/summary.txt" "$tmp/stats.csv" "$machine" "$threads" "$load" "$method" "$spacing" >> "$csv" <<'PY'
import csv, re, sys
summary, stats, machine, threads, load, method, spacing = sys.argv[1:]
text = open(summary).read()
fluid = re.search(r"particles\s+(\d+) fluid", text).group(1)
sim, wall = re.search(r"simulated time\s+([\d.]+) s in ([\d.]+) s wall", text).groups()
rows = list(csv.DictReader(open(stats)))
dt = [float(r["dt"]) for r in rows]
comp = sum(float(r["mean_density_error"]) * d for r, d in zip(rows, dt)) / sum(dt)
iters = divs = ""
if method in ("dfsph", "pbf"):
    iters = "%.2f" % (sum(float(r["density_iterations"]) for r in rows) / len(rows))
if method == "dfsph":
    divs = "%.2f" % (sum(float(r["divergence_iterations"]) for r in rows) / len(rows))
print(",".join([machine, threads, load, "stir", method, spacing, fluid, sim, wall, "%.3f" % (float(sim) / float(wall)),
                str(len(rows)), "%.4f" % (100 * comp), iters, divs]))
PY
    tail -1 "$csv"
  done
done
