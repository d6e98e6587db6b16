// Packing charts into lightmap atlases (stage 2 of afterglow uv).
#pragma once

#include <functional>
#include <vector>

#include <glm/glm.hpp>

namespace afterglow::uv {

struct PackOptions {
  float texelsPerUnit = 16.0f;  // texels per world metre (× each instance's lightmapScale)
  int padding = 2;              // empty texels between any two charts' conservative footprints
  int maxAtlasSize = 4096;      // texels; charts spill into further atlases beyond this
  bool allowRotation = true;    // try 90° turns when placing charts
  // Polled between charts; returning true stops the packing early (Ctrl-C), leaving the
  // result incomplete for the caller to discard.
  std::function<bool()> cancelled;
};

// A chart to place: its triangles in texel units (3 points each), already scaled to the final
// texel density, in any position and orientation (the packer picks its own orientation).
struct PackChart {
  std::vector<glm::vec2> triangles;
};

// Where a chart went: atlas texel coordinate = rotation * point + offset (point in the
// PackChart's texel units). Divide by the atlas size for UVs in [0,1].
struct ChartPlacement {
  int atlas = -1;
  glm::mat2 rotation{1.0f};  // orthonormal (the packer's chosen orientation)
  glm::vec2 offset{0.0f};    // texels
};

struct PackResult {
  std::vector<glm::ivec2> atlasSizes;       // width, height of each atlas, texels
  std::vector<ChartPlacement> placements;   // parallel to the input charts
};

// Packs the charts: conservative footprints, padding, rotation, spill to more atlases past
// maxAtlasSize. Deterministic: the same input gives the same output whatever the thread count.
// A chart that fits no atlas even alone (larger than maxAtlasSize in every orientation), or has
// non-finite points, keeps atlas = -1; the others are still packed.
PackResult packCharts(const std::vector<PackChart>& charts, const PackOptions& options = {});

}  // namespace afterglow::uv
