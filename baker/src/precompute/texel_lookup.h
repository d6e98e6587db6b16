// The texel under a gather ray's hit, as one table lookup per hit: the gather's hottest path
// after Embree, so slot() and resolve() stay inline.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/texels.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

class LightVisibility;

// texelAtUv as one table lookup per hit: for every atlas pixel, its texel when valid. Built
// from the texels' validity at the time; a hit on any other pixel (padding, or a texel that is
// unused or buried) takes texelAtUv: the valid neighbour nearest to the hit.
class TexelLookup {
 public:
  explicit TexelLookup(const TexelSet& texels);

  // The table entry for a point, or nullptr (outside the atlas, no lightmap): fetch it early
  // with __builtin_prefetch, the load misses the cache for nearly every hit.
  const uint32_t* slot(const scenes::Scene& scene, uint32_t instance, glm::vec2 uv1) const {
    const scenes::LightmapLocation& where =
        scenes::lightmapOf(scene.instances[instance], texels_.uvSet);
    if (where.atlas < 0 || size_t(where.atlas) >= resolved_.size()) return nullptr;
    const runtime::AtlasLayout& layout = texels_.atlases[size_t(where.atlas)];
    const float px = uv1.x * float(layout.width), py = uv1.y * float(layout.height);
    if (!(px >= 0.0f && py >= 0.0f && px < float(layout.width) && py < float(layout.height)))
      return nullptr;
    return &resolved_[size_t(where.atlas)][size_t(py) * size_t(layout.width) + size_t(px)];
  }

  // The texel, with kNear set when the hit point's sight line to its sample must be checked
  // (TexelOfHit): for a texel near other geometry (TexelSet::nearGeometry, packed in the same
  // table entry to save a second cache miss per hit), and always for a stand-in, the valid
  // neighbour nearest to the hit that texelAtUv finds when the texel under the hit is unused
  // or buried: its sample may lie past the very wall that buried that texel (a roof cutting
  // through a cornice). A texel from the table needs no instance check: a point inside a chart
  // only finds that chart's texels (charts sit `padding` texels apart).
  static constexpr uint32_t kNear = 0x80000000u;

  // Optional: the lights that reach each texel's sample (LightVisibility::texels), so that a
  // hit close to its ray's origin takes the light of a texel lit like the hit point
  // (TexelOfHit's light match). Both must outlive the lookup.
  void setLights(const LightVisibility* lights, const std::vector<uint32_t>* reached);
  const LightVisibility* lights() const { return lights_; }
  const std::vector<uint32_t>& reached() const { return *reached_; }

  uint32_t resolve(const scenes::Scene& scene, uint32_t instance, glm::vec2 uv1,
                   const uint32_t* entry) const {
    if (entry && *entry != runtime::kNoTexel) return *entry;
    const uint32_t t = texelAtUv(scene, texels_, instance, uv1);
    return t == runtime::kNoTexel ? t : (t | kNear);
  }

 private:
  const TexelSet& texels_;
  std::vector<std::vector<uint32_t>> resolved_;
  const LightVisibility* lights_ = nullptr;
  const std::vector<uint32_t>* reached_ = nullptr;
};

}  // namespace afterglow::baker
