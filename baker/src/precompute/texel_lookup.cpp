// TexelLookup's table, built once per set of valid texels (texel_lookup.h).
#include "precompute/texel_lookup.h"

#include "precompute/light_visibility.h"

namespace afterglow::baker {

TexelLookup::TexelLookup(const TexelSet& texels) : texels_(texels) {
  resolved_.resize(texels.atlases.size());
  for (size_t a = 0; a < texels.atlases.size(); ++a) {
    const runtime::AtlasLayout& layout = texels.atlases[a];
    std::vector<uint32_t>& out = resolved_[a];
    out.assign(layout.texelOfPixel.size(), runtime::kNoTexel);
    for (size_t p = 0; p < out.size(); ++p) {
      const uint32_t own = layout.texelOfPixel[p];
      if (own != runtime::kNoTexel && texels.valid[own])
        out[p] = own | (texels.nearGeometry[own] ? kNear : 0u);
    }
  }
}

void TexelLookup::setLights(const LightVisibility* lights, const std::vector<uint32_t>* reached) {
  lights_ = lights && !lights->empty() ? lights : nullptr;
  reached_ = reached;
}

}  // namespace afterglow::baker
