// The reflection capture's reads of the previous pass's probes (reflection_capture.h): a tap,
// resolved once against a chain's shape, reads what an engine's trilinear lookup of the chain
// (sampleChain) reads; a probe's tabulated irradiance reads what its SH gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/reflection_capture.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "test_rng.h"

namespace afterglow::runtime {
namespace {

using test::Rng;

// A uniform direction: a point uniform in the ball (by rejection), normalised.
glm::vec3 directionInBall(Rng& rng) {
  for (;;) {
    const glm::vec3 d(2.0f * rng.unit() - 1.0f, 2.0f * rng.unit() - 1.0f, 2.0f * rng.unit() - 1.0f);
    const float len = glm::length(d);
    if (len > 0.05f && len <= 1.0f) return d / len;
  }
}

// A room-like radiance cube: smooth variation, a bright patch (a sun or a lamp) and texel noise,
// so every mip holds something different.
Cubemap roomRadiance(int size, Rng& rng) {
  Cubemap cube = makeCubemap(size);
  const glm::vec3 sun = glm::normalize(glm::vec3(0.4f, 0.8f, -0.3f));
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const glm::vec3 d = cubemapTexelDirection(face, x, y, size);
        const float lobe = std::pow(std::max(glm::dot(d, sun), 0.0f), 40.0f);
        cube.at(face, x, y) = glm::vec3(0.3f + 0.2f * d.y, 0.25f + 0.1f * d.x, 0.2f) +
                              glm::vec3(20.0f, 18.0f, 15.0f) * lobe +
                              0.05f * glm::vec3(rng.unit(), rng.unit(), rng.unit());
      }
  return cube;
}

TEST(ReflectionLighting, ATapReadsWhatTheTrilinearLookupReads) {
  Rng rng{7};
  const CubemapChain chain = reflectionChain(roomRadiance(32, rng));
  const std::vector<ProbeLight> lights = {probeLight(chain)};
  const ReflectionLighting lighting{nullptr, &lights, nullptr, 0};
  float worst = 0.0f;
  for (int i = 0; i < 4000; ++i) {
    ReflectionLookup lookup;
    lookup.probe = 0;
    lookup.weight = 0.25f + rng.unit();
    lookup.reflected = directionInBall(rng);
    lookup.normal = directionInBall(rng);
    // Mirrors, both ends and every mip in between.
    const float r = i % 7 == 0 ? 0.0f : i % 7 == 1 ? 1.0f : rng.unit();
    const ReflectionTap tap = reflectionTap(lookup, r, chain[0].size, int(chain.size()));
    const glm::vec3 got = lighting.radiance(&tap, 1, r, nullptr);
    const glm::vec3 want = lookup.weight * sampleChain(chain, lookup.reflected, r);
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(got[c] - want[c]) / want[c]);
  }
  std::printf("tap against sampleChain: worst relative difference %.2g\n", double(worst));
  EXPECT_LT(worst, 1e-5f);  // float rounding only: the same texels and weights
}

TEST(ReflectionLighting, TabulatedIrradianceIsTheShs) {
  Rng rng{11};
  const CubemapChain chain = reflectionChain(roomRadiance(32, rng));
  const ProbeLight light = probeLight(chain);
  const ShL2 sh = chainIrradianceSh(chain);
  // Against the mean irradiance: a sun's SH L2 irradiance falls near zero on the far side,
  // where a relative figure means nothing.
  double mean = 0.0, worst = 0.0;
  std::vector<glm::vec3> dirs;
  for (int i = 0; i < 4000; ++i) dirs.push_back(directionInBall(rng));
  for (const glm::vec3& d : dirs) mean += double(irradianceOverPi(sh, d).x);
  mean /= double(dirs.size());
  for (const glm::vec3& d : dirs) {
    const glm::vec3 got = sampleBorderedCubemap(light.irradiance, d);
    const glm::vec3 want = glm::max(irradianceOverPi(sh, d), glm::vec3(0.0f));
    worst = std::max(worst, double(std::abs(got.x - want.x)) / mean);
  }
  std::printf("tabulated irradiance (%d² faces) against the SH: worst error %.3f%% of the mean\n",
              kProbeIrradianceSize, 100.0 * worst);
  EXPECT_LT(worst, 0.01);  // reflection_capture.h's figure
}

}  // namespace
}  // namespace afterglow::runtime
