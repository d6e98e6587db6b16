// The light probes' Delaunay tetrahedralisation (CGAL) and point location on it: the Delaunay
// property, the hull's volume, determinism, barycentric interpolation inside the hull and
// continuity across it.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <vector>

#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "runtime/test_rng.h"

namespace afterglow::probes {
namespace {

using runtime::ProbeLocation;
using runtime::ProbeTetrahedra;
using runtime::locateProbe;
using runtime::test::Rng;

constexpr float kCube = 10.0f;  // metres

glm::vec3 randomIn(Rng& rng, glm::vec3 lo, glm::vec3 hi) {
  return lo + (hi - lo) * glm::vec3(rng.unit(), rng.unit(), rng.unit());
}

std::vector<glm::vec3> randomPoints(uint64_t seed, int n, glm::vec3 lo, glm::vec3 hi) {
  Rng rng{seed};
  std::vector<glm::vec3> p;
  for (int i = 0; i < n; ++i) p.push_back(randomIn(rng, lo, hi));
  return p;
}

// A jittered 5 x 5 x 5 grid strictly inside the cube [0, 10]^3 and the cube's eight corners, so
// the convex hull is the cube.
std::vector<glm::vec3> jitteredCube(uint64_t seed) {
  Rng rng{seed};
  std::vector<glm::vec3> p;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 5; ++k)
        p.push_back(2.0f * glm::vec3(i + 0.5f, j + 0.5f, k + 0.5f) +
                    randomIn(rng, glm::vec3(-0.45f), glm::vec3(0.45f)));
  for (int c = 0; c < 8; ++c)
    p.push_back(kCube * glm::vec3(float(c & 1), float((c >> 1) & 1), float((c >> 2) & 1)));
  return p;
}

double volume(const ProbeTetrahedra& m, size_t t) {
  const glm::ivec4 v = m.tetrahedra[t];
  const glm::dvec3 a(m.positions[size_t(v[0])]), b(m.positions[size_t(v[1])]),
      c(m.positions[size_t(v[2])]), d(m.positions[size_t(v[3])]);
  return glm::dot(b - a, glm::cross(c - a, d - a)) / 6.0;
}

double totalVolume(const ProbeTetrahedra& m) {
  double sum = 0.0;
  for (size_t t = 0; t < m.tetrahedra.size(); ++t) sum += volume(m, t);
  return sum;
}

std::map<int, double> weightsByProbe(const ProbeLocation& loc) {
  std::map<int, double> w;
  for (int i = 0; i < 4; ++i)
    if (loc.probes[i] >= 0) w[loc.probes[i]] += double(loc.weights[i]);
  return w;
}

// Σ |w_a − w_b| over the probes of either location.
double weightDistance(const ProbeLocation& a, const ProbeLocation& b) {
  std::map<int, double> wa = weightsByProbe(a), wb = weightsByProbe(b);
  double d = 0.0;
  for (const auto& [probe, w] : wa) d += std::abs(w - (wb.count(probe) ? wb[probe] : 0.0));
  for (const auto& [probe, w] : wb)
    if (!wa.count(probe)) d += w;
  return d;
}

glm::dvec3 interpolated(const ProbeTetrahedra& m, const ProbeLocation& loc) {
  glm::dvec3 q(0.0);
  for (int i = 0; i < 4; ++i)
    if (loc.probes[i] >= 0) q += double(loc.weights[i]) * glm::dvec3(m.positions[size_t(loc.probes[i])]);
  return q;
}

void expectNormalised(const ProbeLocation& loc) {
  float sum = 0.0f;
  for (int i = 0; i < 4; ++i) {
    EXPECT_GE(loc.weights[i], 0.0f);
    sum += loc.weights[i];
  }
  EXPECT_NEAR(sum, 1.0f, 1e-5f);
}

// The brute-force answer: the weights in the tetrahedron whose smallest barycentric coordinate
// is the largest (computed here independently of the runtime).
std::map<int, double> bruteForceWeights(const ProbeTetrahedra& m, glm::vec3 pf) {
  const glm::dvec3 p(pf);
  double bestMin = -std::numeric_limits<double>::infinity();
  std::map<int, double> best;
  for (size_t t = 0; t < m.tetrahedra.size(); ++t) {
    const glm::ivec4 v = m.tetrahedra[t];
    std::array<glm::dvec3, 4> c;
    for (int i = 0; i < 4; ++i) c[size_t(i)] = glm::dvec3(m.positions[size_t(v[i])]);
    // Solve p = c0 + T (b1, b2, b3) with T's columns the edges from c0.
    const glm::dmat3 T(c[1] - c[0], c[2] - c[0], c[3] - c[0]);
    const glm::dvec3 b = glm::inverse(T) * (p - c[0]);
    const std::array<double, 4> bary = {1.0 - b.x - b.y - b.z, b.x, b.y, b.z};
    const double lowest = *std::min_element(bary.begin(), bary.end());
    if (lowest > bestMin) {
      bestMin = lowest;
      best.clear();
      for (int i = 0; i < 4; ++i) best[v[i]] += bary[size_t(i)];
    }
  }
  EXPECT_GE(bestMin, -1e-6) << "the brute-force search found no tetrahedron holding the point";
  return best;
}

ProbeTetrahedra tetrahedralizeOrDie(const std::vector<glm::vec3>& p) {
  Result<ProbeTetrahedra> r = tetrahedralize(p);
  EXPECT_TRUE(r.isOk()) << r.message();
  return r.isOk() ? *r : ProbeTetrahedra();
}

TEST(ProbeTetrahedralize, RandomPointsAreDelaunayAndValid) {
  const std::vector<glm::vec3> p = randomPoints(7, 300, glm::vec3(0), glm::vec3(4, 3, 2));
  const ProbeTetrahedra m = tetrahedralizeOrDie(p);
  ASSERT_GT(m.tetrahedra.size(), 300u);
  EXPECT_EQ(runtime::checkProbeTetrahedra(m), "");
  EXPECT_EQ(m.positions, p);
  // No probe strictly inside any tetrahedron's circumsphere (relative tolerance 1e-6 on r²).
  int violations = 0;
  for (size_t t = 0; t < m.tetrahedra.size(); ++t) {
    const glm::ivec4 v = m.tetrahedra[t];
    const glm::dvec3 a(p[size_t(v[0])]);
    const glm::dvec3 u = glm::dvec3(p[size_t(v[1])]) - a, w = glm::dvec3(p[size_t(v[2])]) - a,
                     s = glm::dvec3(p[size_t(v[3])]) - a;
    const glm::dvec3 offset = (glm::dot(u, u) * glm::cross(w, s) + glm::dot(w, w) * glm::cross(s, u) +
                               glm::dot(s, s) * glm::cross(u, w)) /
                              (2.0 * glm::dot(u, glm::cross(w, s)));
    const glm::dvec3 centre = a + offset;
    const double r2 = glm::dot(offset, offset);
    for (size_t i = 0; i < p.size(); ++i) {
      if (int(i) == v[0] || int(i) == v[1] || int(i) == v[2] || int(i) == v[3]) continue;
      const glm::dvec3 d = glm::dvec3(p[i]) - centre;
      if (glm::dot(d, d) < r2 * (1.0 - 1e-6) && ++violations <= 5)
        ADD_FAILURE() << "probe " << i << " inside tetrahedron " << t << "'s circumsphere";
    }
  }
  EXPECT_EQ(violations, 0);
  // Every interior face has its neighbour, and the hull faces form a closed surface: each
  // hull edge is shared by exactly two hull faces.
  std::map<std::pair<int, int>, int> hullEdges;
  for (size_t t = 0; t < m.tetrahedra.size(); ++t)
    for (int i = 0; i < 4; ++i) {
      if (m.neighbours[t][i] != -1) continue;
      std::vector<int> f;
      for (int j = 0; j < 4; ++j)
        if (j != i) f.push_back(m.tetrahedra[t][j]);
      for (int j = 0; j < 3; ++j)
        ++hullEdges[{std::min(f[size_t(j)], f[size_t((j + 1) % 3)]),
                     std::max(f[size_t(j)], f[size_t((j + 1) % 3)])}];
    }
  ASSERT_FALSE(hullEdges.empty());
  for (const auto& [edge, count] : hullEdges) EXPECT_EQ(count, 2);
}

TEST(ProbeTetrahedralize, VolumesSumToTheHull) {
  const ProbeTetrahedra m = tetrahedralizeOrDie(jitteredCube(3));
  EXPECT_EQ(runtime::checkProbeTetrahedra(m), "");
  for (size_t t = 0; t < m.tetrahedra.size(); ++t) EXPECT_GT(volume(m, t), 0.0);
  EXPECT_NEAR(totalVolume(m), double(kCube * kCube * kCube), 1e-6);
}

TEST(ProbeTetrahedralize, IsDeterministicAndCanonical) {
  const std::vector<glm::vec3> p = jitteredCube(11);
  const ProbeTetrahedra a = tetrahedralizeOrDie(p), b = tetrahedralizeOrDie(p);
  EXPECT_EQ(a.tetrahedra, b.tetrahedra);
  EXPECT_EQ(a.neighbours, b.neighbours);
  EXPECT_TRUE(std::is_sorted(a.tetrahedra.begin(), a.tetrahedra.end(),
                             [](glm::ivec4 x, glm::ivec4 y) {
                               std::array<int, 4> sx{x[0], x[1], x[2], x[3]}, sy{y[0], y[1], y[2], y[3]};
                               std::sort(sx.begin(), sx.end());
                               std::sort(sy.begin(), sy.end());
                               return sx < sy;
                             }));
  // A regular grid (every cube's eight corners cospherical) in reversed order gives the same
  // tetrahedra: CGAL's symbolic perturbation depends on the points, not the insertion order.
  std::vector<glm::vec3> grid;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) grid.push_back(glm::vec3(float(i), float(j), float(k)));
  std::vector<glm::vec3> reversed(grid.rbegin(), grid.rend());
  const ProbeTetrahedra g = tetrahedralizeOrDie(grid), r = tetrahedralizeOrDie(reversed);
  EXPECT_EQ(runtime::checkProbeTetrahedra(g), "");
  EXPECT_NEAR(totalVolume(g), 27.0, 1e-9);
  const int n = int(grid.size());
  std::set<std::array<int, 4>> fromGrid, fromReversed;
  for (glm::ivec4 t : g.tetrahedra) {
    std::array<int, 4> s{t[0], t[1], t[2], t[3]};
    std::sort(s.begin(), s.end());
    fromGrid.insert(s);
  }
  for (glm::ivec4 t : r.tetrahedra) {
    std::array<int, 4> s{n - 1 - t[0], n - 1 - t[1], n - 1 - t[2], n - 1 - t[3]};
    std::sort(s.begin(), s.end());
    fromReversed.insert(s);
  }
  EXPECT_EQ(fromGrid, fromReversed);
}

TEST(ProbeTetrahedralize, LocatesInsidePointsBarycentrically) {
  const ProbeTetrahedra m = tetrahedralizeOrDie(jitteredCube(5));
  Rng rng{42};
  const glm::vec3 a(0.3f, -1.2f, 0.7f);
  const float b = 2.0f;
  int hint = 0;
  for (int q = 0; q < 300; ++q) {
    const glm::vec3 p = randomIn(rng, glm::vec3(0.01f), glm::vec3(kCube - 0.01f));
    const ProbeLocation loc = locateProbe(m, p, q % 3 == 0 ? int(rng.below(1000)) : hint);
    hint = loc.tetrahedron;
    ASSERT_GE(loc.tetrahedron, 0);
    EXPECT_TRUE(loc.inside);
    expectNormalised(loc);
    const glm::dvec3 back = interpolated(m, loc);
    EXPECT_NEAR(back.x, p.x, 1e-4);
    EXPECT_NEAR(back.y, p.y, 1e-4);
    EXPECT_NEAR(back.z, p.z, 1e-4);
    // The same weights as a brute-force search.
    const std::map<int, double> expected = bruteForceWeights(m, p);
    const std::map<int, double> got = weightsByProbe(loc);
    for (const auto& [probe, w] : expected)
      EXPECT_NEAR(got.count(probe) ? got.at(probe) : 0.0, w, 1e-4) << "probe " << probe;
    // A linear function is interpolated exactly.
    double f = 0.0;
    for (int i = 0; i < 4; ++i)
      f += double(loc.weights[i]) * double(glm::dot(a, m.positions[size_t(loc.probes[i])]) + b);
    EXPECT_NEAR(f, double(glm::dot(a, p) + b), 1e-4);
  }
  // At a probe: that probe, weight 1.
  for (size_t i = 0; i < m.positions.size(); i += 7) {
    const ProbeLocation loc = locateProbe(m, m.positions[i], int(i));
    EXPECT_NEAR(weightsByProbe(loc)[int(i)], 1.0, 1e-5);
  }
}

TEST(ProbeTetrahedralize, OutsidePointsProjectOntoTheHullContinuously) {
  const ProbeTetrahedra m = tetrahedralizeOrDie(jitteredCube(9));
  Rng rng{99};
  int outside = 0;
  for (int q = 0; q < 200; ++q) {
    const glm::vec3 p = randomIn(rng, glm::vec3(-5.0f), glm::vec3(kCube + 5.0f));
    const ProbeLocation loc = locateProbe(m, p, int(rng.below(500)));
    expectNormalised(loc);
    const glm::vec3 nearest = glm::clamp(p, glm::vec3(0.0f), glm::vec3(kCube));
    if (nearest == p) continue;
    ++outside;
    EXPECT_FALSE(loc.inside);
    // The hull is the cube: the interpolated point is the closest point of the cube.
    const glm::dvec3 back = interpolated(m, loc);
    EXPECT_NEAR(back.x, nearest.x, 1e-4);
    EXPECT_NEAR(back.y, nearest.y, 1e-4);
    EXPECT_NEAR(back.z, nearest.z, 1e-4);
  }
  EXPECT_GT(outside, 100);
  // 1 mm across each of the cube's six faces: the weights move by little (the probes are ~2 m
  // apart, so a weight's gradient is about 1 per 2 m: 1e-3 per millimetre and corner).
  double worst = 0.0;
  for (int q = 0; q < 120; ++q) {
    const int axis = q % 3;
    const bool high = (q / 3) % 2 == 1;
    glm::vec3 onFace = randomIn(rng, glm::vec3(0.05f), glm::vec3(kCube - 0.05f));
    onFace[axis] = high ? kCube : 0.0f;
    glm::vec3 step(0.0f);
    step[axis] = high ? 0.0005f : -0.0005f;
    const ProbeLocation in = locateProbe(m, onFace - step), out = locateProbe(m, onFace + step);
    EXPECT_TRUE(in.inside);
    EXPECT_FALSE(out.inside);
    expectNormalised(out);
    worst = std::max(worst, weightDistance(in, out));
  }
  EXPECT_LT(worst, 0.01);
  // Far outside a hull face, the walk may leave through another face: still the nearest one.
  const ProbeLocation far = locateProbe(m, glm::vec3(5.0f, 5.0f, -1000.0f), 0);
  const glm::dvec3 back = interpolated(m, far);
  EXPECT_NEAR(back.z, 0.0, 1e-4);
  EXPECT_NEAR(back.x, 5.0, 1e-4);
  EXPECT_NEAR(back.y, 5.0, 1e-4);
}

TEST(ProbeTetrahedralize, RejectsNonFiniteAndDuplicatePositions) {
  std::vector<glm::vec3> p = randomPoints(1, 10, glm::vec3(0), glm::vec3(1));
  p[6].y = std::numeric_limits<float>::quiet_NaN();
  Result<ProbeTetrahedra> r = tetrahedralize(p);
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.message().find("probe 6"), std::string::npos) << r.message();
  EXPECT_NE(r.message().find("not finite"), std::string::npos) << r.message();
  p[6].y = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(tetrahedralize(p).isOk());

  p = randomPoints(1, 10, glm::vec3(0), glm::vec3(1));
  p[8] = p[3];
  r = tetrahedralize(p);
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.message().find("probes 3 and 8"), std::string::npos) << r.message();
  // Also while the points span no volume yet.
  r = tetrahedralize({glm::vec3(1, 2, 3), glm::vec3(1, 2, 3)});
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.message().find("probes 0 and 1"), std::string::npos) << r.message();
}

TEST(ProbeTetrahedralize, FewOrCoplanarProbesGiveNoTetrahedra) {
  const std::vector<glm::vec3> three = {{0, 0, 0}, {2, 0, 0}, {0, 0, 5}};
  const ProbeTetrahedra m = tetrahedralizeOrDie(three);
  EXPECT_TRUE(m.tetrahedra.empty());
  EXPECT_EQ(m.positions, three);
  const ProbeLocation loc = locateProbe(m, glm::vec3(0.5f, 3.0f, 4.0f));
  EXPECT_EQ(loc.tetrahedron, -1);
  EXPECT_EQ(loc.probes, glm::ivec4(2, -1, -1, -1));
  EXPECT_EQ(loc.weights, glm::vec4(1, 0, 0, 0));

  std::vector<glm::vec3> flat = randomPoints(4, 50, glm::vec3(0), glm::vec3(3, 3, 0));
  EXPECT_TRUE(tetrahedralizeOrDie(flat).tetrahedra.empty());
  EXPECT_TRUE(tetrahedralizeOrDie({}).positions.empty());
  EXPECT_EQ(locateProbe(tetrahedralizeOrDie({}), glm::vec3(0)).tetrahedron, -1);
  // One more probe off the plane: now there is volume.
  flat.push_back(glm::vec3(1, 1, 1));
  const ProbeTetrahedra lifted = tetrahedralizeOrDie(flat);
  EXPECT_FALSE(lifted.tetrahedra.empty());
  EXPECT_EQ(runtime::checkProbeTetrahedra(lifted), "");
}

// Timings, not assertions: run with --gtest_also_run_disabled_tests
// --gtest_filter=*TetrahedralizeTiming*.
TEST(ProbeTetrahedralize, DISABLED_TetrahedralizeTiming) {
  for (int n : {10000, 100000}) {
    const std::vector<glm::vec3> p = randomPoints(uint64_t(n), n, glm::vec3(0), glm::vec3(50, 20, 10));
    const auto start = std::chrono::steady_clock::now();
    const ProbeTetrahedra m = tetrahedralizeOrDie(p);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    Rng rng{1};
    const auto locateStart = std::chrono::steady_clock::now();
    int hint = 0;
    for (int q = 0; q < 100000; ++q)
      hint = locateProbe(m, randomIn(rng, glm::vec3(0), glm::vec3(50, 20, 10)), hint).tetrahedron;
    const double locateSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - locateStart).count();
    std::printf("tetrahedralize %d random points: %.3f s, %zu tetrahedra; 100000 locates "
                "(hint: the previous): %.3f s\n",
                n, seconds, m.tetrahedra.size(), locateSeconds);
    EXPECT_EQ(runtime::checkProbeTetrahedra(m), "");
  }
}

}  // namespace
}  // namespace afterglow::probes
