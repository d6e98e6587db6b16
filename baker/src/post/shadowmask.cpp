#include "afterglow/baker/shadowmask.h"

#include <algorithm>
#include <limits>

#include "afterglow/core/parallel.h"
#include "afterglow/runtime/lightmap_layers.h"
#include "afterglow/trace/raytracer.h"
#include "shading/light_model.h"
#include "shading/sampling.h"

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

std::vector<glm::vec4> probeOcclusion(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                      const std::vector<glm::vec3>& positions,
                                      const std::vector<int>& channels, int rays) {
  std::vector<glm::vec4> occlusion(positions.size(), glm::vec4(1.0f));
  const sampling::Stratified strata{uint32_t(std::max(1, rays))};
  parallelForBlocks(positions.size(), [&](size_t begin, size_t end, int) {
    for (size_t p = begin; p < end; ++p)
      for (size_t k = 0; k < channels.size() && k < scene.lights.size(); ++k) {
        if (channels[k] < 0) continue;
        const scenes::Light& light = scene.lights[k];
        // The light as seen facing it (a probe has no surface): its centre, distance, extent.
        const glm::vec3 toLight = light.type == scenes::LightType::Directional
                                      ? -glm::normalize(light.direction)
                                      : glm::normalize(light.position - positions[p]);
        const LightView view = viewLight(light, positions[p], toLight);
        const int count = view.hasExtent ? std::max(1, rays) : 1;
        const sampling::Rng::ItemSeed seed{
            sampling::Rng::itemSeed(sampling::Stream::ProbeOcclusion, p)};
        int through = 0;
        for (int s = 0; s < count; ++s) {
          sampling::Rng rng(seed, (uint64_t(k) << 32) | uint64_t(s));
          trace::Ray ray;
          ray.origin = positions[p];
          lightShadowRay(light, view, positions[p], strata.point(rng, uint32_t(s)), &ray.direction,
                         &ray.tfar);
          ray.mask = trace::kMaskShadowCasters;
          through += tracer.occluded(ray) ? 0 : 1;
        }
        occlusion[p][channels[k]] = float(through) / float(count);
      }
  }, 256);
  return occlusion;
}

}  // namespace afterglow::baker
