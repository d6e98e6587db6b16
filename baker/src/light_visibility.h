// Which punctual lights reach a point, as a bit set: the gather's check that a ray's hit point
// is lit like the texel whose light it takes (gather_rays.h, TexelOfHit::lightMatch).
//
// Why: a gather ray that lands a centimetre away, on a surface whose texel sample lies a
// quarter metre off in full sun while the hit point sits in the shadow of the very geometry
// the ray left from (a column's foot on an arch), takes that sunlit texel's light. On
// Sponza-sun at 4 texels/m one such texel was 59% of the bounced light's mean squared error
// against the reference path tracer (issue 16). Lights are static, so whether each reaches a
// point is geometry, and a hit may take the light of a texel that is lit alike.
//
// One hard shadow ray toward each light's centre (a directional light's direction, a point or
// spot light's position; outside a spot's outer cone, past a light's range, or behind the
// surface counts as unreached); the first 31 lights. Emissive surfaces are not in the set.
//
// Per texel also whether its footprint is lit evenly (kUneven when one of four points of it
// is reached by other lights than its sample): a front cluster reflects its texels' light
// averaged over their footprints (direct.cpp), so a hit lit like its texel's sample should
// still take an evenly lit neighbour's light when the texel is partly shadowed (a floor texel
// half in a wall's contact shadow reflects half its sample's sunlight).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/raytracer.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/parallel.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

class LightVisibility {
 public:
  static constexpr uint32_t kUneven = 1u << 31;  // texels(): the footprint is lit unevenly

  explicit LightVisibility(const scenes::Scene& scene) {
    for (const scenes::Light& l : scene.lights)
      if (lights_.size() < 31) lights_.push_back(l);
  }
  bool empty() const { return lights_.empty(); }

  // Bit i set when light i reaches p, a point lifted off a surface whose side facing the
  // arriving light is `normal` (unit).
  uint32_t at(const RayTracer& tracer, glm::vec3 p, glm::vec3 normal) const {
    uint32_t bits = 0;
    for (size_t i = 0; i < lights_.size(); ++i) {
      const scenes::Light& l = lights_[i];
      Ray ray;
      ray.origin = p;
      ray.mask = kMaskShadowCasters;
      if (l.type == scenes::LightType::Directional) {
        ray.direction = -glm::normalize(l.direction);
      } else {
        const glm::vec3 d = l.position - p;
        const float distance = glm::length(d);
        if (!(distance > 0.0f) || (l.range > 0.0f && distance > l.range)) continue;
        ray.direction = d / distance;
        ray.tfar = distance;
        if (l.type == scenes::LightType::Spot &&
            glm::dot(-ray.direction, glm::normalize(l.direction)) < std::cos(l.outerConeAngle))
          continue;
      }
      if (glm::dot(ray.direction, normal) <= 0.0f) continue;
      if (!tracer.occluded(ray)) bits |= 1u << i;
    }
    return bits;
  }

  // Every texel's, at its sample on its front side (0 for every texel without lights), with
  // kUneven when one of four points of its footprint (footprintPoints) is reached by other
  // lights.
  std::vector<uint32_t> texels(const RayTracer& tracer, const TexelSet& texels) const {
    std::vector<uint32_t> out(texels.size(), 0);
    if (empty()) return out;
    parallelFor(texels.size(), [&](size_t t) {
      const uint32_t own = at(tracer, texels.position[t], texels.geometricNormal[t]);
      out[t] = own;
      // Every fifth of the footprint's points (its grid's diagonal, or as many as fall inside
      // the triangle, spread): an uneven footprint is rarely lit evenly along all of them.
      glm::vec3 points[16];
      const int n = footprintPoints(tracer.scene(), texels, uint32_t(t), points);
      for (int i = 0; i < n; i += n > 4 ? 5 : 1)
        if (at(tracer, points[i], texels.geometricNormal[t]) != own) {
          out[t] |= kUneven;
          break;
        }
    }, 1024);
    return out;
  }

 private:
  std::vector<scenes::Light> lights_;
};

}  // namespace afterglow::baker
