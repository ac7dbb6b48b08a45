#!/usr/bin/env bash
# The simulated headset's real-time factor on `stir` under --quality auto: each binary given runs
# `sphxr --xr --scene scenes/stir.json --frame-limit 900` (512x512 eyes, llvmpipe, the same cores as the
# simulation) by turns, `--rounds` times; the factor is the water's simulated time over the wall time of
# the session, from the summary line. Compare rows of one run only (a shared machine drifts).
#   bench/xr_realtime.sh [--rounds N] [--csv FILE] BUILD_DIR...   (default: build; bench/results/xr_realtime.csv)
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=2 csv=bench/results/xr_realtime.csv builds=()
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) rounds=$2; shift 2 ;;
    --csv) csv=$2; shift 2 ;;
    -*) echo "usage: bench/xr_realtime.sh [--rounds N] [--csv FILE] BUILD_DIR..." >&2; exit 2 ;;
    *) builds+=("$1"); shift ;;
  esac
done
[ ${#builds[@]} -gt 0 ] || builds=(build)
machine=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//; s/,/ /g')
echo "machine,cores,load_avg_start,build,round,fluid,spacing_m,method,diffuse_turned_off,frames,wall_s,simulated_s,realtime,frame_p50_ms,render_quality_end" > "$csv"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for round in $(seq 1 "$rounds"); do
  for b in "${builds[@]}"; do
    # Each run starts on a quiet machine: the load average under 0.5 (waiting at most 3 minutes).
    for _ in $(seq 1 36); do awk '{exit !($1 < 0.5)}' /proc/loadavg && break; sleep 5; done
    load=$(cut -d' ' -f1 /proc/loadavg)
    dir=$(cd "$b" && pwd)
    XR_RUNTIME_JSON="$dir/xr/sim_runtime/sphxr_sim_runtime.json" SPHXR_SIM_XR_EYE_SIZE=512x512 \
      xvfb-run -a "$dir/app/sphxr" --xr --scene scenes/stir.json --frame-limit 900 > "$tmp/out.txt" 2>&1
    /usr/bin/python3 - "$tmp/out.txt" "$machine" "$(nproc)" "$load" "$b" "$round" >> "$csv" <<'PY'
import re, sys
out, machine, cores, load, build, rnd = sys.argv[1:]
text = open(out).read()
q = re.search(r"quality auto: method (\w+), spacing ([\d.]+) m .*?, (\d+) fluid particles", text)
end = re.search(r"after (\d+) frames .*? in ([\d.]+) s; frame interval p50 ([\d.]+).*?simulation at t = ([\d.]+) s", text)
quality = re.search(r"render quality (\w+); GPU", text)
diffuse = "yes" if "spray, foam and bubbles off" in text else "no"
frames, wall, p50, sim = end.groups()
print(",".join([machine, cores, load, build, rnd, q.group(3), q.group(2), q.group(1), diffuse, frames, wall, sim,
                f"{float(sim) / float(wall):.3f}", p50, quality.group(1) if quality else "-"]))
PY
    tail -1 "$csv"
  done
done
