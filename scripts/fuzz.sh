#!/usr/bin/env bash
# Fuzzing (libFuzzer, clang 14) of the parsers of user input: the scene loader, the state-file reader,
# the trajectory parser and the run arguments' parser of the command line, the module and the sweeps
# (fuzz/). Builds them in build-san/ (scripts/sanitize.sh --build:
# ASan+UBSan) and runs each for SECONDS (default 600) from a seed corpus: scenes/*.json, scenes/*.csv
# and a small state file saved from a scene. A crash leaves its input in build-san/fuzz-artifacts/
# and ends the script with an error.
#   scripts/fuzz.sh [SECONDS]      CI runs it with 60 per target
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
seconds=${1:-600}
build=build-san
"$root/scripts/sanitize.sh" --build >/dev/null

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:allocator_may_return_null=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$root/scripts/sanitizers/ubsan.supp"
work="$build/fuzz-work"
artifacts="$build/fuzz-artifacts"
mkdir -p "$work" "$artifacts"
for t in scene state trajectory run_arguments; do mkdir -p "$work/corpus_$t" "$work/seeds_$t"; done
# The run arguments: the first byte picks the argument (fuzz/run_arguments_fuzz.cpp), the rest its text.
i=0
for text in 0.25 1e300 inf nan -1 1e3 0x10 4000 64 1000000000; do printf "\\x$(printf %02x $i)%s" "$text" >"$work/seeds_run_arguments/$i"; i=$((i + 1)); done
cp scenes/*.json "$work/seeds_scene/"
cp fuzz/seeds/scene/*.json "$work/seeds_scene/"  # names and keys with control and bidi characters
cp scenes/*.csv "$work/seeds_trajectory/"
cp scenes/*.csv "$work/"  # the trajectories the seed scenes name, relative to the working directory
# A state file to start from: a few steps of the small stirring scene, at a coarse spacing.
if [ ! -f "$work/seeds_state/stir.state" ]; then
  ASAN_OPTIONS=detect_leaks=0 "$build/app/sphxr" --headless --scene scenes/stir.json --spacing 0.03 --steps 3 \
    --threads 1 --no-progress --save-state "$work/seeds_state/stir.state" >/dev/null 2>&1 ||
    echo "fuzz.sh: no seed state file (sphxr failed); the state target starts from nothing"
fi

status=0
for t in scene state trajectory run_arguments; do
  echo "fuzz.sh: sphxr_fuzz_$t for $seconds s"
  # Run in the work directory: a fuzzed scene reads trajectory files relative to it.
  # -rss_limit_mb: the scene and state readers must never need much memory for a small input.
  dict=()
  if [ -f "fuzz/$t.dict" ]; then dict=(-dict="$root/fuzz/$t.dict"); fi
  if ! (cd "$work" && "$root/$build/fuzz/sphxr_fuzz_$t" "${dict[@]}" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
          -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$root/$artifacts/${t}_" \
          "corpus_$t" "seeds_$t" >"fuzz_$t.log" 2>&1); then
    echo "fuzz.sh: sphxr_fuzz_$t FAILED; its log: $work/fuzz_$t.log; the input: $artifacts/"
    tail -40 "$work/fuzz_$t.log"
    status=1
  else
    grep -E "stat::number_of_executed_units|cov:" "$work/fuzz_$t.log" | tail -2
  fi
done
exit $status
