#!/usr/bin/env bash
# What DFSPH's step bound and tolerance buy on dam_break_1m (50,653 particles, 1 s, CFL steps): for each
# max_dt and density_tolerance, wall seconds per simulated second (the headless summary), steps and the
# mean step, the time-averaged mean compression max(0, rho/rho0 - 1) (weighted by dt), the mean density
# and divergence iterations a step, the clamps per 1,000 particle-steps and the largest speed; WCSPH at
# the scene's own settings first, in the same run, as the yardstick. The rows run by turns in one
# invocation (this machine's speed drifts: compare rows of one run only); time it with nothing else
# running (the load before and after each row is in the CSV).
#   bench/dfsph_step.sh [--threads T] [--time S] [--max-dt "A B"] [--tolerance "X Y"] [--csv FILE]
#   (defaults: 2 threads, 1 s, max_dt 0.002 0.003 0.005 s, tolerance 0.01 0.02 0.05 %,
#    bench/results/dfsph_step.csv)
set -euo pipefail
cd "$(dirname "$0")/.."
threads=2 time=1.0 maxdts="0.002 0.003 0.005" tolerances="0.01 0.02 0.05" csv=bench/results/dfsph_step.csv
while [ $# -gt 0 ]; do
  case "$1" in
    --threads) threads=$2; shift 2 ;;
    --time) time=$2; shift 2 ;;
    --max-dt) maxdts=$2; shift 2 ;;
    --tolerance) tolerances=$2; shift 2 ;;
    --csv) csv=$2; shift 2 ;;
    *) echo "usage: bench/dfsph_step.sh [--threads T] [--time S] [--max-dt \"A B\"] [--tolerance \"X Y\"] [--csv FILE]" >&2; exit 2 ;;
  esac
done
bin=${SPHXR:-build/app/sphxr}
[ -x "$bin" ] || { echo "bench/dfsph_step.sh: $bin not built (./scripts/setup.sh)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
machine=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//; s/,/ /g')
echo "machine,threads,method,max_dt_s,density_tolerance_pct,simulated_s,wall_per_simulated_s,steps,mean_dt_ms,mean_compression_pct,density_iterations,divergence_iterations,clamps_per_1000,max_speed,load_before,load_after" > "$csv"
row() {  # method max_dt tolerance args...
  local method=$1 maxdt=$2 tol=$3
  shift 3
  local load0 load1
  load0=$(cut -d' ' -f1 /proc/loadavg)
  OMP_WAIT_POLICY=active "$bin" --headless --scene scenes/dam_break_1m.json --time "$time" --threads "$threads" \
    --no-progress --stats "$tmp/stats.csv" "$@" > "$tmp/summary.txt" 2> "$tmp/log.txt"
  load1=$(cut -d' ' -f1 /proc/loadavg)
  /usr/bin/python3 - "$tmp/summary.txt" "$tmp/stats.csv" "$machine" "$threads" "$method" "$maxdt" "$tol" "$load0" "$load1" >> "$csv" <<'PY'
import csv, re, sys
summary, stats, machine, threads, method, maxdt, tol, load0, load1 = sys.argv[1:]
text = open(summary).read()
sim, wall = re.search(r"simulated time\s+([\d.]+) s in ([\d.]+) s wall", text).groups()
clamps = re.search(r"([\d.e+-]+) per 1,000 particle-steps", text)
speed = re.search(r"max speed\s+([\d.]+) m/s", text).group(1)
rows = list(csv.DictReader(open(stats)))
dt = [float(r["dt"]) for r in rows]
comp = sum(float(r["mean_density_error"]) * d for r, d in zip(rows, dt)) / sum(dt)
iters = divs = ""
if "density_iterations" in rows[0]:
    iters = "%.2f" % (sum(float(r["density_iterations"]) for r in rows) / len(rows))
    divs = "%.2f" % (sum(float(r["divergence_iterations"]) for r in rows) / len(rows))
print(",".join([machine, threads, method, maxdt, tol, sim, "%.3f" % (float(wall) / float(sim)), str(len(rows)),
                "%.3f" % (1e3 * sum(dt) / len(dt)), "%.4f" % (100 * comp), iters, divs,
                clamps.group(1) if clamps else "0", speed, load0, load1]))
PY
  tail -1 "$csv"
}
row wcsph scene ""
for maxdt in $maxdts; do
  for tol in $tolerances; do
    row dfsph "$maxdt" "$tol" --set method=dfsph --set fixed_dt=0 --set max_dt="$maxdt" --set density_tolerance="$tol"
  done
done
