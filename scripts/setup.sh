#!/usr/bin/env bash
# First command of the README, for a fresh Debian machine (as root): installs what is missing,
# builds afterglow (Release) into build/ (or $BUILD_DIR), and runs the main job on the built-in
# Cornell box.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
build="${BUILD_DIR:-build}"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$build" --parallel "$(nproc)" --target afterglow

echo
echo "setup: afterglow bake builtin:cornell -o out/cornell"
"$build/apps/afterglow" bake builtin:cornell -o out/cornell
echo
echo "setup: afterglow render out/cornell/scene.gltf -o out/cornell/view.png"
"$build/apps/afterglow" render out/cornell/scene.gltf -o out/cornell/view.png
