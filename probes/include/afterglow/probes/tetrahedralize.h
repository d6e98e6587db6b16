// The light probes' Delaunay tetrahedralisation (CGAL's Delaunay_triangulation_3 with exact
// predicates), as the runtime's ProbeTetrahedra: tetrahedra positively oriented, each with its
// four neighbours. Deterministic: the same positions give the same tetrahedra in the same order,
// whatever the thread count (the construction runs on one thread; probes are inserted along
// CGAL's spatial sort, whose shuffle has a fixed seed, the tetrahedralisation does not depend on
// the insertion order thanks to CGAL's symbolic perturbation, and the tetrahedra are sorted by
// their sorted corner indices).
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/status.h"
#include "afterglow/runtime/probe_tetrahedra.h"

namespace afterglow::probes {

// Errors: a position that is not finite (naming its index), two probes at the same position
// (naming both, the lower first). Fewer than four probes, or probes in one plane, give a mesh
// without tetrahedra (positions only).
Result<runtime::ProbeTetrahedra> tetrahedralize(const std::vector<glm::vec3>& positions);

}  // namespace afterglow::probes
