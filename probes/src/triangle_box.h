// Triangle against axis-aligned box overlap: the separating-axis test of Akenine-Möller (2001),
// for the probe placement's octree refinement (Embree has no box query).
#pragma once

#include <glm/glm.hpp>

namespace afterglow::probes {

// true when the triangle (a, b, c) and the box [lo, hi] share a point (touching counts).
bool triangleOverlapsBox(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 lo, glm::vec3 hi);

}  // namespace afterglow::probes
