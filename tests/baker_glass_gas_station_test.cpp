// Issue 28's figure for light through glass, end to end: the gas station of ../shared/scenes
// (every material double-sided, no lights, a closed shop whose windows are alphaMode BLEND
// glass of alpha 0.42) unwrapped as `afterglow bake` unwraps it and baked under a white sky
// with the default settings, against the reference path tracer on the shop's interior: relative
// RMSE ≤ 5% and |bias| ≤ 2% over its texels. Before glass let light through, the shop was
// dark: 76% off, bias −53% (`afterglow_bench glass --opaque-glass`).
//
// The interior: the valid texels inside the world bounds of the shop's shell (the instance
// "Mesh_new_base_0": walls, floor and roof), shrunk by 2 cm so that the outsides of its 4 cm
// walls and roof stay out; the panes sit in the walls' inner plane, so their texels are in. One
// in 16 of them by a hash of the texel index (as `afterglow_bench glass` picks one in 4), with
// 65536 paths each, so that the reference's own noise stays near 1%.
#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/baker/reference.h"
#include "afterglow/bakefiles/pipeline.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/gltf.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::baker {
namespace {

TEST(BakeGlassGasStation, ShopLitThroughItsWindowsMatchesTheReferencePathTracer) {
  AG_REQUIRE_SHARED_SCENE(path, "gas_station/GasStation.gltf");
  Result<scenes::Scene> loaded = scenes::loadGltf(path);
  ASSERT_TRUE(loaded) << loaded.message();
  scenes::Scene& scene = loaded.value();
  scenes::Bounds shell;
  for (const scenes::Instance& inst : scene.instances)
    if (inst.name == "Mesh_new_base_0")
      scenes::forEachWorldTriangle(scene, inst, [&](size_t, size_t, glm::vec3 a, glm::vec3 b,
                                                    glm::vec3 c) {
        shell.extend(a);
        shell.extend(b);
        shell.extend(c);
      });
  ASSERT_FALSE(shell.empty()) << "the shop's shell is missing";
  bakefiles::BakeJob job;
  job.input = path;
  Result<bakefiles::UnwrapStep> unwrapped = bakefiles::unwrapForBake(scene, job);
  ASSERT_TRUE(unwrapped) << unwrapped.message();

  BakeOptions options;
  options.skyColor = glm::vec3(1.0f);
  Result<BakeResult> baked = bake(scene, options);
  ASSERT_TRUE(baked) << baked.message();
  const BakeResult& b = baked.value();

  const glm::vec3 lo = shell.min + 0.02f, hi = shell.max - 0.02f;
  std::vector<uint32_t> interior;
  for (uint32_t t = 0; t < b.texels.size(); ++t) {
    uint32_t h = t * 0x9e3779b1u;
    h ^= h >> 15;
    const glm::vec3 p = b.texels.position[t];
    if (b.texels.valid[t] && h % 16 == 0 && glm::all(glm::greaterThan(p, lo)) &&
        glm::all(glm::lessThan(p, hi)))
      interior.push_back(t);
  }
  ASSERT_GT(interior.size(), 500u);
  Environment sky;
  runtime::constantSkySh(glm::vec3(1.0f), sky.skySh);
  const ReferenceComparison c = compareToReference(
      referenceOrDie(scene, b.texels, sky, 65536, interior), b.texelDirect, b.texelIndirect);
  ASSERT_EQ(c.texels, interior.size());
  printComparison("gas station shop", c);
  // The reference must be far better than the tolerance for the comparison to mean anything.
  EXPECT_LT(c.total.referenceNoise, 0.015);
  EXPECT_LE(c.total.relativeRmse, 0.05);
  EXPECT_LE(std::abs(c.total.bias), 0.02);
}

}  // namespace
}  // namespace afterglow::baker
