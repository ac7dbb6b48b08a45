#!/usr/bin/env bash
# Rewrites the renderer's reference images after an intended change of the look: the fixed scene
# (tests/data/render_reference.png) and each shipped scene's headless picture (tests/data/pictures/).
# Look at every image before committing them, and say in the commit why the look changed.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
cmake --build "$build" --target sphxr sphxr_render_tests
SPHXR_UPDATE_REFERENCE=1 "$build/tests/sphxr_render_tests" --gtest_filter='ReferenceImage*:Shipped/ScenePictures.*'
git status --short tests/data
