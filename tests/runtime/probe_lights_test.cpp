// Light probes' small sources kept as directions (probe_lights.h): exact for one direction,
// closer than SH L2 for a small source, no change for a spread one, linear under interpolation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "afterglow/core/math.h"
#include "afterglow/runtime/probe_lights.h"
#include "test_rng.h"

namespace afterglow::runtime {
namespace {


// The grey part (channel 0) of an SH as the nine floats a source's unit transfer holds.
std::array<float, kShCount> channel0(const ShL2& sh) {
  std::array<float, kShCount> out{};
  for (int i = 0; i < kShCount; ++i) out[size_t(i)] = sh.c[i].x;
  return out;
}

// A uniform cap of radiance 1 about `axis`, of half-angle `degrees`, as `count` directions of
// equal solid angle (stratified in cos θ and φ); `weight` receives each one's solid angle.
std::vector<glm::vec3> cap(glm::vec3 axis, float degrees, int count, float* weight) {
  const float cosMax = std::cos(degrees * kPi / 180.0f);
  const glm::vec3 u = glm::normalize(glm::cross(axis, std::abs(axis.x) < 0.9f ? glm::vec3(1, 0, 0)
                                                                                : glm::vec3(0, 1, 0)));
  const glm::vec3 v = glm::cross(axis, u);
  const int side = int(std::sqrt(float(count)));
  std::vector<glm::vec3> out;
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const float c = 1.0f - (float(i) + 0.5f) / float(side) * (1.0f - cosMax);
      const float s = std::sqrt(std::max(0.0f, 1.0f - c * c));
      const float phi = 2.0f * kPi * (float(j) + 0.5f) / float(side);
      out.push_back(c * axis + s * (std::cos(phi) * u + std::sin(phi) * v));
    }
  *weight = 2.0f * kPi * (1.0f - cosMax) / float(out.size());
  return out;
}

// The SH of those directions and the probe lighting concentratedPart makes of them.
ProbeLighting lightingOf(const std::vector<glm::vec3>& dirs, float weight) {
  ProbeLighting l;
  for (const glm::vec3& d : dirs) projectRadiance(d, glm::vec3(1.0f), weight, l.sh);
  const std::array<float, kShCount> grey = channel0(l.sh);
  ProbeDirection light;
  float power = 0.0f;
  if (concentratedPart(grey.data(), &light.direction, &power)) {
    light.power = glm::vec3(power);
    l.lights.push_back(light);
  }
  return l;
}

// E/π of the directions themselves at normal n (the truth for that set of directions).
float exactOverPi(const std::vector<glm::vec3>& dirs, float weight, glm::vec3 n) {
  double sum = 0.0;
  for (const glm::vec3& d : dirs) sum += std::max(0.0f, glm::dot(n, d));
  return float(sum * weight / kPi);
}

TEST(ProbeLights, OneDirectionIsReadExactlyForEveryNormalWithAndWithoutDeringing) {
  test::Rng rng{3};
  for (int trial = 0; trial < 20; ++trial) {
    const glm::vec3 d = randomDirection(rng);
    const glm::vec3 e0(0.5f + rng.unit(), 2.0f * rng.unit(), 3.0f);
    ShL2 sh;
    projectRadiance(d, e0, 1.0f, sh);
    const std::array<float, kShCount> grey = channel0(sh);
    ProbeDirection light;
    float power = 0.0f;
    ASSERT_TRUE(concentratedPart(grey.data(), &light.direction, &power));
    EXPECT_NEAR(glm::dot(light.direction, d), 1.0f, 1e-5f);
    EXPECT_NEAR(power, e0.x, 1e-4f * e0.x);
    light.power = e0;  // the source's colour scales the grey unit
    for (float window : {0.0f, 4.0f}) {
      ProbeLighting lighting{deringed(sh, window), {light}};
      for (int k = 0; k < 16; ++k) {
        const glm::vec3 n = randomDirection(rng);
        const glm::vec3 want = e0 * (std::max(0.0f, glm::dot(n, d)) / kPi);
        const glm::vec3 got = lighting.irradianceOverPi(n, window);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 2e-5f * e0[c] + 1e-6f);
      }
    }
  }
}

// A cap of 10° (a lamp of 35 cm seen from 1 m): SH L2 alone is 3-4% of the peak off RMS, the
// cap read as one direction several times less.
TEST(ProbeLights, ASmallSourceIsCloserThanSHAlone) {
  test::Rng rng{5};
  float weight = 0.0f;
  const glm::vec3 axis = glm::normalize(glm::vec3(0.3f, 1.0f, -0.2f));
  const std::vector<glm::vec3> dirs = cap(axis, 10.0f, 4096, &weight);
  const ProbeLighting lighting = lightingOf(dirs, weight);
  ASSERT_EQ(lighting.lights.size(), 1u);
  const float peak = exactOverPi(dirs, weight, axis);
  double shOnly = 0.0, with = 0.0;
  const int normals = 256;
  for (int k = 0; k < normals; ++k) {
    const glm::vec3 n = randomDirection(rng);
    const float truth = exactOverPi(dirs, weight, n);
    shOnly += std::pow(double(irradianceOverPi(lighting.sh, n).x - truth), 2.0);
    with += std::pow(double(lighting.irradianceOverPi(n).x - truth), 2.0);
  }
  shOnly = std::sqrt(shOnly / normals) / peak;
  with = std::sqrt(with / normals) / peak;
  std::printf("a 10-degree cap: E/pi RMS error over %d normals, of its peak: SH L2 %.2f%%, with "
              "its direction %.2f%%\n", normals, 100.0 * shOnly, 100.0 * with);
  EXPECT_GT(shOnly, 0.02);
  EXPECT_LT(with, 0.3 * shOnly);
}

// Sources spread out, where SH L2 is the better fit, are left to it: a constant sky, a
// hemisphere, a cap of 45°.
TEST(ProbeLights, SpreadSourcesStayInTheSH) {
  float weight = 0.0f;
  for (float degrees : {45.0f, 90.0f, 180.0f}) {
    const ProbeLighting lighting = lightingOf(cap(glm::vec3(0, 1, 0), degrees, 4096, &weight), weight);
    EXPECT_TRUE(lighting.lights.empty()) << degrees;
  }
  const float none[kShCount] = {};
  glm::vec3 d;
  float power = 1.0f;
  EXPECT_FALSE(concentratedPart(none, &d, &power));
}

// Lights mix with the probes' weights: E/π at a point is the weighted sum of its probes'.
TEST(ProbeLights, InterpolationIsLinearInTheProbes) {
  test::Rng rng{11};
  std::vector<ShL2> sh(4);
  ProbeDirectionList list;
  list.start.push_back(0);
  std::vector<ProbeLighting> each(4);
  for (int p = 0; p < 4; ++p) {
    const glm::vec3 d = randomDirection(rng);
    const glm::vec3 e(rng.unit(), rng.unit(), rng.unit());
    projectRadiance(d, e, 1.0f, sh[size_t(p)]);
    projectRadiance(randomDirection(rng), glm::vec3(0.2f), 4.0f, sh[size_t(p)]);
    const ProbeDirection light{d, e};
    if (p != 2) list.lights.push_back(light);  // probe 2 has none
    list.start.push_back(uint32_t(list.lights.size()));
    each[size_t(p)] = ProbeLighting{sh[size_t(p)], p != 2 ? std::vector<ProbeDirection>{light}
                                                          : std::vector<ProbeDirection>{}};
  }
  ProbeLocation where;
  const float w[4] = {0.1f, 0.2f, 0.3f, 0.4f};
  for (int k = 0; k < 4; ++k) where.probes[k] = k, where.weights[k] = w[k];
  const ProbeLighting mixed = mixProbeLighting(where, sh, list);
  ASSERT_EQ(mixed.lights.size(), 3u);
  for (int k = 0; k < 16; ++k) {
    const glm::vec3 n = randomDirection(rng);
    glm::vec3 want(0.0f);
    for (int p = 0; p < 4; ++p) want += w[p] * each[size_t(p)].irradianceOverPi(n);
    const glm::vec3 got = mixed.irradianceOverPi(n);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1e-5f);
  }
}

}  // namespace
}  // namespace afterglow::runtime
