// Light modes (Unity's, extras.afterglow.mode; issue 29): a realtime or mixed light's direct
// light is the engine's, so the lightmaps hold only its bounced light: its direct part is 0 and
// the bounced light is the baked light's, bit for bit, at one resolution and on an indirect grid.
#include <algorithm>
#include <cstdio>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/uv/indirect.h"
#include "bake_fixtures.h"

namespace afterglow::baker {
namespace {

// The built-in Cornell box lit by a point light alone (its lamp's emission off).
scenes::Scene lampLitBox(bool grid, scenes::LightMode mode) {
  scenes::Light lamp;
  lamp.name = "lamp";
  lamp.type = scenes::LightType::Point;
  lamp.radius = 0.02f;
  lamp.intensity = 1.0f;
  lamp.mode = mode;
  return lampLitCornell(lamp, glm::vec3(0.4f, 0.8f, 0.5f), grid);
}

void expectOnlyBouncedLight(bool grid, scenes::LightMode mode, const char* what) {
  const BakeOptions o = bakePreset(Quality::Draft);
  const BakeResult baked = bakeOrDie(lampLitBox(grid, scenes::LightMode::Baked), o);
  const BakeResult left = bakeOrDie(lampLitBox(grid, mode), o);
  ASSERT_EQ(baked.texels.size(), left.texels.size());
  ASSERT_EQ(baked.transport.lightmap.active(), grid);
  double directBaked = 0.0, directLeft = 0.0;
  size_t differentBounces = 0;
  for (uint32_t t = 0; t < left.texels.size(); ++t) {
    if (!left.texels.valid[t]) continue;
    directBaked += double(baked.texelDirect[t].x);
    directLeft += double(std::abs(left.texelDirect[t].x));
    differentBounces += left.texelIndirect[t] != baked.texelIndirect[t];
  }
  std::printf("%s: direct light %.1f (baked) -> %.1f; %zu texels' bounced light differs\n", what,
              directBaked, directLeft, differentBounces);
  EXPECT_GT(directBaked, 0.0);
  EXPECT_EQ(directLeft, 0.0);
  EXPECT_EQ(differentBounces, 0u);
  // Relit, the runtime leaves it out alike, and keeps leaving it out when the light changes.
  std::string error;
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::fromData(left.transport, &error);
  ASSERT_TRUE(rt) << error;
  runtime::UpdateOptions update;
  update.fromScratch = true;
  rt->update(update);
  std::vector<glm::vec3> image;
  ASSERT_TRUE(rt->readAtlas(0, image));
  EXPECT_TRUE(image == left.lightmaps[0]) << what;
}

TEST(LightModes, ARealtimeLightsLightmapHoldsItsBouncedLightOnly) {
  expectOnlyBouncedLight(false, scenes::LightMode::Realtime, "realtime");
  expectOnlyBouncedLight(true, scenes::LightMode::Realtime, "realtime, indirect grid");
}

TEST(LightModes, AMixedLightsDirectLightIsLeftToTheEngine) {
  expectOnlyBouncedLight(false, scenes::LightMode::Mixed, "mixed");
}

}  // namespace
}  // namespace afterglow::baker
