// Cosine-distributed gather rays in batches: shared by the texels' gather (gather.cpp) and the
// back-side clusters' rays (links.cpp), so both classify hits the same way.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/raytracer.h"
#include "afterglow/baker/texels.h"
#include "afterglow/baker/transport_precompute.h"
#include "sampling.h"

namespace afterglow::baker {

// The texel whose light a ray hit receives: the texel under the hit point (texelAt), unless a
// wall or object cuts through that texel's footprint and stands between the hit point and the
// texel's sample, as for a floor texel half under a box: a ray from inside the box that lands
// on the hidden half must not collect the light of the sample outside. Then the nearest texel
// of the same chart that the hit point does see stands in; with none, the ray is absorbed.
inline uint32_t texelOfHit(const RayTracer& tracer, const TexelSet& texels, const Hit& hit) {
  const scenes::Scene& scene = tracer.scene();
  const uint32_t t =
      texelAt(scene, texels, hit.instance, hit.primitive, hit.triangle, hit.barycentric);
  if (t == runtime::kNoTexel || !texels.nearGeometry[t]) return t;
  const glm::vec3 side = hit.frontFace ? hit.geometricNormal : -hit.geometricNormal;
  const glm::vec3 from = tracer.position(hit) + side * texels.offset[t];
  auto sees = [&](uint32_t candidate) {
    const glm::vec3 to =
        hit.frontFace ? texels.position[candidate] : texels.backPosition(candidate);
    const glm::vec3 d = to - from;
    const float length = glm::length(d);
    if (!(length > 0.0f)) return true;
    Ray ray;
    ray.origin = from;
    ray.direction = d / length;
    ray.tfar = length;
    return !tracer.occluded(ray);
  };
  if (sees(t)) return t;
  const runtime::AtlasLayout& layout = texels.atlases[texels.atlas[t]];
  const int x = texels.pixel[t].x, y = texels.pixel[t].y;
  uint32_t best = runtime::kNoTexel;
  float bestDistance = std::numeric_limits<float>::infinity();
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int nx = x + dx, ny = y + dy;
      if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= layout.width || ny >= layout.height)
        continue;
      const uint32_t n = layout.texelOfPixel[size_t(ny) * size_t(layout.width) + size_t(nx)];
      if (n == runtime::kNoTexel || !texels.valid[n] || texels.instance[n] != texels.instance[t])
        continue;
      const float distance = glm::length(texels.position[n] - from);
      if (distance < bestDistance && sees(n)) {
        bestDistance = distance;
        best = n;
      }
    }
  return best;
}

struct GatherBatch {
  std::vector<Ray> rays;
  std::vector<Hit> hits;
  std::vector<uint32_t> codes;  // per ray, a TexelGather hit code
  double sky[runtime::kShCount] = {};  // Σ SH basis over the rays that escaped
  int backfaces = 0;                   // rays that hit the back of single-sided geometry
  double inverseDistance = 0.0;        // Σ 1/t over rays that hit anything

  void clear() {
    rays.clear();
    codes.clear();
    for (double& v : sky) v = 0.0;
    backfaces = 0;
    inverseDistance = 0.0;
  }

  // Queues one cosine-distributed ray about the frame's normal. Directions below the geometric
  // surface are mirrored above it: a shading normal tilted away from the face must not send
  // rays into the surface the sample lies on.
  void add(glm::vec3 origin, const sampling::Frame& frame, glm::vec3 geometricNormal, glm::vec2 u) {
    glm::vec3 dir = frame.toWorld(sampling::cosineHemisphere(u));
    const float below = glm::dot(dir, geometricNormal);
    if (below < 0.0f) dir = glm::normalize(dir - 2.0f * below * geometricNormal);
    Ray ray;
    ray.origin = origin;
    ray.direction = dir;
    rays.push_back(ray);
  }

  // Traces the queued rays (appending their codes) and empties the queue.
  void trace(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels) {
    hits.resize(rays.size());
    tracer.intersect(rays.data(), hits.data(), rays.size());
    for (size_t k = 0; k < rays.size(); ++k) {
      const Hit& hit = hits[k];
      uint32_t code = TexelGather::kNoHit;
      if (!hit.valid()) {
        float y[runtime::kShCount];
        sampling::shBasis(rays[k].direction, y);
        for (int i = 0; i < runtime::kShCount; ++i) sky[i] += double(y[i]);
      } else {
        if (hit.t > 0.0f) inverseDistance += 1.0 / double(hit.t);
        if (!hit.frontFace && !tracer.material(hit).doubleSided) {
          ++backfaces;
        } else if (scene.instances[hit.instance].isStatic) {
          // Dynamic instances block the ray but take no part in bounces.
          const uint32_t t = texelOfHit(tracer, texels, hit);
          if (t != runtime::kNoTexel) code = hit.frontFace ? t : (t | TexelGather::kBackSide);
        }
      }
      codes.push_back(code);
    }
    rays.clear();
  }
};

}  // namespace afterglow::baker
