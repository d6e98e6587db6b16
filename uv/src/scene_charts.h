// Charts and texel coverage recovered from a scene's TEXCOORD_1 alone, shared by the metrics and
// the atlas pictures so both see the same charts and the same footprints.
#pragma once

#include <cstdint>
#include <vector>

#include "afterglow/scenes/scene.h"

namespace afterglow::uv::detail {

// Charts of one lightmapped instance: UV-connected components over all its primitives.
// Vertices are joined by the triangles that use them and welded when both uv1 and position are
// identical (authored UVs are often split at normal or material seams only).
struct InstanceCharts {
  int instance = -1;
  int firstChart = 0;  // global id of this instance's chart 0
  int chartCount = 0;
  // Per primitive, per triangle: local chart index, or -1 when the primitive has no usable uv1.
  std::vector<std::vector<int32_t>> triangleChart;
};

struct SceneCharts {
  std::vector<InstanceCharts> instances;  // lightmapped instances (lightmap.atlas >= 0), in order
  int chartCount = 0;
  int atlasCount = 0;                     // 1 + highest atlas index used
  std::vector<int> chartInstance;         // global chart id -> instance index in the Scene
  std::vector<int> chartLocal;            // global chart id -> chart index within its instance
};

SceneCharts labelCharts(const scenes::Scene& scene);

// Which chart covers each texel of one atlas (conservative rasterisation, texel centres at
// half-integers of uv * size).
struct AtlasCoverage {
  int width = 0, height = 0;
  std::vector<int32_t> owner;  // global chart id of the first chart to touch a texel, -1 = empty
  std::vector<uint8_t> shared; // 1 where two or more different charts touch the texel
  size_t covered = 0;
  size_t overlapping = 0;
};

// The atlas size is the largest any instance in it reports.
AtlasCoverage rasterizeAtlas(const scenes::Scene& scene, const SceneCharts& charts, int atlas);

}  // namespace afterglow::uv::detail
