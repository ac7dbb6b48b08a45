#!/usr/bin/env bash
# scripts/gpu_check.sh for a GPU machine that has nvcc and CMake but none of the build's packages
# (GoogleTest, GLFW, epoxy, OpenXR, ...): build here for its architecture, carry the tree, run there.
#
#   scripts/gpu_prebuilt.sh pack [ARCH]   here: configure and build build-gpu for sm_ARCH (default 90),
#                                         then copy its executables and test lists (no object files) and
#                                         the shared libraries they load into .gpu/ (git-ignored)
#   scripts/gpu_prebuilt.sh run           there, in a copy of this checkout holding .gpu/: gpu_check.sh
#                                         on the carried tree; logs into $OUT/gpu-logs (or .gpu/logs)
#
# The carried tree names this checkout by its path here (ctest's lists, the tests' scene and data
# folders), so `run` makes that path lead to the copy it runs in.
set -u
cd "$(dirname "$0")/.."
root=$(pwd)
here_file=.gpu/checkout-path

case "${1:-}" in
pack)
  arch=${2:-90}
  cmake -S . -B build-gpu -G Ninja -DCMAKE_BUILD_TYPE=Release -DSPHXR_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES="$arch" >/dev/null &&
    cmake --build build-gpu -j "$(nproc)" --target sphxr sphxr_gpu_tests sphxr_backend_tests sphxr_bench_perf \
      sphxr_bench_surface sphxr_bench_frame || exit 1
  grep -qx '/.gpu/' .git/info/exclude 2>/dev/null || echo '/.gpu/' >>.git/info/exclude
  rm -rf .gpu && mkdir -p .gpu/lib .gpu/lib-cxx
  # the tree without its objects: executables, ctest files, the discovered test lists
  mkdir -p .gpu/build-gpu
  tar -C build-gpu -cf - --exclude='*.o' --exclude='*.a' --exclude='*.ninja' --exclude='.ninja_*' \
      --exclude='*.dir' --exclude='CMakeFiles' --exclude='test-artifacts' . | tar -C .gpu/build-gpu -xf -
  # only the executables gpu_check.sh runs (the carry is limited)
  keep=" tests/sphxr_gpu_tests tests/sphxr_backend_tests bench/sphxr_bench_perf bench/sphxr_bench_surface bench/sphxr_bench_frame app/sphxr "
  (cd .gpu/build-gpu && find . -type f -perm -u+x | sed 's|^\./||' | while read -r f; do
     case "$keep" in *" $f "*) ;; *) head -c 4 "$f" | grep -q ELF && rm -f "$f" ;; esac
   done)
  # the shared libraries, except the C library's own (the machine's are newer); Debian's libstdc++ and
  # libgcc_s apart, used only if the machine's are older than the build's
  for exe in .gpu/build-gpu/tests/sphxr_gpu_tests .gpu/build-gpu/tests/sphxr_backend_tests \
             .gpu/build-gpu/bench/sphxr_bench_perf .gpu/build-gpu/bench/sphxr_bench_surface \
             .gpu/build-gpu/bench/sphxr_bench_frame .gpu/build-gpu/app/sphxr; do
    ldd "$exe" | awk '$3 ~ /^\// {print $3}'
  done | sort -u | while read -r lib; do
    case "$(basename "$lib")" in
      libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*|ld-linux*) ;;
      libstdc++.so*|libgcc_s.so*) cp -L "$lib" .gpu/lib-cxx/ ;;
      *) cp -L "$lib" .gpu/lib/ ;;
    esac
  done
  # GL's dispatch libraries, which epoxy opens by name (the frame benchmark's EGL); the driver's vendor
  # libraries plug into them there
  for lib in libEGL.so.1 libGL.so.1 libOpenGL.so.0 libGLESv2.so.2; do
    [ -e "/usr/lib/x86_64-linux-gnu/$lib" ] && cp -L "/usr/lib/x86_64-linux-gnu/$lib" .gpu/lib/
  done
  echo "$root" >"$here_file"
  du -sh .gpu
  ;;
run)
  [ -f "$here_file" ] || { echo "gpu_prebuilt: no .gpu/ here: run 'scripts/gpu_prebuilt.sh pack' first"; exit 1; }
  built=$(cat "$here_file")
  if [ "$built" != "$root" ]; then
    if [ -e "$built" ] && [ ! -L "$built" ]; then echo "gpu_prebuilt: $built exists here and is not this checkout"; exit 1; fi
    mkdir -p "$(dirname "$built")" && ln -sfn "$root" "$built"
  fi
  if [ -e build-gpu ] && [ ! -L build-gpu ]; then echo "gpu_prebuilt: build-gpu is a real build here: run 'gpu_check.sh' instead"; exit 1; fi
  ln -sfn .gpu/build-gpu build-gpu
  export LD_LIBRARY_PATH="$root/.gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  if ! build-gpu/tests/sphxr_gpu_tests --gtest_list_tests >/dev/null 2>&1; then
    echo "gpu_prebuilt: the machine's libstdc++ is older than the build's: using the carried one"
    export LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$root/.gpu/lib-cxx"
  fi
  ldd build-gpu/tests/sphxr_backend_tests | grep 'not found' && echo "gpu_prebuilt: libraries missing (above)"
  # EGL for the frame benchmark: the driver's vendor file, where the machine has one
  for f in /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json /usr/share/glvnd/egl_vendor.d/10_nvidia.json; do
    [ -f "$f" ] && export __EGL_VENDOR_LIBRARY_FILENAMES="$f" && break
  done
  logs=${OUT:+$OUT/gpu-logs}
  PREBUILT=1 BUILD_DIR=build-gpu LOGS="${logs:-$root/.gpu/logs}" scripts/gpu_check.sh
  ;;
*)
  echo "usage: scripts/gpu_prebuilt.sh pack [ARCH] | run"
  exit 2
  ;;
esac
