#include "afterglow/baker/shadowmask.h"

#include <algorithm>
#include <limits>

#include "afterglow/runtime/lightmap_layers.h"
#include "shading/light_model.h"

namespace afterglow::baker {
namespace {

// Whether two lights can light one point: their reaches (spheres of their ranges; all space
// for a directional light or one without a range) meet.
bool overlap(const scenes::Light& a, const scenes::Light& b) {
  auto reach = [](const scenes::Light& l) {
    return l.type == scenes::LightType::Directional || !(l.range > 0.0f)
               ? std::numeric_limits<float>::infinity()
               : l.range;
  };
  return glm::length(a.position - b.position) < reach(a) + reach(b);
}

}  // namespace

std::vector<int> shadowmaskChannels(const std::vector<scenes::Light>& lights,
                                    std::vector<std::string>* overflow) {
  std::vector<int> channel(lights.size(), -1);
  for (size_t i = 0; i < lights.size(); ++i) {
    if (lights[i].mode != scenes::LightMode::Mixed) continue;
    bool taken[kShadowmaskChannels] = {};
    for (size_t j = 0; j < i; ++j)
      if (channel[j] >= 0 && overlap(lights[i], lights[j])) taken[channel[j]] = true;
    for (int c = 0; c < kShadowmaskChannels && channel[i] < 0; ++c)
      if (!taken[c]) channel[i] = c;
    if (channel[i] < 0 && overflow) overflow->push_back(lights[i].name);
  }
  return channel;
}

std::vector<glm::vec4> shadowmaskTexels(const scenes::Scene& scene, const TexelSet& lightmap,
                                        const runtime::TransportData& transport,
                                        const std::vector<int>& channels) {
  std::vector<glm::vec4> mask(lightmap.size(), glm::vec4(1.0f));
  const runtime::LightmapLayers& layers = transport.lightmap;
  // Light sources come first in the transport, in the scene's light order.
  for (size_t k = 0; k < channels.size() && k < scene.lights.size() && k < transport.sources.size();
       ++k) {
    if (channels[k] < 0) continue;
    const bool layered = layers.active() && k < layers.direct.size() &&
                         layers.direct[k].size() == lightmap.size();
    const std::vector<float>& transfer = transport.sources[k].texelTransfer;
    if (!layered && transfer.size() != lightmap.size()) continue;
    for (uint32_t t = 0; t < lightmap.size(); ++t) {
      if (!lightmap.valid[t]) continue;
      const float unshadowed =
          viewLight(scene.lights[k], lightmap.position[t], lightmap.normal[t]).transfer;
      if (!(unshadowed > 0.0f)) continue;
      const float direct = layered ? runtime::halfToFloat(layers.direct[k][t]) * layers.directScale[k]
                                   : transfer[t];
      mask[t][channels[k]] = std::clamp(direct / unshadowed, 0.0f, 1.0f);
    }
  }
  return mask;
}

}  // namespace afterglow::baker
