#!/usr/bin/env bash
# PBF's real-time table on this machine: scenes/stir.json under PBF at 1 cm (13,322 particles) and at
# 1.18 cm (about 8,000), and scenes/tank_rest.json (still water, 1 s from the lattice), each for 1
# simulated second at the scene's PBF settings (pbf_substeps, pbf_iterations, pbf_skin at their
# defaults unless --set is given), in one invocation. For each: fluid particles, simulated seconds per
# wall second inside the run (the headless summary), the time-averaged mean compression
# max(0, rho/rho0 - 1), and the load average when it started (quote a table taken at load < 0.5).
#   bench/small_steps.sh [--threads T] [--csv FILE] [--set key=value ...]   (default bench/results/small_steps.csv)
# Targets: stir >= 1.0 simulated s per wall s at 13,300 particles with mean compression <= 2.7 %,
# >= 1.5 at 8,000; tank_rest no worse than the table in docs/design/pbf.md.
set -euo pipefail
cd "$(dirname "$0")/.."
threads=2 csv=bench/results/small_steps.csv sets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --threads) threads=$2; shift 2 ;;
    --csv) csv=$2; shift 2 ;;
    --set) sets+=(--set "$2"); shift 2 ;;
    *) echo "usage: bench/small_steps.sh [--threads T] [--csv FILE] [--set key=value ...]" >&2; exit 2 ;;
  esac
done
bin=${SPHXR:-build/app/sphxr}
[ -x "$bin" ] || { echo "bench/small_steps.sh: $bin not built (./scripts/setup.sh)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
machine=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//; s/,/ /g')
echo "machine,threads,load_avg_start,scene,spacing_m,fluid,simulated_s,wall_s,sim_per_wall,steps,mean_compression_pct,settings" > "$csv"
run() {  # scene spacing extra...
  local scene=$1 spacing=$2; shift 2
  local load; load=$(cut -d' ' -f1 /proc/loadavg)
  env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "$bin" --headless --scene "scenes/$scene.json" --spacing "$spacing" --time 1 \
    --threads "$threads" --no-progress --stats "$tmp/stats.csv" --set method=pbf "$@" ${sets[@]+"${sets[@]}"} \
    > "$tmp/summary.txt" 2> "$tmp/log.txt"
  /usr/bin/python3 - "$tmp/summary.txt" "$tmp/stats.csv" "$machine" "$threads" "$load" "$scene" "$spacing" \
    "${sets[*]:-defaults}" "$@" >> "$csv" <<'PY'
import csv, re, sys
summary, stats, machine, threads, load, scene, spacing, settings = sys.argv[1:9]
text = open(summary).read()
fluid = re.search(r"particles\s+(\d+) fluid", text).group(1)
sim, wall = re.search(r"simulated time\s+([\d.]+) s in ([\d.]+) s wall", text).groups()
rows = list(csv.DictReader(open(stats)))
dt = [float(r["dt"]) for r in rows]
comp = sum(float(r["mean_density_error"]) * d for r, d in zip(rows, dt)) / sum(dt)
extra = " ".join(sys.argv[9:])
print(",".join([machine, threads, load, scene, spacing, fluid, sim, wall, "%.3f" % (float(sim) / float(wall)),
                str(len(rows)), "%.3f" % (100 * comp), (settings + " " + extra).replace("--set ", "").strip()]))
PY
  tail -1 "$csv" | cut -d, -f3-
}
echo "load_avg_start,scene,spacing_m,fluid,simulated_s,wall_s,sim_per_wall,steps,mean_compression_pct,settings"
run stir 0.01
run stir 0.0118
run tank_rest 0.01 --settle 0
