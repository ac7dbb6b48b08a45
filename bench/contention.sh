#!/usr/bin/env bash
# The CPU backend when the machine is shared: ms per step of scenes/stir.json (13,322 fluid particles and
# a scripted paddle, no rendering) alone and beside one busy process (a shell loop at nice 0, the kind of
# neighbour a second sweep, a compiler or a compositor is), at 1 thread and at every core, by turns in
# one invocation (compare rows of one run only; the median of --rounds runs per row).
#   bench/contention.sh [--time S] [--rounds R] [--csv FILE]   (default 0.1 s, 3 rounds, bench/results/contention.csv)
# The rows: threads 1 and N (every core) are fixed teams (--threads 1, --threads N); threads auto is sphxr's
# default (--threads 0: the team measured step by step, sim/src/cpu/team.h, docs/design/contention.md).
#   wait=default   the OpenMP runtime's own (libgomp: a spin of 300,000 rounds before sleeping)
#   wait=passive   OMP_WAIT_POLICY=passive (sleep at once at every barrier), for comparison
# The targets: beside one busy process, the threads=auto step <= 1.3x the 1-thread step alone;
# alone, the threads=auto step within 5 % of the fixed N-thread step.
set -euo pipefail
cd "$(dirname "$0")/.."
time_s=0.1 rounds=3 csv=bench/results/contention.csv
while [ $# -gt 0 ]; do
  case "$1" in
    --time) time_s=$2; shift 2 ;;
    --rounds) rounds=$2; shift 2 ;;
    --csv) csv=$2; shift 2 ;;
    *) echo "usage: bench/contention.sh [--time S] [--rounds R] [--csv FILE]" >&2; exit 2 ;;
  esac
done
bin=${SPHXR:-build/app/sphxr}
[ -x "$bin" ] || { echo "bench/contention.sh: $bin not built (./scripts/setup.sh)" >&2; exit 2; }
cores=$(nproc)
machine=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//; s/,/ /g')
load=$(cut -d' ' -f1 /proc/loadavg)
tmp=$(mktemp -d)
busy_pid=""
stop_busy() { if [ -n "$busy_pid" ]; then kill "$busy_pid" 2>/dev/null || true; wait "$busy_pid" 2>/dev/null || true; busy_pid=""; fi; }
trap 'stop_busy; rm -rf "$tmp"' EXIT

# one run: prints its ms per step (the headless summary's total)
run() {  # threads wait
  local threads=$1 wait=$2 envs=(env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT -u KMP_BLOCKTIME)
  [ "$wait" = passive ] && envs+=(OMP_WAIT_POLICY=passive)
  [ "$threads" = auto ] && threads=0
  "${envs[@]}" "$bin" --headless --scene scenes/stir.json --time "$time_s" --threads "$threads" --no-progress \
    > "$tmp/summary.txt" 2> "$tmp/log.txt" || { cat "$tmp/log.txt" >&2; exit 1; }
  sed -n 's/^ *ms per step *\([0-9.]*\) total.*/\1/p' "$tmp/summary.txt"
}
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }

rows=()
for neighbour in alone busy; do
  for threads in 1 "$cores" auto; do rows+=("$neighbour $threads default"); done
  rows+=("$neighbour $cores passive")
done
declare -A samples
for ((r = 0; r < rounds; ++r)); do
  for row in "${rows[@]}"; do
    read -r neighbour threads wait <<< "$row"
    if [ "$neighbour" = busy ]; then (while :; do :; done) & busy_pid=$!; sleep 0.2; fi
    samples[$row]+="$(run "$threads" "$wait") "
    stop_busy
  done
done

echo "machine,cores,load_avg_start,scene,simulated_s,neighbour,threads,wait,ms_per_step,runs" > "$csv"
printf '%-8s %-8s %-8s %12s\n' neighbour threads wait "ms/step"
for row in "${rows[@]}"; do
  read -r neighbour threads wait <<< "$row"
  ms=$(tr ' ' '\n' <<< "${samples[$row]}" | grep . | median)
  echo "$machine,$cores,$load,stir,$time_s,$neighbour,$threads,$wait,$ms,$(tr ' ' ';' <<< "${samples[$row]% }")" >> "$csv"
  printf '%-8s %-8s %-8s %12s\n' "$neighbour" "$threads" "$wait" "$ms"
done
