// The default bake against the reference path tracer on the measured Cornell box of
// ../shared/scenes (McGuire's, its emissive ceiling lamp emitting downwards only), unwrapped
// into one 256² atlas: relative RMSE ≤ 3% over valid texels and mean bias ≤ 1%, for direct and
// for indirect light. The errors are per texel and relative to the texel's own value
// (baker::compareToReference); the reference runs 32768 paths per texel over every 32nd valid
// texel, so its own noise stays near 1% and cannot hide a real error.
#include <cstdio>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/uv/unwrap.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::baker {
namespace {

TEST(BakeAccuracy, CornellBoxDefaultBakeMatchesTheReferencePathTracer) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  const scenes::Scene scene = cornellForAccuracy(path);  // the lamp emits downwards only
  ASSERT_FALSE(scene.materials.empty());

  Result<BakeResult> baked = bake(scene, BakeOptions());
  ASSERT_TRUE(baked) << baked.message();
  const BakeResult& b = baked.value();

  std::vector<uint32_t> subset;
  for (uint32_t t = 0, k = 0; t < b.texels.size(); ++t)
    if (b.texels.valid[t] && k++ % 32 == 0) subset.push_back(t);
  ASSERT_GT(subset.size(), 1000u);
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  ReferenceOptions high;
  high.samples = 32768;
  Result<ReferenceTexels> ref =
      referenceTexels(scene, *tracer.value(), b.texels, Environment(), high, subset);
  ASSERT_TRUE(ref) << ref.message();
  const ReferenceComparison c = compareToReference(ref.value(), b.texelDirect, b.texelIndirect);
  std::printf("cornell %ux%u, %zu texels compared: direct RMSE %.2f%% bias %+.2f%%, indirect "
              "RMSE %.2f%% bias %+.2f%% (reference noise %.2f%% / %.2f%%)\n",
              b.texels.atlases[0].width, b.texels.atlases[0].height, c.texels,
              100.0 * c.direct.relativeRmse, 100.0 * c.direct.bias,
              100.0 * c.indirect.relativeRmse, 100.0 * c.indirect.bias,
              100.0 * c.direct.referenceNoise, 100.0 * c.indirect.referenceNoise);
  // The reference must be far better than the tolerance for the comparison to mean anything.
  EXPECT_LT(c.direct.referenceNoise, 0.015);
  EXPECT_LT(c.indirect.referenceNoise, 0.015);
  EXPECT_LE(c.direct.relativeRmse, 0.03);
  EXPECT_LE(std::abs(c.direct.bias), 0.01);
  EXPECT_LE(c.indirect.relativeRmse, 0.03);
  EXPECT_LE(std::abs(c.indirect.bias), 0.01);
}

}  // namespace
}  // namespace afterglow::baker
