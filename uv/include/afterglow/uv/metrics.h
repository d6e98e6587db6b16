// Lightmap-UV quality metrics, computed from a scene's TEXCOORD_1 and lightmap locations alone,
// so they judge generated and authored (--uv keep) UVs the same way.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "afterglow/scenes/scene.h"

namespace afterglow::uv {

struct AtlasMetrics {
  int width = 0, height = 0;   // texels
  size_t coveredTexels = 0;    // texels touched by any chart (conservative rasterisation)
  double utilization = 0.0;    // coveredTexels / (width * height)
};

struct Metrics {
  std::vector<AtlasMetrics> atlases;
  size_t chartCount = 0;          // UV-connected components over all lightmapped instances
  size_t triangleCount = 0;       // lightmapped triangles over all instances
  double utilization = 0.0;       // covered texels / atlas texels, over all atlases
  size_t overlappingTexels = 0;   // texels covered by two or more charts (must be 0)
  size_t paddingViolations = 0;   // texels of one chart closer than `padding` to another chart
  size_t outOfRangeTriangles = 0; // triangles with a TEXCOORD_1 outside [0,1]
  size_t flippedTriangles = 0;    // triangles whose UV winding disagrees with their chart's
  double stretchL2 = 0.0;         // area-weighted L2 stretch (Sander et al. 2001), 1 = isometric
  double stretchL2Max = 0.0;      // worst chart's L2 stretch
  double densityMin = 0.0;        // texels per metre, lowest chart
  double densityMax = 0.0;        // texels per metre, highest chart
  double densitySpread = 0.0;     // coefficient of variation of per-chart texel density
                                  // (each chart's density divided by its instance's target)
};

// Measures the scene's lightmap UVs. padding is the gap to check, in texels.
Metrics computeMetrics(const scenes::Scene& scene, int padding);

// JSON text of the metrics (the `afterglow uv` report).
std::string metricsToJson(const Metrics& metrics);

}  // namespace afterglow::uv
