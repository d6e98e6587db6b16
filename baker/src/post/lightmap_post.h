// Lightmap post-processing, as mixes in the atlas layouts (runtime::AtlasLayout): the pixels of
// invalid texels (buried in geometry or wedged in gaps) take their value from the nearest valid
// texels of the same instance, every chart grows `dilation` pixels into its padding so
// bilinear filtering at chart borders never fetches an unbaked (black) pixel, and the pixels
// along seams (an edge the unwrapper cut into two charts where the surface runs on smoothly)
// are stitched so bilinear lookups on either side of the seam agree (seams.h). Mixes are linear
// in the texel values, so the runtime applies the same post-processing to relit values.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "afterglow/baker/texels.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

struct PostOptions {
  int dilation = 2;               // pixels: how far each chart grows into its padding
  bool stitchSeams = true;        // stitch seams after filling and dilating (seams.h)
  // Seams whose two faces' normals, or whose shading normals at either shared corner, differ by
  // more than this are hard edges (a box's corner): the light legitimately differs across them
  // and they are left alone. Half the unwrapper's hard-edge angle (60°).
  float stitchMaxAngleDeg = 30.0f;  // degrees
  // Weight of keeping each stitched pixel at its unstitched value, against 1 per seam sample
  // for the two sides agreeing (seams.h explains the choice).
  float stitchLambda = 0.05f;     // unitless
  int stitchIterations = 8;       // Gauss-Seidel sweeps over the seam samples
  size_t stitchMaxMix = 16;       // texels a stitched pixel may mix at most
};

// What stitching did, summed over atlases.
struct PostStats {
  size_t seamEdges = 0;        // mesh edges stitched
  size_t seamSamples = 0;      // points along them where both sides are made to agree
  size_t stitchedPixels = 0;   // pixels whose mix stitching rewrote
  size_t stitchedEntries = 0;  // mix entries those pixels hold
};

// Writes the mixes of every atlas of `texels` (replacing any there): fill, then dilation, then
// seam stitching. A pixel reached from several nearest sources at once averages them; a fill or
// dilation mix keeps at most kMaxMix texels (the strongest), renormalised, a stitched one at
// most options.stitchMaxMix. An invalid texel with no valid texel of its instance to take
// light from gets an empty mix (black). Seams are found on the scene's lightmapped static
// instances (the scene `texels` was computed from); a pixel holding a valid texel becomes a
// mix when stitching changes it.
PostStats computeAtlasMixes(TexelSet& texels, const scenes::Scene& scene,
                            const PostOptions& options = {});

constexpr size_t kMaxMix = 4;

// A pixel's value as texel weights (sorted by texel) while the mixes are built.
using PixelMix = std::vector<std::pair<uint32_t, float>>;

// Σ scale · mix over `parts`, merged by texel, trimmed to the `cap` entries largest in
// magnitude (ties by texel, so the choice depends on nothing else). The weight a trim drops is
// spread over the kept entries in proportion to their magnitude, so the weights still sum to
// what they summed to: a constant lightmap stays constant.
PixelMix combineMixes(const std::vector<std::pair<const PixelMix*, float>>& parts, size_t cap);

}  // namespace afterglow::baker
