// The default bake, and one with an indirect grid, against the reference path tracer on the
// measured Cornell box of ../shared/scenes (McGuire's, its emissive ceiling lamp emitting
// downwards only), unwrapped into one 256² atlas: relative RMSE ≤ 3% over valid texels and mean
// bias ≤ 1%, for direct and for indirect light (the grid's bounced light: below). The errors are per texel and relative to the texel's own value
// (baker::compareToReference); the reference runs 32768 paths per texel over every 32nd valid
// texel, so its own noise stays near 1% and cannot hide a real error.
#include <cmath>
#include <cstdio>
#include <memory>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/uv/indirect.h"
#include "afterglow/uv/unwrap.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::baker {
namespace {

// The scene, and the reference over every 32nd valid texel of its default bake, made once for
// both tests (the lightmap's texels are the same with an indirect grid).
struct CornellReference {
  scenes::Scene scene;
  BakeResult bake;
  ReferenceTexels reference;
};

const CornellReference* cornellReference(const std::string& path) {
  static CornellReference* cached = nullptr;
  if (cached) return cached;
  auto* c = new CornellReference;
  c->scene = cornellForAccuracy(path);  // the lamp emits downwards only
  EXPECT_FALSE(c->scene.materials.empty());
  EXPECT_FALSE(hasIndirectGrid(c->scene));
  Result<BakeResult> baked = bake(c->scene, BakeOptions());
  EXPECT_TRUE(baked) << baked.message();
  if (!baked) return nullptr;
  c->bake = std::move(baked.value());
  const BakeResult& b = c->bake;
  std::vector<uint32_t> subset;
  for (uint32_t t = 0, k = 0; t < b.texels.size(); ++t)
    if (b.texels.valid[t] && k++ % 32 == 0) subset.push_back(t);
  EXPECT_GT(subset.size(), 1000u);
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(c->scene);
  EXPECT_TRUE(tracer) << tracer.message();
  if (!tracer) return nullptr;
  ReferenceOptions high;
  high.samples = 32768;
  Result<ReferenceTexels> ref =
      referenceTexels(c->scene, *tracer.value(), b.texels, Environment(), high, subset);
  EXPECT_TRUE(ref) << ref.message();
  if (!ref) return nullptr;
  c->reference = std::move(ref.value());
  cached = c;
  return cached;
}

// RMSE within `indirectRmse` for bounced light and 3% for direct light, biases within
// `indirectBias` and 1%.
void expectAccurate(const char* what, const BakeResult& b, const ReferenceTexels& ref,
                    double indirectRmse = 0.03, double indirectBias = 0.01) {
  const ReferenceComparison c = compareToReference(ref, b.texelDirect, b.texelIndirect);
  std::printf("%s %ux%u, %zu texels compared: direct RMSE %.2f%% bias %+.2f%%, indirect "
              "RMSE %.2f%% bias %+.2f%% (reference noise %.2f%% / %.2f%%)\n",
              what, b.texels.atlases[0].width, b.texels.atlases[0].height, c.texels,
              100.0 * c.direct.relativeRmse, 100.0 * c.direct.bias,
              100.0 * c.indirect.relativeRmse, 100.0 * c.indirect.bias,
              100.0 * c.direct.referenceNoise, 100.0 * c.indirect.referenceNoise);
  // The reference must be far better than the tolerance for the comparison to mean anything.
  EXPECT_LT(c.direct.referenceNoise, 0.015);
  EXPECT_LT(c.indirect.referenceNoise, 0.015);
  EXPECT_LE(c.direct.relativeRmse, 0.03);
  EXPECT_LE(std::abs(c.direct.bias), 0.01);
  EXPECT_LE(c.indirect.relativeRmse, indirectRmse);
  EXPECT_LE(std::abs(c.indirect.bias), indirectBias);
}

TEST(BakeAccuracy, CornellBoxDefaultBakeMatchesTheReferencePathTracer) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  const CornellReference* c = cornellReference(path);
  ASSERT_TRUE(c);
  expectAccurate("cornell", c->bake, c->reference);
}

// Bounced light on an indirect grid of a quarter the lightmap's texels, direct light per
// lightmap texel, on the same texels: the direct light as accurate as the default bake's (it is
// the same light, to half precision); the bounced light within 6% (5.3% measured: the grid's
// bilinear reads soften it where it changes within a grid texel, in the corners and under the
// blocks; a grid as fine as the lightmap gives 3.2%), bias within 1.5%.
TEST(BakeAccuracy, CornellBoxOnAnIndirectGridMatchesTheReferencePathTracer) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  const CornellReference* c = cornellReference(path);
  ASSERT_TRUE(c);
  scenes::Scene scene = c->scene;
  Result<uv::IndirectLayout> grid =
      uv::packIndirect(scene, uv::texelsPerUnitFor(scene, double(c->bake.texels.size()) / 4.0));
  ASSERT_TRUE(grid) << grid.message();
  Result<BakeResult> baked = bake(scene, BakeOptions());
  ASSERT_TRUE(baked) << baked.message();
  ASSERT_TRUE(baked->transport.lightmap.active());
  ASSERT_EQ(baked->texels.size(), c->bake.texels.size());
  // The texels the lightmap keeps in both (its own burial test may bury a few more).
  ReferenceTexels both;
  for (size_t i = 0; i < c->reference.texels.size(); ++i) {
    if (!baked->texels.valid[c->reference.texels[i]]) continue;
    both.texels.push_back(c->reference.texels[i]);
    both.direct.push_back(c->reference.direct[i]);
    both.indirect.push_back(c->reference.indirect[i]);
    both.directVariance.push_back(c->reference.directVariance[i]);
    both.indirectVariance.push_back(c->reference.indirectVariance[i]);
  }
  std::printf("indirect grid: %u texels for %u lightmap texels; %zu of %zu reference texels "
              "valid in both\n",
              baked->transport.texelCount, baked->transport.lightmap.texelCount,
              both.texels.size(), c->reference.texels.size());
  EXPECT_GE(both.texels.size(), c->reference.texels.size() * 98 / 100);
  expectAccurate("cornell, indirect grid", baked.value(), both, 0.06, 0.015);
}

}  // namespace
}  // namespace afterglow::baker
