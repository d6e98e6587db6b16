// Lightmap post-processing, as mixes in the atlas layouts (runtime::AtlasLayout): the pixels of
// invalid texels (buried in geometry or wedged in gaps) take their value from the nearest valid
// texels of the same instance, and every chart grows `dilation` pixels into its padding so
// bilinear filtering at chart borders never fetches an unbaked (black) pixel. Mixes are linear
// in the texel values, so the runtime applies the same post-processing to relit values.
#pragma once

#include <vector>

#include "afterglow/baker/texels.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::baker {

// Writes the mixes of every atlas of `texels` (replacing any there). A pixel reached from
// several nearest sources at once averages them; a mix keeps at most kMaxMix texels (the
// strongest), renormalised. An invalid texel with no valid texel of its instance to take
// light from gets an empty mix (black).
void computeAtlasMixes(TexelSet& texels, int dilation);

constexpr size_t kMaxMix = 4;

}  // namespace afterglow::baker
