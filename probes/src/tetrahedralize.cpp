// The light probes' Delaunay tetrahedralisation with CGAL (exact predicates, so no degenerate
// or inverted tetrahedra whatever the input), converted to the runtime's ProbeTetrahedra.
#include "afterglow/probes/tetrahedralize.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_data_structure_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <CGAL/property_map.h>
#include <CGAL/spatial_sort.h>
#include <CGAL/Spatial_sort_traits_adapter_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <utility>

namespace afterglow::probes {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
// Vertices carry their probe index; cells their output index (-1: infinite).
using Vb = CGAL::Triangulation_vertex_base_with_info_3<int, K>;
using Cb = CGAL::Triangulation_cell_base_with_info_3<int, K, CGAL::Delaunay_triangulation_cell_base_3<K>>;
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
using Delaunay = CGAL::Delaunay_triangulation_3<K, Tds>;

}  // namespace

Result<runtime::ProbeTetrahedra> tetrahedralize(const std::vector<glm::vec3>& positions) {
  for (size_t i = 0; i < positions.size(); ++i) {
    const glm::vec3& p = positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      return Result<runtime::ProbeTetrahedra>::error(
          format("probe %zu: position (%g, %g, %g) is not finite", i, double(p.x), double(p.y),
                 double(p.z)));
  }

  // One at a time along CGAL's spatial sort (a Hilbert order over a shuffle by a fixed-seed
  // generator, boost::rand48 default-constructed: the same order for the same positions), each
  // located from the previous one: 100,000 random probes take 0.6 s instead of 2.7 s in the
  // given order. The Delaunay tetrahedralisation does not depend on the insertion order anyway
  // (CGAL's symbolic perturbation of cospherical points depends on the points alone; the test
  // IsDeterministicAndCanonical checks it on a grid), and the sort below fixes the numbering.
  using Indexed = std::pair<Delaunay::Point, int>;
  std::vector<Indexed> points;
  points.reserve(positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    const glm::vec3& p = positions[i];
    points.emplace_back(Delaunay::Point(double(p.x), double(p.y), double(p.z)), int(i));
  }
  CGAL::spatial_sort(points.begin(), points.end(),
                     CGAL::Spatial_sort_traits_adapter_3<K, CGAL::First_of_pair_property_map<Indexed>>());
  Delaunay dt;
  Delaunay::Vertex_handle previous;
  for (const auto& [point, index] : points) {
    const size_t before = dt.number_of_vertices();
    Delaunay::Vertex_handle v =
        previous == Delaunay::Vertex_handle() ? dt.insert(point) : dt.insert(point, previous->cell());
    if (dt.number_of_vertices() == before)
      return Result<runtime::ProbeTetrahedra>::error(
          format("probes %d and %d are at the same position (%g, %g, %g)",
                 std::min(v->info(), index), std::max(v->info(), index), point.x(), point.y(),
                 point.z()));
    v->info() = index;
    previous = v;
  }

  runtime::ProbeTetrahedra mesh;
  mesh.positions = positions;
  if (dt.dimension() < 3) return mesh;  // fewer than four probes, or all in a plane

  // Each finite cell's corners, positively oriented (CGAL's cells already are; swapping two
  // corners otherwise, with their neighbours), keyed by its sorted probe indices.
  struct Tet {
    Delaunay::Cell_handle cell;
    std::array<int, 4> order;  // output corner k is CGAL's vertex order[k]
    glm::ivec4 corners;
    glm::ivec4 key;
  };
  std::vector<Tet> tets;
  tets.reserve(dt.number_of_finite_cells());
  const K::Orientation_3 orientation = K().orientation_3_object();
  for (auto c = dt.all_cells_begin(); c != dt.all_cells_end(); ++c) c->info() = -1;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    Tet t;
    t.cell = c;
    t.order = {0, 1, 2, 3};
    if (orientation(c->vertex(0)->point(), c->vertex(1)->point(), c->vertex(2)->point(),
                    c->vertex(3)->point()) == CGAL::NEGATIVE)
      std::swap(t.order[2], t.order[3]);
    for (int k = 0; k < 4; ++k) t.corners[k] = c->vertex(t.order[size_t(k)])->info();
    std::array<int, 4> sorted = {t.corners[0], t.corners[1], t.corners[2], t.corners[3]};
    std::sort(sorted.begin(), sorted.end());
    t.key = glm::ivec4(sorted[0], sorted[1], sorted[2], sorted[3]);
    tets.push_back(t);
  }
  std::sort(tets.begin(), tets.end(), [](const Tet& a, const Tet& b) {
    for (int k = 0; k < 4; ++k)
      if (a.key[k] != b.key[k]) return a.key[k] < b.key[k];
    return false;
  });
  for (size_t i = 0; i < tets.size(); ++i) tets[i].cell->info() = int(i);

  mesh.tetrahedra.reserve(tets.size());
  mesh.neighbours.reserve(tets.size());
  for (const Tet& t : tets) {
    mesh.tetrahedra.push_back(t.corners);
    glm::ivec4 n;
    // CGAL's neighbour(i) is across the face opposite vertex(i), as ours.
    for (int k = 0; k < 4; ++k) n[k] = t.cell->neighbor(t.order[size_t(k)])->info();
    mesh.neighbours.push_back(n);
  }
  return mesh;
}

}  // namespace afterglow::probes
