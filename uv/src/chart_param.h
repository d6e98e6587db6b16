// Parameterisation of one chart (internal to afterglow_uv): planar projection, LSCM, and the
// quality checks (flips, L2 stretch) that decide whether a chart is kept or split.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

namespace afterglow::uv::detail {

// A chart's own vertices and triangles (local indices), degenerate triangles left out.
struct ChartGeometry {
  std::vector<glm::dvec3> positions;
  std::vector<uint32_t> triangles;  // 3 local indices per triangle
};

struct ChartParam {
  std::vector<glm::dvec2> uv;  // per local vertex, scaled so area2d == area3d
  double area3d = 0.0;
  double stretch = 1.0;        // area-weighted L2 stretch (Sander et al. 2001), 1 = isometric
  int flipped = 0;             // triangles with non-positive UV area after orientation
  bool planar = false;
};

// Orthogonal projection onto the plane with the given unit normal.
ChartParam projectPlanar(const ChartGeometry& chart, glm::dvec3 normal);

// Least-squares conformal map with two pinned vertices far apart. Returns a param with
// flipped > 0 when the solve fails.
ChartParam solveLscm(const ChartGeometry& chart);

// LSCM over `triangles` for the vertices not pinned; pinned vertices keep their uv and anchor the
// rest (at least two must touch the triangles). False when the system is singular.
bool lscmSolve(const std::vector<glm::dvec3>& positions, const std::vector<uint32_t>& triangles,
               const std::vector<uint8_t>& pinned, std::vector<glm::dvec2>& uv);

// Orients the map counter-clockwise, counts flips, scales it so area2d == area3d and measures
// its stretch.
ChartParam evaluate(const ChartGeometry& chart, std::vector<glm::dvec2> uv);

// L2 stretch of one triangle for the map uv -> 3D, before any area normalisation (squared).
double triangleStretchSquared(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                              glm::dvec2 q0, glm::dvec2 q1, glm::dvec2 q2);

// True when two boundary segments (pairs of local vertex indices) properly cross in UV space.
// With no flipped triangles, a chart whose boundary does not cross itself maps one-to-one.
bool boundaryCrosses(const std::vector<glm::dvec2>& uv,
                     const std::vector<std::pair<uint32_t, uint32_t>>& segments);

}  // namespace afterglow::uv::detail
