#!/usr/bin/env bash
# Two builds of sphxr side by side: the same headless run with each, alternated rep by rep (this
# machine's speed drifts: only runs of one invocation compare), one CSV row per run with the summary's
# ms per step by stage. For a change that should only make a stage faster: build the commit before it
# in a worktree (git worktree add /tmp/base HEAD~1; cmake --preset cpu there; cmake --build build-cpu
# --target sphxr) and compare.
#   bench/ab.sh --a BIN --b BIN [--reps N] [--threads T] --csv FILE -- RUN-ARGUMENTS...
# e.g. bench/ab.sh --a /tmp/base/build-cpu/app/sphxr --b build/app/sphxr --csv bench/results/dfsph_simd.csv \
#        -- --scene scenes/dam_break_1m.json --set method=dfsph --set fixed_dt=0 --time 0.3
# Time it with nothing else running (the load before and after each run is in the CSV).
set -euo pipefail
cd "$(dirname "$0")/.."
a="" b="" reps=3 threads=2 csv=""
while [ $# -gt 0 ]; do
  case "$1" in
    --a) a=$2; shift 2 ;;
    --b) b=$2; shift 2 ;;
    --reps) reps=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --csv) csv=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "usage: bench/ab.sh --a BIN --b BIN [--reps N] [--threads T] --csv FILE -- RUN-ARGUMENTS..." >&2; exit 2 ;;
  esac
done
[ -n "$a" ] && [ -n "$b" ] && [ -n "$csv" ] || { echo "bench/ab.sh: --a, --b and --csv are required" >&2; exit 2; }
for bin in "$a" "$b"; do [ -x "$bin" ] || { echo "bench/ab.sh: $bin is not an executable" >&2; exit 2; }; done
machine=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//; s/,/ /g')
stages="cells sort grid activity density forces integrate bodies divergence pressure probes"
echo "machine,threads,build,binary,rep,arguments,steps,ms_per_step,$(echo $stages | tr ' ' ','),load_before,load_after" > "$csv"
for rep in $(seq 1 "$reps"); do
  for which in a b; do
    bin=$a; [ "$which" = b ] && bin=$b
    load0=$(cut -d' ' -f1 /proc/loadavg)
    summary=$(OMP_WAIT_POLICY=active "$bin" --headless --threads "$threads" --no-progress "$@" 2>/dev/null)
    load1=$(cut -d' ' -f1 /proc/loadavg)
    steps=$(echo "$summary" | sed -n 's/^ *steps *\([0-9]*\).*/\1/p')
    line=$(echo "$summary" | grep "ms per step")
    total=$(echo "$line" | sed -n 's/.*ms per step *\([0-9.]*\) total.*/\1/p')
    values=""
    for s in $stages; do values="$values,$(echo "$line" | sed -n "s/.* $s \([0-9.]*\).*/\1/p")"; done
    echo "$machine,$threads,$which,$bin,$rep,\"$*\",$steps,$total$values,$load0,$load1" >> "$csv"
    tail -1 "$csv"
  done
done
