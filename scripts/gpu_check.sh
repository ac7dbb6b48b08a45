#!/usr/bin/env bash
# One command for the first run on a machine with an NVIDIA GPU: build for this GPU, run the agreement
# suites (ctest label gpu: the CUDA backend against the CPU and, step by step, against cpu-reference, its
# own orchestration on the host), time the CUDA backend (sphxr_bench_perf at 50k and 205k particles,
# sphxr_bench_surface, sphxr_bench_frame), count what a step asks of the device (the summary's "device
# work": launches, host waits, allocations, copies back, per step, for stir with PBF and DFSPH and
# dam_break_1m with WCSPH, on cuda beside cpu-reference, whose counts are CUDA's by construction), and
# print one table. No machine the project is built on has a
# GPU, so this is where the CUDA backend first runs: it measures instead of setting up.
#
# Exit status: 0 all agreed; 1 a build failure, or an agreement test failed (a disagreement); 2 no GPU.
# Environment: BUILD_DIR (default build-gpu), JOBS (default all cores), PREBUILT=1 (use BUILD_DIR as it
# is: a tree built elsewhere for this GPU's architecture, for a machine without the build's packages;
# scripts/gpu_prebuilt.sh), LOGS (the logs' folder; default a fresh temporary one), PHASE_LIMIT_S (the
# longest any one phase may run, default 1800 s: the agreement suite, each benchmark).
set -u
cd "$(dirname "$0")/.."

if ! command -v nvidia-smi >/dev/null 2>&1 || ! nvidia-smi -L 2>/dev/null | grep -q '^GPU '; then
  echo "gpu_check: no NVIDIA GPU on this machine (nvidia-smi lists none); nothing to check here"
  exit 2
fi

build=${BUILD_DIR:-build-gpu}
jobs=${JOBS:-$(nproc)}
logs=${LOGS:-$(mktemp -d)}
mkdir -p "$logs"
limit=${PHASE_LIMIT_S:-1800}
gpu=$(nvidia-smi --query-gpu=name --format=csv,noheader | head -n 1)
driver=$(nvidia-smi --query-gpu=driver_version --format=csv,noheader | head -n 1)
arch=$(nvidia-smi --query-gpu=compute_cap --format=csv,noheader | head -n 1 | tr -d '.')
echo "gpu_check: $gpu (driver $driver, sm_$arch); logs in $logs"

launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_CUDA_COMPILER_LAUNCHER=ccache)
fi
# This GPU's architecture only (the release preset builds five), with the CUDA backend required.
if [ "${PREBUILT:-0}" = 1 ]; then
  for t in tests/sphxr_gpu_tests tests/sphxr_backend_tests bench/sphxr_bench_perf; do
    if [ ! -x "$build/$t" ]; then echo "gpu_check: PREBUILT=1 but $build/$t is missing"; exit 1; fi
  done
  echo "gpu_check: using the prebuilt tree $build"
elif ! cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DSPHXR_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES="$arch" \
       "${launcher[@]}" >"$logs/configure.log" 2>&1 ||
   ! cmake --build "$build" -j "$jobs" --target sphxr sphxr_gpu_tests sphxr_backend_tests sphxr_bench_perf \
       sphxr_bench_surface sphxr_bench_frame >"$logs/build.log" 2>&1; then
  echo "gpu_check: the build failed: see $logs/configure.log and $logs/build.log"
  exit 1
fi

# 1. Agreement (the tests print one "[agreement] ..." line each with their worst differences).
timeout "$limit" ctest --test-dir "$build" -L gpu -V --timeout "$limit" >"$logs/agreement.log" 2>&1
agreement=$?
skipped=$(grep -c "Skipped" "$logs/agreement.log" || true)

# 2. Timings on CUDA (the benchmarks report; they never fail on a time).
timeout "$limit" "$build/bench/sphxr_bench_perf" --device cuda --csv "$logs/perf.csv" >"$logs/perf.log" 2>&1 || echo "gpu_check: sphxr_bench_perf failed (see $logs/perf.log)"
timeout "$limit" "$build/bench/sphxr_bench_surface" --device cuda --csv "$logs/surface.csv" >"$logs/surface.log" 2>&1 || echo "gpu_check: sphxr_bench_surface failed (see $logs/surface.log)"
timeout "$limit" "$build/bench/sphxr_bench_frame" --device cuda >"$logs/frame.log" 2>&1 || echo "gpu_check: sphxr_bench_frame failed (see $logs/frame.log; it needs EGL)"

# 3. What a step asks of the device, with its stage timings (CUDA events), on cuda and on cpu-reference.
counts() {  # NAME DEVICE SCENE ARGS...
  local name=$1 device=$2 scene=$3
  shift 3
  timeout "$limit" "$build/app/sphxr" --headless --no-progress --device "$device" --scene "$scene" "$@" \
    >"$logs/counts_${name}_${device}.log" 2>&1 || echo "gpu_check: counting $name on $device failed (see $logs/counts_${name}_${device}.log)"
}
for device in cuda cpu-reference; do
  counts stir_pbf "$device" scenes/stir.json --set method=pbf --steps 30
  counts stir_dfsph "$device" scenes/stir.json --set method=dfsph --steps 30
  counts dam_break_wcsph "$device" scenes/dam_break_1m.json --steps 10
done

# 4. One table.
python3 - "$logs" "$gpu" "$driver" "$agreement" "$skipped" <<'EOF'
import csv, os, re, sys
logs, gpu, driver, agreement, skipped = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
def rows(name):
    path = os.path.join(logs, name)
    return list(csv.DictReader(open(path))) if os.path.exists(path) else []
perf = {int(r["fluid"]): float(r["median_ms"]) for r in rows("perf.csv")}
def near(n):
    best = min(perf, key=lambda k: abs(k - n), default=None)
    return f"{perf[best]:.2f} ({best} particles)" if best is not None else "n/a"
surface = rows("surface.csv")
hpmc = ", ".join(f"{float(r['extraction_ms']):.2f} ms at cell {float(r['cell_size_m'])*1000:.1f} mm ({r['triangles']} triangles)"
                 for r in surface) or "n/a"
frame = [l for l in open(os.path.join(logs, "frame.log")) if l.startswith("| ") and "---" not in l][1:] \
    if os.path.exists(os.path.join(logs, "frame.log")) else []
lines = [re.sub(r"^.*\[agreement\] ", "", l.strip()) for l in open(os.path.join(logs, "agreement.log")) if "[agreement]" in l]
print()
print(f"| GPU | {gpu} |")
print(f"|---|---|")
print(f"| driver | {driver} |")
print(f"| ms per step, dam_break_1m ~50k | {near(50653)} |")
print(f"| ms per step, dam_break_1m ~205k | {near(205379)} |")
print(f"| HPMC extraction (field + pyramid + traversal) | {hpmc} |")
for l in frame:
    cells = [c.strip() for c in l.strip().strip("|").split("|")]
    print(f"| frame, {cells[0]} | step {cells[2]} ms, surface {cells[3]} ms |")
for name in ("stir_pbf", "stir_dfsph", "dam_break_wcsph"):
    for device in ("cuda", "cpu-reference"):
        path = os.path.join(logs, f"counts_{name}_{device}.log")
        text = open(path).read() if os.path.exists(path) else ""
        work = re.search(r"device work +per step: (.*)", text)
        ms = re.search(r"ms per step +([0-9.]+) total", text)
        print(f"| per step, {name} on {device} | {ms.group(1) + ' ms; ' if ms else ''}"
              f"{work.group(1) if work else 'n/a'} |")
for l in lines:
    print(f"| agreement | {l} |")
print(f"| agreement tests | {'passed' if agreement == 0 else 'FAILED (a disagreement: see agreement.log)'}"
      f"{', ' + str(skipped) + ' skipped' if skipped else ''} |")
EOF
if [ "$agreement" -ne 0 ]; then
  echo "gpu_check: the CUDA backend disagrees with the CPU or with cpu-reference: see $logs/agreement.log"
  exit 1
fi
echo "gpu_check: agreement passed"
