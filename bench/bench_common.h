// Small pieces the benchmark commands share.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

#include "afterglow/baker/options.h"
#include "afterglow/baker/reference.h"
#include "afterglow/core/status.h"
#include "afterglow/core/timer.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"

namespace afterglow::bench {

inline int fail(const std::string& message) {
  std::fprintf(stderr, "afterglow_bench: %s\n", message.c_str());
  return 1;
}

// A .gltf/.glb path or builtin:cornell / builtin:furnace, textures decoded.
inline Result<scenes::Scene> loadBenchScene(const std::string& path, bool textures = true) {
  if (path == "builtin:cornell") return scenes::makeCornellBox();
  if (path == "builtin:furnace") return scenes::makeFurnaceBox();
  return scenes::loadGltf(path, scenes::LoadOptions{textures});
}

// Lightmap UVs as `afterglow bake` makes them (bakefiles::unwrapForBake): at texelsPerUnit, or
// (atlasSize > 0) at the most texels per metre that fit one atlas of that size. Returns the
// texels per metre used.
Result<float> unwrapForBench(scenes::Scene& scene, float texelsPerUnit, int atlasSize = 0,
                             float indirectTexelsPerUnit = 0.0f);

const char* mark(bool ok);

// A quality preset by its name on the command line: draft, high, else default.
baker::Quality qualityNamed(const std::string& name);

// The comparison's direct, indirect and total lines: relative RMSE, bias, reference noise.
void printErrors(const baker::ReferenceComparison& c);

int benchUv(int argc, char** argv);
int benchAccuracy(int argc, char** argv);
int benchBake(int argc, char** argv);
int benchRuntime(int argc, char** argv);
int benchViews(int argc, char** argv);
int benchProbes(int argc, char** argv);
int benchReflection(int argc, char** argv);
int benchGlass(int argc, char** argv);
int benchNoise(int argc, char** argv);
// bench_reflection_probes.cpp: capture, runtime update and transport share of a bake.
int reflectionBakeFigures(const std::string& path, float texelsPerUnit, int threads, int repeat,
                          int probeCount, int resolution);

}  // namespace afterglow::bench
