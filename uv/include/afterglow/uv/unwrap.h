// afterglow uv: lightmap UVs for every static instance of a scene.
#pragma once

#include <string>
#include <vector>

#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/scenes/scene.h"
#include "afterglow/uv/charts.h"
#include "afterglow/uv/metrics.h"
#include "afterglow/uv/pack.h"

namespace afterglow::uv {

enum class UvMode {
  Generate,  // chart, parameterise and pack new UVs
  Keep,      // use the authored TEXCOORD_1 when it is valid; fail with the reason otherwise
};

struct UnwrapOptions {
  UvMode mode = UvMode::Generate;
  ChartOptions charts;
  PackOptions pack;
};

// Wall time of each stage, seconds (for reports and the benchmark).
struct UnwrapTimings {
  double charts = 0.0;   // segmentation and parameterisation (keep mode: validation)
  double pack = 0.0;     // packing
  double apply = 0.0;    // writing uv1 and per-instance meshes
  double metrics = 0.0;  // computeMetrics
};

struct UnwrapResult {
  Metrics metrics;
  std::vector<std::string> warnings;
  UnwrapTimings timings;
};

// Gives every static instance lightmap UVs (Primitive::uv1) and a LightmapLocation. Each static
// instance ends up with a mesh of its own (instances of a shared mesh are duplicated, since each
// needs its own atlas space); dynamic instances are left as they are. Deterministic.
Result<UnwrapResult> unwrap(scenes::Scene& scene, const UnwrapOptions& options = {},
                            Progress& progress = nullProgress());

// The texelsPerUnit that gives the static geometry about `texels` texels (its world area ×
// lightmapScale², before charts and padding); 0 without static geometry. `afterglow bake`'s
// default density, so a level in centimetres and a room in metres both bake in seconds.
float texelsPerUnitFor(const scenes::Scene& scene, double texels);

// The largest texelsPerUnit (to 1%) at which `generate` packs every static instance into one
// atlas of at most atlasSize × atlasSize texels (`--atlas-size`: "give me a 256² lightmap").
// Unwraps copies of the scene a dozen times, so it costs a dozen unwraps.
Result<float> fitTexelsPerUnit(const scenes::Scene& scene, const UnwrapOptions& options,
                               int atlasSize, Progress& progress = nullProgress());

}  // namespace afterglow::uv
