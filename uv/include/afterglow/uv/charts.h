// Chart segmentation and parameterisation of one mesh (stage 1 of afterglow uv).
//
// Charts are computed once per Mesh in object space; every instance of the mesh later gets its own
// copy of the charts in the atlas (packing, pack.h). The mesh's vertices are split where chart
// boundaries run, so a vertex belongs to exactly one chart.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/scenes/scene.h"

namespace afterglow::uv {

struct ChartOptions {
  // A face joins a growing chart only if its normal is within this angle of the chart's mean
  // normal. Neighbouring charts may then merge past it when the union still unfolds flip-free
  // with little stretch (a cylinder unrolls as one or two charts).
  float maxChartAngleDeg = 40.0f;       // degrees
  // Edges whose dihedral angle exceeds this are always chart boundaries (hard edges).
  float hardEdgeAngleDeg = 60.0f;       // degrees
  // Edges where the input's vertex normals differ by more than this are chart boundaries too
  // (hard shading edges). Faceted low-poly surfaces split their normals at smaller angles; they
  // stay in one chart below this angle.
  float shadingSeamAngleDeg = 45.0f;    // degrees
  // Faces within this angle of the chart's plane keep a chart planar (projected, zero stretch).
  float planarAngleDeg = 1.0f;          // degrees
  // Triangles with area below this fraction of the primitive's mean triangle area count as
  // degenerate: they join a chart that holds one of their vertices, and are a (zero-area) chart of
  // their own only when no such chart exists.
  float degenerateAreaFraction = 1e-6f; // unitless
};

// A chart: connected triangles of one primitive that are unfolded together.
struct Chart {
  int primitive = 0;                // index into Mesh::primitives
  std::vector<uint32_t> triangles;  // triangle indices within that primitive
  double area3d = 0.0;              // object-space surface area, square metres (object units)
  double area2d = 0.0;              // parameter-space area, same units (== area3d after scaling)
  bool planar = false;              // true when projected onto a plane (no stretch)
};

// One primitive after the split: new vertices, each mapping back to an original vertex.
struct ChartedPrimitive {
  std::vector<uint32_t> vertexRemap;  // new vertex -> vertex index in the original Primitive
  std::vector<uint32_t> indices;      // 3 per triangle, same triangle order as the original
  std::vector<glm::vec2> chartUv;     // per new vertex: chart-local coordinates, object units,
                                      // scaled so each chart's 2D area equals its 3D area
  std::vector<uint32_t> vertexChart;  // per new vertex: index into MeshCharts::charts
};

struct MeshCharts {
  std::vector<ChartedPrimitive> primitives;  // parallel to Mesh::primitives
  std::vector<Chart> charts;
};

// Segments a mesh into charts and parameterises each with no flipped triangles: planar charts are
// projected; curved ones are unfolded with a conformal map (LSCM). Handles non-manifold edges,
// duplicate and zero-area faces. Deterministic.
MeshCharts computeCharts(const scenes::Mesh& mesh, const ChartOptions& options = {});

}  // namespace afterglow::uv
