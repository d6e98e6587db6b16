// Two resolutions (Enlighten's, and Unity's "indirect resolution"): bounced light is smooth, so
// the relightable solve (gather points, clusters, links, sky) lives on a coarse indirect grid,
// while each source's direct light, which is sharp, is kept per lightmap texel. A lightmap texel
// is then composed as
//
//   L_t = Σ_s scale_s · directScale_s · half(direct_s[t])  +  Σ_k w_tk · C_k
//
// where C are the indirect texels' values (bounced light and sky, as the solver gives them) and
// w_tk the bilinear weights of the indirect texels around t's point on its chart: the indirect
// grid lives on the lightmap's own charts (uv/indirect.h repacks them), so the four corners are
// texels of t's chart or empty padding, never another chart's; corners the baker found buried
// or out of sight of t's point are masked out and the rest renormalised. Relighting costs what
// the indirect grid costs; the composition is a few reads per lightmap texel, and an engine can
// do it in its shader instead (the layers are what it uploads).
//
// GLM and the standard library only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/atlas_layout.h"

namespace afterglow::runtime {

// Where a lightmap texel reads its bounced light: the 2×2 indirect texels whose centres surround
// its point in the indirect atlas.
struct IndirectCorners {
  uint16_t x = 0, y = 0;  // the square's lower-left pixel in the indirect atlas
  uint8_t atlas = 0;      // the indirect atlas
  uint8_t fraction = 0;   // the point within the square, in sixteenths: fx | fy << 4
  uint8_t mask = 0;       // bit k: corner (k & 1, k >> 1) counts (a texel t's point sees)
  uint8_t reserved = 0;
};
static_assert(sizeof(IndirectCorners) == 8, "stored as is in the transport file");

// The lightmap's own texels when the transport's are an indirect grid (TransportData::lightmap).
// texelCount 0: one resolution, the transport's texels are the lightmap's.
struct LightmapLayers {
  uint32_t texelCount = 0;
  std::vector<AtlasLayout> atlases;       // the lightmap atlases
  std::vector<IndirectCorners> corners;   // per lightmap texel
  // Per source (parallel to TransportData::sources): unit direct light per lightmap texel as
  // half floats of value / directScale (so lamps near walls stay within half range; each value
  // keeps 11 significant bits, 0.05%).
  std::vector<std::vector<uint16_t>> direct;
  std::vector<float> directScale;

  bool active() const { return texelCount > 0; }
  // Bytes the layers hold, and of which the per-source direct light.
  size_t memoryBytes() const;
  size_t directBytes() const;
  // Empty when every array agrees with the counts and every corner lies in an indirect atlas
  // of `indirectAtlases`, else what is wrong.
  std::string validate(size_t sources, const std::vector<AtlasLayout>& indirectAtlases) const;
};

// The bilinear weights of a lightmap texel's corners (masked, renormalised; equal when the
// point has no bilinear weight on any corner that counts; all 0 when none counts) and their
// indirect texels (kNoTexel where the pixel has none).
void cornerWeights(const IndirectCorners& c, const std::vector<AtlasLayout>& indirectAtlases,
                   uint32_t texel[4], float weight[4]);

// Half floats of values / scale, where scale is the largest value (1 when all are 0).
float encodeDirectLayer(const std::vector<float>& values, std::vector<uint16_t>& halves);

}  // namespace afterglow::runtime
