#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) and fuzzes the glTF importer for a
# bounded time. Exits non-zero when the fuzzer finds a crash, a leak, a timeout or an OOM.
#   FUZZ_SECONDS  time budget in seconds (default 60)
#   BUILD_DIR     build folder (default <repo>/build-fuzz)
#   JOBS          ninja parallelism (default 2)
# The seed corpus is copied into the build folder; the fuzzer never writes into the source tree.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build-fuzz}"
seconds="${FUZZ_SECONDS:-60}"
jobs="${JOBS:-2}"

cmake -S "$root" -B "$build" -G Ninja \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DAFTERGLOW_BUILD_FUZZERS=ON -DAFTERGLOW_BUILD_TESTS=OFF >/dev/null
ninja -C "$build" -j"$jobs" gltf_fuzzer

corpus="$build/fuzz-corpus/gltf"
artifacts="$build/fuzz-artifacts"
mkdir -p "$corpus" "$artifacts"
cp -n "$root"/fuzz/corpus/gltf/* "$corpus"/

echo "fuzzing gltf_fuzzer for ${seconds}s (corpus $corpus, crashes go to $artifacts)"
# -rss_limit_mb: the importer caps its own allocations far below this.
"$build/fuzz/gltf_fuzzer" "$corpus" \
  -dict="$root/fuzz/gltf.dict" \
  -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
  -artifact_prefix="$artifacts/" -print_final_stats=1
echo "gltf_fuzzer: no crash in ${seconds}s"
