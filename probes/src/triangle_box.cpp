#include "triangle_box.h"

#include <algorithm>
#include <cmath>

namespace afterglow::probes {

namespace {

// Projections of the three vertices and of the box (half extents h) on an axis separate them?
bool separated(glm::vec3 axis, glm::vec3 v0, glm::vec3 v1, glm::vec3 v2, glm::vec3 h) {
  const float p0 = glm::dot(axis, v0), p1 = glm::dot(axis, v1), p2 = glm::dot(axis, v2);
  const float r = h.x * std::abs(axis.x) + h.y * std::abs(axis.y) + h.z * std::abs(axis.z);
  const float lo = std::min({p0, p1, p2}), hi = std::max({p0, p1, p2});
  return lo > r || hi < -r;
}

}  // namespace

bool triangleOverlapsBox(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 lo, glm::vec3 hi) {
  const glm::vec3 centre = 0.5f * (lo + hi), h = 0.5f * (hi - lo);
  const glm::vec3 v0 = a - centre, v1 = b - centre, v2 = c - centre;
  // The box's face normals: the triangle's bounds against the box.
  for (int i = 0; i < 3; ++i) {
    const float mn = std::min({v0[i], v1[i], v2[i]}), mx = std::max({v0[i], v1[i], v2[i]});
    if (mn > h[i] || mx < -h[i]) return false;
  }
  const glm::vec3 e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
  // The triangle's plane.
  const glm::vec3 n = glm::cross(e0, e1);
  if (separated(n, v0, v1, v2, h)) return false;
  // The nine cross products of box axes and triangle edges (zero axes separate nothing).
  const glm::vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const glm::vec3& u : axes)
    for (const glm::vec3& e : {e0, e1, e2}) {
      const glm::vec3 axis = glm::cross(u, e);
      if (axis == glm::vec3(0.0f)) continue;
      if (separated(axis, v0, v1, v2, h)) return false;
    }
  return true;
}

}  // namespace afterglow::probes
