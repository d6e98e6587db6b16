// Light probes' visibility (probe_visibility.h): the octahedral map's texels, a probe's map of
// a wall, and interpolation weights that drop the probes a point is hidden from.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "afterglow/core/math.h"
#include "afterglow/runtime/probe_visibility.h"
#include "test_rng.h"

namespace afterglow::runtime {
namespace {


// 4,096 directions spread over the sphere (a Fibonacci spiral) as a probe's rays.
std::vector<glm::vec3> rays(size_t n) {
  std::vector<glm::vec3> out;
  const float golden = kPi * (3.0f - std::sqrt(5.0f));
  for (size_t i = 0; i < n; ++i) {
    const float z = 1.0f - (2.0f * float(i) + 1.0f) / float(n);
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    out.emplace_back(r * std::cos(golden * float(i)), r * std::sin(golden * float(i)), z);
  }
  return out;
}

TEST(ProbeVisibility, EveryTexelsCentreFallsInItself) {
  for (int t = 0; t < kProbeDepthTexels; ++t) {
    const glm::vec3 d = probeDepthTexelDirection(t);
    EXPECT_NEAR(glm::length(d), 1.0f, 1e-5f);
    EXPECT_EQ(probeDepthTexel(d), t);
  }
  // And every direction falls in a texel whose centre is within 40° of it.
  test::Rng rng{7};
  for (int k = 0; k < 1000; ++k) {
    const glm::vec3 d = randomDirection(rng);
    EXPECT_GT(glm::dot(d, probeDepthTexelDirection(probeDepthTexel(d))), std::cos(0.7f));
  }
}

// A probe 1 m from an infinite wall (x = 1) with nothing else around: points on its side of the
// wall, half way to it, are seen in every direction within 73° of the wall's normal; points half
// a metre behind it are hidden within 45° (nearer the grazing angle the coarse map, a texel every
// 25°, reads the wall at distances a few rays apart: the price of 256 bytes a probe).
TEST(ProbeVisibility, AWallHidesWhatIsBehindIt) {
  const std::vector<glm::vec3> dirs = rays(256);
  std::vector<float> distance;
  for (const glm::vec3& d : dirs) distance.push_back(d.x > 0.0f ? 1.0f / d.x : kProbeDepthFar);
  std::vector<uint16_t> map(kProbeDepthValues);
  probeDepthMoments(probeDepthFilter(dirs.data(), dirs.size()), distance.data(), map.data());
  test::Rng rng{9};
  int inFront = 0, behind = 0, hiddenInFront = 0, seenBehind = 0;
  for (int k = 0; k < 2000; ++k) {
    const glm::vec3 d = randomDirection(rng);
    if (d.x < 0.3f) continue;
    const float wall = 1.0f / d.x;
    ++inFront;
    hiddenInFront += probeVisibility(map.data(), d * (0.5f * wall)) < 0.99f;
    if (d.x < std::cos(kPi / 4.0f)) continue;
    ++behind;
    seenBehind += probeVisibility(map.data(), d * (wall + 0.5f / d.x)) > 0.01f;
  }
  EXPECT_GT(inFront, 500);
  EXPECT_GT(behind, 200);
  EXPECT_EQ(hiddenInFront, 0);
  EXPECT_EQ(seenBehind, 0);

  // Two probes, at x = 0 (the wall at x = 1 ahead) and x = 2 (its own map: the wall behind it),
  // a point at x = 1.3 weighed half and half: all its weight goes to the probe at x = 2.
  std::vector<float> back;
  for (const glm::vec3& d : dirs) back.push_back(d.x < 0.0f ? -1.0f / d.x : kProbeDepthFar);
  std::vector<uint16_t> maps(2 * kProbeDepthValues);
  const ProbeDepthFilter filter = probeDepthFilter(dirs.data(), dirs.size());
  probeDepthMoments(filter, distance.data(), maps.data());
  probeDepthMoments(filter, back.data(), maps.data() + kProbeDepthValues);
  const std::vector<glm::vec3> positions = {{0, 0, 0}, {2, 0, 0}};
  ProbeLocation where;
  where.probes = glm::ivec4(0, 1, -1, -1);
  where.weights = glm::vec4(0.5f, 0.5f, 0.0f, 0.0f);
  const ProbeLocation seen = weighByVisibility(where, positions, maps, glm::vec3(1.3f, 0.1f, 0.0f));
  EXPECT_LT(seen.weights[0], 1e-3f);
  EXPECT_NEAR(seen.weights[0] + seen.weights[1], 1.0f, 1e-6f);
  // Without maps the weights stay as located.
  const ProbeLocation same = weighByVisibility(where, positions, {}, glm::vec3(1.3f, 0.1f, 0.0f));
  EXPECT_EQ(same.weights, where.weights);
}

}  // namespace
}  // namespace afterglow::runtime
