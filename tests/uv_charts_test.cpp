// uv::computeCharts: exact chart counts on meshes whose geometry dictates them, stretch and flip
// bounds on curved surfaces, broken input (zero-area, duplicate, non-manifold faces),
// determinism, and Sponza against xatlas's chart count.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <tuple>
#include <array>
#include <algorithm>

#include "afterglow/core/math.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/uv/charts.h"
#include "test_util.h"

namespace afterglow::uv {
namespace {

using scenes::Mesh;
using scenes::Primitive;


Mesh single(Primitive p) {
  Mesh mesh;
  mesh.primitives.push_back(std::move(p));
  return mesh;
}

// glTF-style cube: 4 vertices per face (split at every edge), 12 triangles, outward normals.
Primitive cube() {
  Primitive p;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = -1; side <= 1; side += 2) {
      glm::vec3 n(0.0f), u(0.0f), v(0.0f);
      n[axis] = float(side);
      u[(axis + 1) % 3] = 1.0f;
      v[(axis + 2) % 3] = 1.0f;
      if (glm::dot(glm::cross(u, v), n) < 0.0f) std::swap(u, v);
      uint32_t base = uint32_t(p.positions.size());
      for (glm::vec2 c : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)}) {
        p.positions.push_back(0.5f * (n + u * c.x + v * c.y));
        p.normals.push_back(n);
      }
      for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) p.indices.push_back(base + i);
    }
  return p;
}

// A grid of cols x rows quads spanning origin + [0,1]*u + [0,1]*v, facing u x v.
void addGrid(Primitive& p, glm::vec3 origin, glm::vec3 u, glm::vec3 v, int cols, int rows) {
  glm::vec3 n = glm::normalize(glm::cross(u, v));
  uint32_t base = uint32_t(p.positions.size());
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i <= cols; ++i) {
      p.positions.push_back(origin + u * (float(i) / cols) + v * (float(j) / rows));
      p.normals.push_back(n);
    }
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) {
      uint32_t a = base + j * (cols + 1) + i, b = a + 1, c = a + cols + 1, d = c + 1;
      for (uint32_t k : {a, b, d, a, d, c}) p.indices.push_back(k);
    }
}

// Open cylinder (radius 1, height 2) with a duplicated seam column, as exporters write it.
Primitive cylinder(int segments, int rings) {
  Primitive p;
  for (int j = 0; j <= rings; ++j)
    for (int i = 0; i <= segments; ++i) {
      float a = 2.0f * kPi * float(i % segments) / float(segments);
      p.positions.push_back({std::cos(a), 2.0f * float(j) / rings, std::sin(a)});
      p.normals.push_back({std::cos(a), 0.0f, std::sin(a)});
      p.uv0.push_back({float(i) / segments, float(j) / rings});
    }
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < segments; ++i) {
      uint32_t a = j * (segments + 1) + i, b = a + 1, c = a + segments + 1, d = c + 1;
      for (uint32_t k : {a, c, d, a, d, b}) p.indices.push_back(k);
    }
  return p;
}

// UV sphere of radius 1 with poles as single vertices.
Primitive sphere(int segments, int stacks) {
  Primitive p;
  p.positions.push_back({0, 1, 0});
  p.normals.push_back({0, 1, 0});
  for (int j = 1; j < stacks; ++j)
    for (int i = 0; i < segments; ++i) {
      float theta = kPi * float(j) / stacks, phi = 2.0f * kPi * float(i) / segments;
      glm::vec3 q(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
      p.positions.push_back(q);
      p.normals.push_back(q);
    }
  p.positions.push_back({0, -1, 0});
  p.normals.push_back({0, -1, 0});
  const uint32_t south = uint32_t(p.positions.size() - 1);
  auto ring = [&](int j, int i) { return uint32_t(1 + (j - 1) * segments + (i % segments)); };
  for (int i = 0; i < segments; ++i) {
    for (uint32_t k : {0u, ring(1, i + 1), ring(1, i)}) p.indices.push_back(k);
    for (uint32_t k : {south, ring(stacks - 1, i), ring(stacks - 1, i + 1)}) p.indices.push_back(k);
  }
  for (int j = 1; j < stacks - 1; ++j)
    for (int i = 0; i < segments; ++i) {
      uint32_t a = ring(j, i), b = ring(j, i + 1), c = ring(j + 1, i), d = ring(j + 1, i + 1);
      for (uint32_t k : {a, b, d, a, d, c}) p.indices.push_back(k);
    }
  return p;
}

// Brute force: do two triangles of one chart overlap in UV (interiors, not shared edges)?
size_t overlappingPairs(const MeshCharts& charts) {
  auto orient = [](glm::dvec2 o, glm::dvec2 a, glm::dvec2 b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  };
  size_t pairs = 0;
  for (const Chart& chart : charts.charts) {
    const ChartedPrimitive& out = charts.primitives[chart.primitive];
    std::vector<std::array<glm::dvec2, 3>> uv;
    std::vector<std::array<uint32_t, 3>> ids;
    double extent = 0.0;
    for (uint32_t t : chart.triangles) {
      std::array<glm::dvec2, 3> q;
      std::array<uint32_t, 3> id;
      for (int k = 0; k < 3; ++k) {
        id[k] = out.indices[3 * t + k];
        q[k] = out.chartUv[id[k]];
        extent = std::max({extent, std::abs(q[k].x), std::abs(q[k].y)});
      }
      uv.push_back(q);
      ids.push_back(id);
    }
    const double eps = 1e-9 * extent * extent;
    for (size_t i = 0; i < uv.size(); ++i)
      for (size_t j = i + 1; j < uv.size(); ++j) {
        bool hit = false;
        for (int e = 0; e < 3 && !hit; ++e)
          for (int f = 0; f < 3 && !hit; ++f) {
            glm::dvec2 a = uv[i][e], b = uv[i][(e + 1) % 3], c = uv[j][f], d = uv[j][(f + 1) % 3];
            double d1 = orient(c, d, a), d2 = orient(c, d, b), d3 = orient(a, b, c), d4 = orient(a, b, d);
            hit = ((d1 > eps && d2 < -eps) || (d1 < -eps && d2 > eps)) &&
                  ((d3 > eps && d4 < -eps) || (d3 < -eps && d4 > eps));
          }
        for (int k = 0; k < 3 && !hit; ++k) {  // a vertex strictly inside the other triangle
          for (auto [p, q, pid, qid] : {std::tuple(&uv[i], &uv[j], &ids[i], &ids[j]),
                                        std::tuple(&uv[j], &uv[i], &ids[j], &ids[i])}) {
            glm::dvec2 v = (*p)[k];
            if ((*pid)[k] == (*qid)[0] || (*pid)[k] == (*qid)[1] || (*pid)[k] == (*qid)[2]) continue;
            double a = orient((*q)[0], (*q)[1], v), b = orient((*q)[1], (*q)[2], v),
                   c = orient((*q)[2], (*q)[0], v);
            if (a > eps && b > eps && c > eps) hit = true;
          }
        }
        if (hit) ++pairs;
      }
  }
  return pairs;
}

struct Quality {
  size_t flipped = 0;
  double stretch = 0.0;     // area-weighted L2 over all charts, each normalised to its 3D area
  double maxStretch = 0.0;  // worst chart
  double area3d = 0.0;
};

double signedArea(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return 0.5 * ((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
}

// Checks every invariant of the output and measures flips and stretch (Sander et al. 2001).
// flatDegenerates: zero-area triangles must get zero UV area too, which holds where they lie in
// flat or developable charts (not in triangle soup, where a collinear triple can sit in a curved
// chart whose map bends the line).
Quality check(const Mesh& mesh, const MeshCharts& charts, bool flatDegenerates = true) {
  Quality q;
  EXPECT_EQ(charts.primitives.size(), mesh.primitives.size());
  std::vector<std::vector<int>> chartOfTriangle(mesh.primitives.size());
  for (size_t p = 0; p < mesh.primitives.size(); ++p)
    chartOfTriangle[p].assign(mesh.primitives[p].triangleCount(), -1);
  for (size_t c = 0; c < charts.charts.size(); ++c) {
    const Chart& chart = charts.charts[c];
    EXPECT_FALSE(chart.triangles.empty());
    for (uint32_t t : chart.triangles) {
      EXPECT_EQ(chartOfTriangle[chart.primitive][t], -1) << "triangle in two charts";
      chartOfTriangle[chart.primitive][t] = int(c);
    }
  }
  double stretchSum = 0.0;
  for (size_t c = 0; c < charts.charts.size(); ++c) {
    const Chart& chart = charts.charts[c];
    const Primitive& prim = mesh.primitives[chart.primitive];
    const ChartedPrimitive& out = charts.primitives[chart.primitive];
    double area3d = 0.0, area2d = 0.0, chartStretch = 0.0, degenerateArea = 0.0;
    for (uint32_t t : chart.triangles) {
      glm::dvec3 p[3];
      glm::dvec2 uv[3];
      for (int k = 0; k < 3; ++k) {
        uint32_t v = out.indices[3 * t + k];
        EXPECT_EQ(out.vertexRemap[v], prim.indices[3 * t + k]);
        EXPECT_EQ(out.vertexChart[v], c);
        EXPECT_TRUE(std::isfinite(out.chartUv[v].x) && std::isfinite(out.chartUv[v].y));
        p[k] = prim.positions[prim.indices[3 * t + k]];
        uv[k] = out.chartUv[v];
      }
      double a3 = 0.5 * glm::length(glm::cross(p[1] - p[0], p[2] - p[0]));
      double a2 = signedArea(uv[0], uv[1], uv[2]);
      area3d += a3;
      if (a3 < 1e-9) { degenerateArea += std::abs(a2); continue; }  // zero-area input
      area2d += std::abs(a2);
      if (!(a2 > 0.0)) { ++q.flipped; continue; }
      glm::dvec3 ss = (p[0] * (uv[1].y - uv[2].y) + p[1] * (uv[2].y - uv[0].y) +
                       p[2] * (uv[0].y - uv[1].y)) / (2.0 * a2);
      glm::dvec3 st = (p[0] * (uv[2].x - uv[1].x) + p[1] * (uv[0].x - uv[2].x) +
                       p[2] * (uv[1].x - uv[0].x)) / (2.0 * a2);
      chartStretch += a3 * 0.5 * (glm::dot(ss, ss) + glm::dot(st, st));
    }
    EXPECT_NEAR(chart.area3d, area3d, 1e-6 * std::max(1.0, area3d));
    EXPECT_NEAR(chart.area2d, area3d, 1e-4 * area3d + 1e-9) << "chart " << c;
    EXPECT_NEAR(area2d, area3d, 1e-4 * area3d + 1e-9) << "chart " << c;
    if (flatDegenerates) {
      EXPECT_LE(degenerateArea, 1e-6 * std::max(area3d, 1e-3));
    }
    if (area3d > 0.0 && area2d > 0.0) {
      double l2 = std::sqrt(chartStretch / area3d * area2d / area3d);
      q.maxStretch = std::max(q.maxStretch, l2);
      stretchSum += l2 * l2 * area3d;
      q.area3d += area3d;
    }
  }
  for (const auto& prim : chartOfTriangle)
    for (int c : prim) EXPECT_GE(c, 0) << "triangle in no chart";
  q.stretch = q.area3d > 0.0 ? std::sqrt(stretchSum / q.area3d) : 1.0;
  return q;
}

TEST(UvCharts, CubeGivesSixPlanarCharts) {
  Mesh mesh = single(cube());
  MeshCharts charts = computeCharts(mesh);
  ASSERT_EQ(charts.charts.size(), 6u);
  for (const Chart& chart : charts.charts) {
    EXPECT_TRUE(chart.planar);
    EXPECT_EQ(chart.triangles.size(), 2u);
    EXPECT_NEAR(chart.area3d, 1.0, 1e-6);
  }
  // Each corner position sits in 3 charts: 8 corners x 3 = 24 split vertices.
  EXPECT_EQ(charts.primitives[0].vertexRemap.size(), 24u);
  Quality q = check(mesh, charts);
  EXPECT_EQ(q.flipped, 0u);
  EXPECT_NEAR(q.stretch, 1.0, 1e-6);
}

TEST(UvCharts, SubdividedPlaneIsOneChart) {
  Primitive p;
  addGrid(p, {0, 0, 0}, {3, 0, 0}, {0, 0, -2}, 10, 10);
  Mesh mesh = single(p);
  MeshCharts charts = computeCharts(mesh);
  ASSERT_EQ(charts.charts.size(), 1u);
  EXPECT_TRUE(charts.charts[0].planar);
  EXPECT_EQ(charts.charts[0].triangles.size(), 200u);
  EXPECT_EQ(charts.primitives[0].vertexRemap.size(), 121u);
  Quality q = check(mesh, charts);
  EXPECT_EQ(q.flipped, 0u);
  EXPECT_NEAR(q.stretch, 1.0, 1e-6);
  EXPECT_NEAR(charts.charts[0].area3d, 6.0, 1e-5);
}

TEST(UvCharts, PerpendicularPlanesAreTwoCharts) {
  Primitive p;
  addGrid(p, {0, 0, 0}, {2, 0, 0}, {0, 0, -2}, 4, 4);  // floor, facing +Y
  addGrid(p, {0, 0, -2}, {2, 0, 0}, {0, 2, 0}, 4, 4);  // wall along the floor's far edge, +Z
  Mesh mesh = single(p);
  MeshCharts charts = computeCharts(mesh);
  ASSERT_EQ(charts.charts.size(), 2u);
  for (const Chart& chart : charts.charts) {
    EXPECT_TRUE(chart.planar);
    EXPECT_EQ(chart.triangles.size(), 32u);
  }
  Quality q = check(mesh, charts);
  EXPECT_EQ(q.flipped, 0u);
  EXPECT_NEAR(q.stretch, 1.0, 1e-6);
}

TEST(UvCharts, PrimitivesNeverShareAChart) {
  Primitive a, b;
  addGrid(a, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 2, 2);
  addGrid(b, {1, 0, 0}, {1, 0, 0}, {0, 1, 0}, 2, 2);  // coplanar, touching a
  Mesh mesh;
  mesh.primitives = {a, b};
  MeshCharts charts = computeCharts(mesh);
  ASSERT_EQ(charts.charts.size(), 2u);
  EXPECT_EQ(charts.charts[0].primitive, 0);
  EXPECT_EQ(charts.charts[1].primitive, 1);
  check(mesh, charts);
}

// A cylinder is developable, but an open one is a ring: it needs one cut, and the normal cone
// (40 degrees) starts it as five strips that merging joins until only the ring-closing merge is
// left, so at most two charts, each unrolled without stretch.
TEST(UvCharts, CylinderUnrollsIntoFewCharts) {
  Mesh mesh = single(cylinder(32, 4));
  MeshCharts charts = computeCharts(mesh);
  EXPECT_LE(charts.charts.size(), 2u);
  Quality q = check(mesh, charts);
  EXPECT_EQ(q.flipped, 0u);
  EXPECT_LE(q.stretch, 1.02);
  EXPECT_LE(q.maxStretch, 1.02);
  EXPECT_EQ(overlappingPairs(charts), 0u);
}

// Two planes meeting at a 30-degree fold (below the hard-edge angle) are one developable chart:
// LSCM unfolds it exactly.
TEST(UvCharts, ShallowFoldUnfoldsWithoutStretch) {
  Primitive p;
  float c = std::cos(kPi / 6.0f), s = std::sin(kPi / 6.0f);
  addGrid(p, {0, 0, 0}, {2, 0, 0}, {0, 0, -1}, 4, 2);
  addGrid(p, {0, 0, -1}, {2, 0, 0}, {0, s, -c}, 4, 2);
  Mesh mesh = single(p);
  MeshCharts charts = computeCharts(mesh);
  ASSERT_EQ(charts.charts.size(), 1u);
  EXPECT_FALSE(charts.charts[0].planar);
  Quality q = check(mesh, charts);
  EXPECT_EQ(q.flipped, 0u);
  EXPECT_NEAR(q.stretch, 1.0, 1e-4);
  EXPECT_EQ(overlappingPairs(charts), 0u);
}

// A flat square whose halves carry vertex normals 50 degrees apart (a hard shading edge) is cut
// there; 30 degrees apart (below shadingSeamAngleDeg) stays one chart.
TEST(UvCharts, HardShadingEdgesCut) {
  for (float degrees : {50.0f, 30.0f}) {
    Primitive p;
    addGrid(p, {0, 0, 0}, {1, 0, 0}, {0, 0, -1}, 2, 2);
    addGrid(p, {1, 0, 0}, {1, 0, 0}, {0, 0, -1}, 2, 2);
    float a = degrees * kPi / 180.0f;
    for (size_t v = 9; v < 18; ++v) p.normals[v] = {std::sin(a), std::cos(a), 0.0f};
    Mesh mesh = single(p);
    MeshCharts charts = computeCharts(mesh);
    EXPECT_EQ(charts.charts.size(), degrees > 45.0f ? 2u : 1u) << degrees << " degrees";
    Quality q = check(mesh, charts);
    EXPECT_EQ(q.flipped, 0u);
  }
}

// A sphere is not developable: charts must stay small enough that conformal maps keep the area
// distortion low; the bound is what a 40-degree cone allows (1/cos of the cone, roughly).
TEST(UvCharts, SphereHasNoFlipsAndLowStretch) {
  Mesh mesh = single(sphere(32, 16));
  MeshCharts charts = computeCharts(mesh);
  Quality q = check(mesh, charts);
  std::printf("sphere: %zu charts, L2 stretch %.4f (max %.4f)\n", charts.charts.size(), q.stretch,
              q.maxStretch);
  EXPECT_EQ(q.flipped, 0u);
  EXPECT_LE(q.stretch, 1.1);
  EXPECT_GE(charts.charts.size(), 2u);   // a closed surface needs cutting
  EXPECT_LE(charts.charts.size(), 40u);  // but not into slivers
  EXPECT_EQ(overlappingPairs(charts), 0u);
}

// Broken input: a zero-area triangle (repeated vertex), a collinear sliver, a duplicated face,
// and an edge shared by three triangles.
TEST(UvCharts, BrokenFacesAreChartedSafely) {
  Primitive p;
  addGrid(p, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 2, 2);  // vertices 0..8, z = 0
  const uint32_t fin = uint32_t(p.positions.size());
  // A fin standing on the grid's edge between vertices 4 and 5 (centre, middle right): that edge
  // now has three triangles.
  p.positions.push_back({0.75f, 0.5f, 0.5f});
  p.normals.push_back({0, -1, 0});
  for (uint32_t k : {4u, 5u, fin}) p.indices.push_back(k);
  // Zero-area triangles: a repeated vertex and three collinear vertices along the grid edge.
  for (uint32_t k : {0u, 1u, 1u}) p.indices.push_back(k);
  for (uint32_t k : {0u, 1u, 2u}) p.indices.push_back(k);
  // A duplicate of the first grid triangle.
  for (int k = 0; k < 3; ++k) p.indices.push_back(p.indices[k]);
  // A zero-area triangle on its own, away from everything.
  uint32_t lone = uint32_t(p.positions.size());
  for (int k = 0; k < 3; ++k) {
    p.positions.push_back({5.0f + k, 5.0f, 5.0f});
    p.normals.push_back({0, 0, 1});
  }
  for (uint32_t k : {lone, lone + 1, lone + 2}) p.indices.push_back(k);
  Mesh mesh = single(p);
  MeshCharts charts = computeCharts(mesh);
  Quality q = check(mesh, charts);
  EXPECT_EQ(q.flipped, 0u);
  EXPECT_LE(q.stretch, 1.0 + 1e-6);
  // Grid, fin, duplicate, lone degenerate: the degenerate ones on the grid join the grid chart.
  EXPECT_EQ(charts.charts.size(), 4u);
  size_t total = 0;
  for (const Chart& chart : charts.charts) total += chart.triangles.size();
  EXPECT_EQ(total, p.triangleCount());
  EXPECT_EQ(overlappingPairs(charts), 0u);
}

// Triangle soup over a few vertices of a bumpy sheet: every edge is likely non-manifold, with
// duplicates, reversed duplicates and repeated-vertex triangles mixed in. Whatever the charts,
// the invariants hold: one chart per triangle, no flips, finite UVs, area2d == area3d.
TEST(UvCharts, TriangleSoupKeepsTheInvariants) {
  Primitive p;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 6; ++i) {
      p.positions.push_back({float(i), 0.3f * std::sin(float(i * j)), float(j)});
      p.normals.push_back({0, 1, 0});
    }
  uint32_t state = 12345u;
  auto next = [&]() {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) % 36u;
  };
  for (int t = 0; t < 300; ++t)
    for (int k = 0; k < 3; ++k) p.indices.push_back(next());
  Mesh mesh = single(p);
  MeshCharts charts = computeCharts(mesh);
  Quality q = check(mesh, charts, /*flatDegenerates=*/false);
  EXPECT_EQ(q.flipped, 0u);
  EXPECT_LE(q.stretch, 1.1);
}

TEST(UvCharts, Deterministic) {
  Mesh mesh;
  mesh.primitives = {sphere(24, 12), cylinder(20, 3), cube()};
  MeshCharts a = computeCharts(mesh), b = computeCharts(mesh);
  ASSERT_EQ(a.charts.size(), b.charts.size());
  for (size_t c = 0; c < a.charts.size(); ++c) EXPECT_EQ(a.charts[c].triangles, b.charts[c].triangles);
  for (size_t p = 0; p < a.primitives.size(); ++p) {
    EXPECT_EQ(a.primitives[p].vertexRemap, b.primitives[p].vertexRemap);
    EXPECT_EQ(a.primitives[p].indices, b.primitives[p].indices);
    ASSERT_EQ(a.primitives[p].chartUv.size(), b.primitives[p].chartUv.size());
    EXPECT_EQ(0, std::memcmp(a.primitives[p].chartUv.data(), b.primitives[p].chartUv.data(),
                             a.primitives[p].chartUv.size() * sizeof(glm::vec2)));
  }
}

// xatlas cuts Sponza's 262k instanced triangles into 10,192 charts; we want fewer, with low
// stretch and no flips.
TEST(UvCharts, SponzaFewerChartsThanXatlas) {
  AG_REQUIRE_SHARED_SCENE(path, "sponza/Sponza.gltf");
  scenes::LoadOptions options;
  options.loadTextures = false;
  auto scene = scenes::loadGltf(path, options);
  ASSERT_TRUE(scene.isOk()) << scene.message();
  std::vector<size_t> instancesOf(scene->meshes.size(), 0);
  for (const auto& instance : scene->instances) ++instancesOf[instance.mesh];
  size_t instancedCharts = 0, charts = 0, flipped = 0;
  double stretchSum = 0.0, area = 0.0;
  auto start = std::chrono::steady_clock::now();
  std::clock_t cpuStart = std::clock();
  std::vector<MeshCharts> results;
  for (const auto& mesh : scene->meshes) results.push_back(computeCharts(mesh));
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  double cpuSeconds = double(std::clock() - cpuStart) / CLOCKS_PER_SEC;
  for (size_t m = 0; m < scene->meshes.size(); ++m) {
    Quality q = check(scene->meshes[m], results[m]);
    charts += results[m].charts.size();
    instancedCharts += results[m].charts.size() * instancesOf[m];
    flipped += q.flipped;
    stretchSum += q.stretch * q.stretch * q.area3d;
    area += q.area3d;
  }
  double stretch = std::sqrt(stretchSum / area);
  std::printf("Sponza: %zu meshes, %zu charts (%zu over instances), L2 stretch %.4f, %zu flipped, "
              "charting %.3f s single-threaded (%.3f s CPU)\n",
              scene->meshes.size(), charts, instancedCharts, stretch, flipped, seconds, cpuSeconds);
  EXPECT_LT(instancedCharts, 10192u);
  EXPECT_LE(stretch, 1.05);
  EXPECT_EQ(flipped, 0u);
}

}  // namespace
}  // namespace afterglow::uv
