// Which texels lie on one surface, and the sight lines between points on surfaces: what the
// gather's blocks, the clusters, the far fields' sharing and the filter's neighbours test
// before they let two places share light.
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "afterglow/baker/texels.h"
#include "afterglow/trace/raytracer.h"

namespace afterglow::baker {

// Two texels on one surface: same instance, normals within 30°, neither above the other's
// plane by more than a fifth of their distance (so neither a step nor a fold lies between
// them). Texels that may share a gather point, a far field, or smooth each other's light.
inline bool sameSurface(const TexelSet& texels, uint32_t a, uint32_t b) {
  if (texels.instance[a] != texels.instance[b]) return false;
  if (glm::dot(texels.normal[a], texels.normal[b]) < 0.866f) return false;
  const glm::vec3 d = texels.position[b] - texels.position[a];
  const float distance = glm::length(d);
  return std::abs(glm::dot(texels.geometricNormal[a], d)) <= 0.2f * distance &&
         std::abs(glm::dot(texels.geometricNormal[b], d)) <= 0.2f * distance;
}

// The ray from `from` to `to`, ending there; false when the two coincide.
inline bool segment(glm::vec3 from, glm::vec3 to, trace::Ray& ray) {
  const glm::vec3 d = to - from;
  const float length = glm::length(d);
  if (!(length > 0.0f)) return false;
  ray.origin = from;
  ray.direction = d / length;
  ray.tfar = length;
  return true;
}

// The sight line from a point on a surface (normal na) to another on the same or a nearby
// surface (nb), both lifted off their surfaces by a quarter of their distance, so the surface
// itself does not block it when it curves within a normal cone; false when the two coincide
// (nothing can stand between them). Clusters test their texels and the filter its neighbours
// with it.
inline bool liftedSightLine(glm::vec3 pa, glm::vec3 na, glm::vec3 pb, glm::vec3 nb, trace::Ray& ray) {
  const float lift = 0.25f * glm::length(pb - pa);
  return segment(pa + na * lift, pb + nb * lift, ray);
}

}  // namespace afterglow::baker
