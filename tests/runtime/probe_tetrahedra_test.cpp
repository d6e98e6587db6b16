// The light probes' point location and mesh check on a hand-made mesh: two tetrahedra sharing
// the triangle A B C in the plane z = 0, one with apex D above it, one with apex E below (a
// convex bipyramid: the segment DE crosses the shared triangle).
#include <gtest/gtest.h>

#include <map>

#include "afterglow/runtime/probe_tetrahedra.h"

namespace afterglow::runtime {
namespace {

enum { A, B, C, D, E };

ProbeTetrahedra bipyramid() {
  ProbeTetrahedra m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25f, 0.25f, 1}, {0.25f, 0.25f, -1}};
  m.tetrahedra = {{A, B, C, D}, {A, C, B, E}};
  m.neighbours = {{-1, -1, -1, 1}, {-1, -1, -1, 0}};
  return m;
}

// Weight per probe (probes -1 skipped), so that locations in different tetrahedra compare.
std::map<int, float> weightsByProbe(const ProbeLocation& loc) {
  std::map<int, float> w;
  for (int i = 0; i < 4; ++i)
    if (loc.probes[i] >= 0) w[loc.probes[i]] += loc.weights[i];
  return w;
}

float weight(const ProbeLocation& loc, int probe) {
  const std::map<int, float> w = weightsByProbe(loc);
  const auto it = w.find(probe);
  return it == w.end() ? 0.0f : it->second;
}

glm::vec3 interpolated(const ProbeTetrahedra& m, const ProbeLocation& loc) {
  glm::vec3 q(0.0f);
  for (int i = 0; i < 4; ++i)
    if (loc.probes[i] >= 0) q += loc.weights[i] * m.positions[size_t(loc.probes[i])];
  return q;
}

void expectNormalised(const ProbeLocation& loc) {
  float sum = 0.0f;
  for (int i = 0; i < 4; ++i) {
    EXPECT_GE(loc.weights[i], 0.0f);
    if (loc.probes[i] < 0) {
      EXPECT_EQ(loc.weights[i], 0.0f);
    }
    sum += loc.weights[i];
  }
  EXPECT_NEAR(sum, 1.0f, 1e-6f);
}

TEST(ProbeTetrahedra, TheHandMadeMeshIsValid) {
  EXPECT_EQ(checkProbeTetrahedra(bipyramid()), "");
}

TEST(ProbeTetrahedra, LocatesPointsInsideEachTetrahedronFromEitherHint) {
  const ProbeTetrahedra m = bipyramid();
  const glm::vec3 above = (m.positions[A] + m.positions[B] + m.positions[C] + m.positions[D]) / 4.0f;
  const glm::vec3 below = glm::vec3(0.2f, 0.3f, -0.3f);
  for (int hint : {0, 1, -5, 99}) {
    const ProbeLocation up = locateProbe(m, above, hint);
    EXPECT_EQ(up.tetrahedron, 0) << "hint " << hint;
    EXPECT_TRUE(up.inside);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(up.weights[i], 0.25f, 1e-6f);
    expectNormalised(up);
    const ProbeLocation down = locateProbe(m, below, hint);
    EXPECT_EQ(down.tetrahedron, 1) << "hint " << hint;
    EXPECT_TRUE(down.inside);
    expectNormalised(down);
    const glm::vec3 q = interpolated(m, down);
    EXPECT_NEAR(q.x, below.x, 1e-6f);
    EXPECT_NEAR(q.y, below.y, 1e-6f);
    EXPECT_NEAR(q.z, below.z, 1e-6f);
    EXPECT_GT(weight(down, E), 0.0f);
    EXPECT_EQ(weight(down, D), 0.0f);
  }
}

TEST(ProbeTetrahedra, WeightsAreContinuousAcrossTheSharedFace) {
  const ProbeTetrahedra m = bipyramid();
  const glm::vec3 onFace(0.2f, 0.3f, 0.0f);
  const ProbeLocation from0 = locateProbe(m, onFace, 0);
  const ProbeLocation from1 = locateProbe(m, onFace, 1);
  EXPECT_TRUE(from0.inside);
  EXPECT_TRUE(from1.inside);
  // On the face both apexes have weight 0, and the face's probes the same weights.
  for (int probe : {A, B, C, D, E}) EXPECT_NEAR(weight(from0, probe), weight(from1, probe), 1e-6f);
  EXPECT_NEAR(weight(from0, D), 0.0f, 1e-6f);
  EXPECT_NEAR(weight(from0, E), 0.0f, 1e-6f);
  EXPECT_NEAR(weight(from0, B), 0.2f, 1e-6f);
  EXPECT_NEAR(weight(from0, C), 0.3f, 1e-6f);
  // Just above and just below: the two tetrahedra, weights within the step's size.
  const ProbeLocation up = locateProbe(m, onFace + glm::vec3(0, 0, 1e-4f), 1);
  const ProbeLocation down = locateProbe(m, onFace - glm::vec3(0, 0, 1e-4f), 0);
  EXPECT_EQ(up.tetrahedron, 0);
  EXPECT_EQ(down.tetrahedron, 1);
  for (int probe : {A, B, C, D, E}) EXPECT_NEAR(weight(up, probe), weight(down, probe), 1e-3f);
}

TEST(ProbeTetrahedra, APointOutsideProjectsOntoTheNearestHullFace) {
  const ProbeTetrahedra m = bipyramid();
  // Beyond the face A B D (outward normal (0, -1, 0.25)), half a metre off its centroid.
  const glm::vec3 centroid = (m.positions[A] + m.positions[B] + m.positions[D]) / 3.0f;
  const glm::vec3 p = centroid + 0.5f * glm::normalize(glm::vec3(0, -1, 0.25f));
  for (int hint : {0, 1}) {
    const ProbeLocation loc = locateProbe(m, p, hint);
    EXPECT_FALSE(loc.inside);
    EXPECT_EQ(loc.tetrahedron, 0);
    expectNormalised(loc);
    EXPECT_EQ(loc.probes[3], -1);
    EXPECT_NEAR(weight(loc, A), 1.0f / 3.0f, 1e-5f);
    EXPECT_NEAR(weight(loc, B), 1.0f / 3.0f, 1e-5f);
    EXPECT_NEAR(weight(loc, D), 1.0f / 3.0f, 1e-5f);
    const glm::vec3 q = interpolated(m, loc);
    EXPECT_NEAR(glm::distance(q, centroid), 0.0f, 1e-5f);
  }
  // Straight above the apex D, in the cone of its faces' normals: clamped to D alone.
  const ProbeLocation apex = locateProbe(m, m.positions[D] + glm::vec3(0, 0, 3), 1);
  EXPECT_FALSE(apex.inside);
  expectNormalised(apex);
  EXPECT_NEAR(weight(apex, D), 1.0f, 1e-6f);
  // Off the face B C E along its normal (1, 1, -0.5), from its centroid: the walk from
  // tetrahedron 0 leaves at once through its hull face B C D (A's coordinate there, -1.42, is
  // more negative than D's, -0.83), but the nearest point is B C E's centroid, in tetrahedron 1.
  const glm::vec3 centroidBCE = (m.positions[B] + m.positions[C] + m.positions[E]) / 3.0f;
  const glm::vec3 far = centroidBCE + glm::vec3(1.0f, 1.0f, -0.5f);
  const ProbeLocation loc = locateProbe(m, far, 0);
  EXPECT_FALSE(loc.inside);
  EXPECT_EQ(loc.tetrahedron, 1);
  for (int probe : {B, C, E}) EXPECT_NEAR(weight(loc, probe), 1.0f / 3.0f, 1e-5f);
  expectNormalised(loc);
  const glm::vec3 q = interpolated(m, loc);
  // The closest point of the hull: no probe nor sampled hull point is nearer.
  const float nearest = glm::distance(q, far);
  for (const glm::vec3& probe : m.positions) EXPECT_LE(nearest, glm::distance(probe, far) + 1e-5f);
  for (float s = 0.0f; s <= 1.0f; s += 0.01f)
    for (int apexProbe : {D, E}) {
      const glm::vec3 onEdge = glm::mix(m.positions[B], m.positions[C], s);
      for (float t = 0.0f; t <= 1.0f; t += 0.05f) {
        const glm::vec3 h = glm::mix(onEdge, m.positions[size_t(apexProbe)], t);
        EXPECT_LE(nearest, glm::distance(h, far) + 1e-5f);
      }
    }
  EXPECT_GT(weight(loc, E), 0.0f);
}

TEST(ProbeTetrahedra, SamplingAtAProbeGivesThatProbe) {
  const ProbeTetrahedra m = bipyramid();
  for (int probe : {A, B, C, D, E})
    for (int hint : {0, 1}) {
      const ProbeLocation loc = locateProbe(m, m.positions[size_t(probe)], hint);
      EXPECT_NEAR(weight(loc, probe), 1.0f, 1e-6f) << "probe " << probe << " hint " << hint;
      expectNormalised(loc);
    }
}

TEST(ProbeTetrahedra, WithoutTetrahedraTheNearestProbeTakesAll) {
  ProbeTetrahedra m;
  ProbeLocation empty = locateProbe(m, glm::vec3(1.0f));
  EXPECT_EQ(empty.tetrahedron, -1);
  EXPECT_EQ(empty.probes, glm::ivec4(-1));
  m.positions = {{0, 0, 0}, {5, 0, 0}, {0, 5, 0}};
  const ProbeLocation loc = locateProbe(m, glm::vec3(4, 1, 7));
  EXPECT_EQ(loc.tetrahedron, -1);
  EXPECT_FALSE(loc.inside);
  EXPECT_EQ(loc.probes, glm::ivec4(1, -1, -1, -1));
  EXPECT_EQ(loc.weights, glm::vec4(1, 0, 0, 0));
  EXPECT_EQ(checkProbeTetrahedra(m), "");
}

TEST(ProbeTetrahedra, TheCheckCatchesAFlippedTetrahedron) {
  ProbeTetrahedra m = bipyramid();
  std::swap(m.tetrahedra[1][1], m.tetrahedra[1][2]);
  const std::string message = checkProbeTetrahedra(m);
  EXPECT_NE(message.find("tetrahedron 1"), std::string::npos) << message;
  EXPECT_NE(message.find("negative volume"), std::string::npos) << message;
  // A flat one (E moved into the plane z = 0) has no volume.
  m = bipyramid();
  m.positions[E] = glm::vec3(0.5f, 0.5f, 0.0f);
  EXPECT_NE(checkProbeTetrahedra(m).find("tetrahedron 1: zero volume"), std::string::npos);
}

TEST(ProbeTetrahedra, TheCheckCatchesABadIndex) {
  ProbeTetrahedra m = bipyramid();
  m.tetrahedra[0][2] = 7;
  const std::string message = checkProbeTetrahedra(m);
  EXPECT_NE(message.find("tetrahedron 0: corner 2 is probe 7, out of range"), std::string::npos)
      << message;
  m = bipyramid();
  m.neighbours[1][0] = 2;
  EXPECT_NE(checkProbeTetrahedra(m).find("tetrahedron 1: neighbour 2"), std::string::npos);
}

TEST(ProbeTetrahedra, TheCheckCatchesANonMutualNeighbour) {
  ProbeTetrahedra m = bipyramid();
  m.neighbours[1][3] = -1;
  const std::string message = checkProbeTetrahedra(m);
  EXPECT_NE(message.find("tetrahedron 0"), std::string::npos) << message;
  EXPECT_NE(message.find("does not have it as a neighbour"), std::string::npos) << message;
  // Mutual, but across faces that are not the shared one.
  m = bipyramid();
  m.neighbours = {{1, -1, -1, -1}, {0, -1, -1, -1}};
  EXPECT_NE(checkProbeTetrahedra(m).find("does not share that face"), std::string::npos);
}

}  // namespace
}  // namespace afterglow::runtime
