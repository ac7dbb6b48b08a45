#!/usr/bin/env bash
# The sanitizer job: an ASan+UBSan build of the CPU backend (clang 14, no CUDA, no benchmarks) in
# build-san/, and the fast tests of the executables that do not need a GPU or a window. The same build
# carries libFuzzer's coverage, so scripts/fuzz.sh links its targets from it.
#   scripts/sanitize.sh            build, then run the unit tier (or, before the tiers are labelled, every
#                                  test of sim/app/interaction but the slow ones)
#   scripts/sanitize.sh --build    build only
# Suppressions: scripts/sanitizers/ubsan.supp (thrust's upstream report), lsan.supp (Mesa's leaks).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
build=build-san
jobs=$(nproc)

if [ ! -f "$build/build.ninja" ]; then
  CC=clang-14 CXX=clang++-14 cmake -S . -B "$build" -G Ninja -DSPHXR_CUDA=OFF -DSPHXR_BUILD_BENCH=OFF -DSPHXR_FUZZ=ON \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g -DNDEBUG" \
    -DCMAKE_CXX_FLAGS="-fsanitize=address,undefined -fsanitize=fuzzer-no-link -fno-omit-frame-pointer" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
    $(command -v ccache >/dev/null && echo -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# Only what the job runs: the tests of sim, app and interaction, the binary the app tests run, and the
# fuzz targets.
cmake --build "$build" -j "$jobs" --target sphxr sphxr_sim_tests sphxr_app_tests sphxr_interaction_tests \
  sphxr_fuzz_scene sphxr_fuzz_state sphxr_fuzz_trajectory sphxr_fuzz_run_arguments
[ "${1:-}" = "--build" ] && exit 0

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$root/scripts/sanitizers/ubsan.supp"
export LSAN_OPTIONS="suppressions=$root/scripts/sanitizers/lsan.supp:print_suppressions=0"
# Mesa unloads its driver at eglTerminate, and LeakSanitizer, which reports at exit, then sees the
# driver's allocations in "<unknown module>", which no suppression can name; kept loaded, they stay
# Mesa's (the runs that draw pictures through EGL: --frames, --screenshot).
for driver in /usr/lib/*/dri/swrast_dri.so /usr/lib/dri/swrast_dri.so; do
  if [ -f "$driver" ]; then export LD_PRELOAD="$driver"; break; fi
done

# The unit tier when tests/CMakeLists.txt labels it, else everything but the validation, GPU and
# integration tiers (and render and xr, not built here); either way without the tests that take over
# 8 s under the sanitizers (a few tests that are most of the tier's time there; each runs in the normal
# test command), and the conformance suite's cases that take over 0.5 s without them (every row of
# each: the name matches all of its instances).
slow=(BodyMotion.FollowsTheSegmentWithTheRigidVelocity ConservationTest.MomentumOfCollidingBlocksInAClosedBox
      Wcsph.DensityBlocksFittedToTheParticlesGiveThePairsBits Solvers/Conformance.TheSameBitsAtEveryThreadCount
      Wcsph.OneAndTwoThreadsGiveIdenticalResultsWithReuse Energy.MirroredWallsDoNotConserveIt
      Solvers/Conformance.TheWallsHoldTheWaterWithoutTheClamp Solvers/Conformance.APaddlePushesTheWaterAheadAndFeelsItResist
      Solvers/Conformance.StillWaterRestsUnderHydrostaticPressure
      Energy.ViscosityOnlyTakesEnergyOut Energy.WallDensityWithoutViscosityConservesItToTheIntegratorsError
      ExtremesTest.BlockTouchingTheWalls HeadlessTest.AStirredRunContinuedFromItsStateFileEndsWhereTheWholeRunEnds
      PaddleFluid.FiveMetresPerSecondSwingLeavesNoParticleInside PaddleFluid.HeldStillInWaterFeelsArchimedesBuoyancy
      PaddleFluid.OneMetreTeleportIsNotAHugeVelocity PaddleFluid.ParticlesNearAPaddleStayActiveUnderReuse
      PaddleFluid.ScriptedTrajectoryReplaysBitwise PaddleFluid.SweepPushesWaterAlongAndDragGrowsWithSpeed
      PaddleFluid.TrackingLossHoldsThenWithdraws Reuse.DeepTankAtRestIsMostlyInactiveButItsSurfaceIsActive
      Reuse.FastPresetSurvivesTenSecondsOfADamBreak Reuse.GuardKeepsADeepTankAsCalmAsReuseOff
      Reuse.ImpulseHoldKeepsADeepTankCalmWithoutTheGuard Reuse.LiveDensityRecomputesTheReusingNeighboursOfComputingParticles
      Reuse.NoParticleReusesMoreThanIdleConsecutiveSteps SettleTest.GoesDownhillInEnergyAndEndsAtRest
      Surface.AMillionTrianglesGrowTheBufferAndMatchTheReference SurfaceParticles.FieldMatchesABruteForceSumAtEveryCellSize
      SurfaceParticles.WaterAtRestInABoxHasItsSurfaceAtTheFreeSurfaceHeight
      SurfaceTable.RandomFieldsOnOddAndTinyLatticesMatchTheReference)
exclude="_NOT_BUILT|$(IFS='|'; echo "${slow[*]}" | sed 's/\./\\./g')"
if grep -Eq 'LABELS[^)]*\bunit\b' tests/CMakeLists.txt; then
  select=(-L unit)
else
  select=(-LE 'validation|gpu|integration|render|xr')
fi
start=$(date +%s)
ctest --test-dir "$build" --output-on-failure -j2 --timeout 600 "${select[@]}" -E "$exclude"
echo "sanitize.sh: tests took $(( $(date +%s) - start )) s"
