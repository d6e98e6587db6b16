#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) and fuzzes the glTF importer, the
# transport file reader, then the light probes' user file (a small JSON parser: a third of the
# time), each for a bounded time. Exits non-zero when a fuzzer finds a crash, a
# leak, a timeout or an OOM.
#   FUZZ_SECONDS  time budget per fuzzer in seconds (default 60)
#   BUILD_DIR     build folder (default <repo>/build-fuzz)
#   JOBS          ninja parallelism (default 2)
# The seed corpora live in the build folder (the glTF one copied from fuzz/corpus, the transport
# one written by transport_seeds); the fuzzers never write into the source tree.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build-fuzz}"
seconds="${FUZZ_SECONDS:-60}"
jobs="${JOBS:-2}"

cmake -S "$root" -B "$build" -G Ninja \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DAFTERGLOW_BUILD_FUZZERS=ON -DAFTERGLOW_BUILD_TESTS=OFF >/dev/null
ninja -C "$build" -j"$jobs" gltf_fuzzer transport_fuzzer transport_seeds probes_fuzzer

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

# The transport reader's seeds are written by the current writer rather than committed as blobs,
# so they never fall behind the format.
corpus="$build/fuzz-corpus/transport"
mkdir -p "$corpus"
"$build/fuzz/transport_seeds" "$corpus"

echo "fuzzing transport_fuzzer for ${seconds}s (corpus $corpus, crashes go to $artifacts)"
# -rss_limit_mb: the reader bounds every count by the bytes left in its section, so it never
# allocates much more than the input. -max_len: the seeds are a few KB; larger inputs only slow
# each run down without reaching new code.
"$build/fuzz/transport_fuzzer" "$corpus" \
  -dict="$root/fuzz/transport.dict" \
  -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=16384 \
  -artifact_prefix="$artifacts/" -print_final_stats=1
echo "transport_fuzzer: no crash in ${seconds}s"

corpus="$build/fuzz-corpus/probes"
mkdir -p "$corpus"
cp -n "$root"/fuzz/corpus/probes/* "$corpus"/
probe_seconds=$(( seconds / 3 > 0 ? seconds / 3 : 1 ))
echo "fuzzing probes_fuzzer for ${probe_seconds}s (corpus $corpus, crashes go to $artifacts)"
"$build/fuzz/probes_fuzzer" "$corpus" \
  -max_total_time="$probe_seconds" -timeout=10 -rss_limit_mb=2048 -max_len=4096 \
  -artifact_prefix="$artifacts/" -print_final_stats=1
echo "probes_fuzzer: no crash in ${probe_seconds}s"
