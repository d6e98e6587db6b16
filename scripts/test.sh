#!/usr/bin/env bash
# Second command of the README (and what CI runs through .ci/run): installs what is missing,
# builds everything into build/ or $BUILD_DIR (warnings are errors when CI=true), runs the test
# suite, then fuzzes the glTF importer for a bounded minute.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
werror=OFF
if [ "${CI:-}" = "true" ]; then werror=ON; fi
build="${BUILD_DIR:-build}"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DAFTERGLOW_WERROR="$werror"
cmake --build "$build" --parallel "$(nproc)"
ctest --test-dir "$build" --output-on-failure -j2 --timeout 900

if [ -f scripts/fuzz.sh ]; then
  # The fuzzer builds with clang, so it gets a build folder of its own.
  BUILD_DIR="$build-fuzz" bash scripts/fuzz.sh
else
  echo "test: scripts/fuzz.sh is absent; skipping the fuzzer"
fi
echo "test: all passed"
