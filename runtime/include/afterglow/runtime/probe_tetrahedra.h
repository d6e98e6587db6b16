// Light probes' tetrahedral mesh and point location (GLM only: engines sample probes with it).
// The mesh is a 3D Delaunay tetrahedralisation of the probe positions (probes::tetrahedralize
// builds it); a point inside the hull is interpolated with the barycentric weights of the
// tetrahedron that holds it, found by walking from a hinted tetrahedron across the faces the
// point lies beyond. A point outside the hull takes the closest point on the hull: projected
// onto the nearest hull face and clamped to it (Unity's approach; the face the walk leaves
// through need not be the nearest, so every hull face is searched), so the weights change
// continuously as the point crosses the hull.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace afterglow::runtime {

struct ProbeTetrahedra {
  std::vector<glm::vec3> positions;    // probe positions, world
  // Four probe indices per tetrahedron, positively oriented:
  // dot(p1 − p0, cross(p2 − p0, p3 − p0)) > 0.
  std::vector<glm::ivec4> tetrahedra;
  // Per tetrahedron, the tetrahedron across the face opposite each of its four corners, or -1
  // on the hull.
  std::vector<glm::ivec4> neighbours;
};

struct ProbeLocation {
  int tetrahedron = -1;      // the one holding the point (or whose hull face it projects to)
  glm::ivec4 probes{-1};     // its four probes (-1 where a weight is unused)
  glm::vec4 weights{0.0f};   // non-negative, summing to 1 (all 0 for an empty mesh)
  bool inside = false;       // false: outside the hull, projected onto a hull face
};
// Outside the hull, probes[0..2] are the hull face's three corners (in the tetrahedron's corner
// order) and probes[3] is -1 with weight 0. Without tetrahedra, probes[0] is the nearest probe
// with weight 1 and the rest are -1.

// Where p lies, walking from `hint` (any tetrahedron index; out-of-range starts at 0). Returns
// tetrahedron -1 for an empty mesh (and no probes) or a mesh without tetrahedra: with a single
// probe or probes that span no volume (fewer than 4, or all in a plane) the nearest probe takes
// weight 1. Barycentric coordinates are computed in double precision; a walk longer than the
// tetrahedron count (a cycle) falls back to a scan of every tetrahedron. A p that is not finite
// gives the first tetrahedron's first probe weight 1.
ProbeLocation locateProbe(const ProbeTetrahedra& mesh, glm::vec3 p, int hint = 0);

// Empty when every index is in range, every tetrahedron positively oriented with a non-zero
// volume, and neighbours are mutual (t's neighbour across a face has t across the same face);
// otherwise what is wrong, naming the tetrahedron.
std::string checkProbeTetrahedra(const ProbeTetrahedra& mesh);

}  // namespace afterglow::runtime
