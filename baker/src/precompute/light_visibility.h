// Which punctual lights reach a point, as a bit set: the gather's check that a ray's hit point
// is lit like the texel whose light it takes (texel_of_hit.h, TexelOfHit's light match).
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
// surface counts as unreached); the first 31 lights. Emissive surfaces are not in the set. A
// light reaches a point through glass (trace::Glass::Light): some of it gets there.
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
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/trace/raytracer.h"
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
  size_t size() const { return lights_.size(); }
  // Light i's hard shadow ray from p, a point lifted off a surface whose side facing the
  // arriving light is `normal` (unit), or false when light i cannot reach p.
  bool shadowRayOf(size_t i, glm::vec3 p, glm::vec3 normal, trace::Ray& ray) const {
    return shadowRay(lights_[i], p, normal, ray);
  }

  // Every texel's, at its sample on its front side (0 for every texel without lights), with
  // kUneven when one of four points of its footprint (footprintPoints) is reached by other
  // lights.
  std::vector<uint32_t> texels(const trace::RayTracer& tracer, const TexelSet& texels) const {
    std::vector<uint32_t> out(texels.size(), 0);
    if (empty()) return out;
    // A block's rays traced as one stream (one by one they ran at half Embree's rate): per
    // texel its sample's, then those of every fifth of its footprint's points (the grid's
    // diagonal, or as many as fall inside the triangle, spread), light by light.
    parallelForBlocks(texels.size(), [&](size_t begin, size_t end, int) {
      struct Query {
        uint32_t texel, point, light;  // point 0: the sample
      };
      std::vector<trace::Ray> rays;
      std::vector<Query> queries;
      glm::vec3 points[16];
      std::vector<uint32_t> bits;  // per texel of the block and point (up to 5)
      bits.assign((end - begin) * 5, 0);
      std::vector<uint8_t> pointCount(end - begin, 0);
      for (size_t t = begin; t < end; ++t) {
        glm::vec3 at[5];
        at[0] = texels.position[t];
        int m = 1;
        const int n = footprintPoints(tracer.scene(), texels, uint32_t(t), points);
        for (int i = 0; i < n && m < 5; i += n > 4 ? 5 : 1) at[m++] = points[i];
        pointCount[t - begin] = uint8_t(m);
        for (int j = 0; j < m; ++j)
          for (size_t i = 0; i < lights_.size(); ++i) {
            trace::Ray ray;
            if (!shadowRay(lights_[i], at[j], texels.geometricNormal[t], ray)) continue;
            rays.push_back(ray);
            queries.push_back({uint32_t(t - begin), uint32_t(j), uint32_t(i)});
          }
      }
      std::unique_ptr<bool[]> blocked(new bool[rays.size() + 1]);
      tracer.occluded(rays.data(), blocked.get(), rays.size(), trace::Glass::Light);
      for (size_t k = 0; k < rays.size(); ++k)
        if (!blocked[k]) bits[queries[k].texel * 5 + queries[k].point] |= 1u << queries[k].light;
      for (size_t t = begin; t < end; ++t) {
        const uint32_t* b = &bits[(t - begin) * 5];
        out[t] = b[0];
        for (int j = 1; j < pointCount[t - begin]; ++j)
          if (b[j] != b[0]) out[t] |= kUneven;
      }
    }, 256);
    return out;
  }

 private:
  // The hard shadow ray from p toward light l's centre, or false when l cannot reach p
  // (outside a spot's outer cone, past its range, behind the surface).
  static bool shadowRay(const scenes::Light& l, glm::vec3 p, glm::vec3 normal, trace::Ray& ray) {
    ray.origin = p;
    ray.mask = trace::kMaskShadowCasters;
    if (l.type == scenes::LightType::Directional) {
      ray.direction = -glm::normalize(l.direction);
    } else {
      const glm::vec3 d = l.position - p;
      const float distance = glm::length(d);
      if (!(distance > 0.0f) || (l.range > 0.0f && distance > l.range)) return false;
      ray.direction = d / distance;
      ray.tfar = distance;
      if (l.type == scenes::LightType::Spot &&
          glm::dot(-ray.direction, glm::normalize(l.direction)) < std::cos(l.outerConeAngle))
        return false;
    }
    return glm::dot(ray.direction, normal) > 0.0f;
  }

  std::vector<scenes::Light> lights_;
};

}  // namespace afterglow::baker
