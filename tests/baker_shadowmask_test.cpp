// Shadowmask (Unity's, for mixed lights; issue 29): each mixed light gets a channel no
// overlapping mixed light has, at most four, the rest reported; a channel holds the visible
// fraction of its light, which must match a visibility estimate of the test's own (many shadow
// rays to the light's silhouette disk, sampled here, not by the baker) within 2%.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/baker/shadowmask.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/uv/indirect.h"
#include "bake_fixtures.h"

namespace afterglow::baker {
namespace {

scenes::Light pointLight(const char* name, glm::vec3 position, float range,
                         scenes::LightMode mode = scenes::LightMode::Mixed) {
  scenes::Light l;
  l.name = name;
  l.type = scenes::LightType::Point;
  l.position = position;
  l.range = range;
  l.mode = mode;
  return l;
}

TEST(Shadowmask, OverlappingMixedLightsGetDifferentChannelsAtMostFour) {
  std::vector<scenes::Light> lights;
  scenes::Light sun;
  sun.name = "sun";
  sun.type = scenes::LightType::Directional;
  sun.mode = scenes::LightMode::Mixed;
  lights.push_back(sun);                                                          // 0: overlaps all
  lights.push_back(pointLight("baked", glm::vec3(0), 5, scenes::LightMode::Baked));  // no channel
  lights.push_back(pointLight("a", glm::vec3(0, 0, 0), 2));
  lights.push_back(pointLight("b", glm::vec3(3, 0, 0), 2));     // overlaps a
  lights.push_back(pointLight("far", glm::vec3(100, 0, 0), 2)); // overlaps only the sun
  lights.push_back(pointLight("c", glm::vec3(1, 1, 0), 2));     // overlaps the sun, a, b
  lights.push_back(pointLight("d", glm::vec3(1, -1, 0), 0));    // no range: overlaps all 4
  lights.push_back(pointLight("rt", glm::vec3(0), 5, scenes::LightMode::Realtime));
  std::vector<std::string> overflow;
  const std::vector<int> channel = shadowmaskChannels(lights, &overflow);
  ASSERT_EQ(channel.size(), lights.size());
  EXPECT_EQ(channel[0], 0);
  EXPECT_EQ(channel[1], -1);
  EXPECT_EQ(channel[2], 1);
  EXPECT_EQ(channel[3], 2);
  EXPECT_EQ(channel[4], 1);  // shares a's channel: they never light one point together
  EXPECT_EQ(channel[5], 3);
  EXPECT_EQ(channel[6], -1);  // the sun, a, b, c and far take all four where it reaches
  EXPECT_EQ(channel[7], -1);
  ASSERT_EQ(overflow.size(), 1u);
  EXPECT_EQ(overflow[0], "d");
}

// The built-in Cornell box lit by one mixed point light of 5 cm radius (its lamp's emission
// off): the blocks cast soft shadows.
scenes::Scene mixedLampBox(bool grid) {
  scenes::Light lamp = pointLight("lamp", glm::vec3(0.0f), 0);
  lamp.radius = 0.05f;
  return lampLitCornell(lamp, glm::vec3(0.4f, 0.85f, 0.5f), grid);
}

// The visible fraction of a sphere light from point p: kRays shadow rays to points spread
// evenly (a golden-angle spiral) over the disk through its centre facing p.
float visibility(const trace::RayTracer& tracer, const scenes::Light& light, glm::vec3 p) {
  constexpr int kRays = 256;
  const glm::vec3 d = light.position - p;
  const float distance = glm::length(d);
  const glm::vec3 w = d / distance;
  const glm::vec3 u = glm::normalize(glm::cross(std::abs(w.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0), w));
  const glm::vec3 v = glm::cross(w, u);
  int through = 0;
  for (int i = 0; i < kRays; ++i) {
    const float r = light.radius * std::sqrt((float(i) + 0.5f) / float(kRays));
    const float a = 2.39996323f * float(i);
    const glm::vec3 target = light.position + r * (std::cos(a) * u + std::sin(a) * v);
    trace::Ray ray;
    ray.origin = p;
    ray.direction = glm::normalize(target - p);
    ray.tfar = 0.999f * glm::length(target - p);
    ray.mask = trace::kMaskShadowCasters;
    through += tracer.occluded(ray) ? 0 : 1;
  }
  return float(through) / float(kRays);
}

void expectVisibility(bool grid, const char* what) {
  const scenes::Scene scene = mixedLampBox(grid);
  const BakeResult b = bakeOrDie(scene, bakePreset(Quality::Default));
  ASSERT_EQ(b.shadowmaskChannel.size(), 1u);
  ASSERT_EQ(b.shadowmaskChannel[0], 0);
  ASSERT_EQ(b.shadowmasks.size(), b.texels.atlases.size());
  const std::vector<glm::vec4> mask = shadowmaskTexels(scene, b.texels, b.transport, b.shadowmaskChannel);
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  double sum = 0.0, worst = 0.0;
  size_t compared = 0, shadowed = 0, unused = 0;
  for (uint32_t t = 0; t < b.texels.size(); t += 3) {
    if (!b.texels.valid[t]) continue;
    unused += mask[t].y != 1.0f || mask[t].z != 1.0f || mask[t].w != 1.0f;
    if (glm::dot(scene.lights[0].position - b.texels.position[t], b.texels.normal[t]) <= 0.0f) continue;
    const float want = visibility(*tracer.value(), scene.lights[0], b.texels.position[t]);
    const double error = std::abs(double(mask[t].x) - double(want));
    sum += error;
    worst = std::max(worst, error);
    ++compared;
    shadowed += want < 0.5f;
  }
  std::printf("%s: %zu texels facing the lamp (%zu mostly shadowed): shadowmask vs visibility, "
              "mean difference %.4f, largest %.3f\n",
              what, compared, shadowed, sum / double(compared), worst);
  EXPECT_GT(shadowed, compared / 50);  // the blocks' shadows are there to match
  EXPECT_LE(sum / double(compared), 0.02);
  EXPECT_EQ(unused, 0u);  // channels without a light stay 1
}

TEST(Shadowmask, AMixedLightsChannelIsItsVisibility) {
  expectVisibility(false, "one resolution");
  expectVisibility(true, "indirect grid");
}

// Light probes carry the mixed light's occlusion (Unity's probe occlusion) as a probe sees it,
// channel by channel: points all through the box, some in the blocks' shadows.
TEST(Shadowmask, ProbeOcclusionIsTheLightsVisibility) {
  const scenes::Scene scene = mixedLampBox(false);
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  const scenes::Bounds box = scene.bounds();
  std::vector<glm::vec3> points;
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        points.push_back(box.min + (box.max - box.min) * (glm::vec3(x, y, z) + 0.5f) / 8.0f);
  const std::vector<int> channels = shadowmaskChannels(scene.lights);
  const std::vector<glm::vec4> occlusion = probeOcclusion(scene, *tracer.value(), points, channels, 256);
  ASSERT_EQ(occlusion.size(), points.size());
  double sum = 0.0;
  size_t shadowed = 0, lit = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const float want = visibility(*tracer.value(), scene.lights[0], points[i]);
    sum += std::abs(double(occlusion[i].x) - double(want));
    shadowed += want < 0.5f;
    lit += want > 0.5f;
    EXPECT_EQ(occlusion[i].y, 1.0f);
  }
  std::printf("%zu probe positions (%zu shadowed, %zu lit): occlusion vs visibility, mean "
              "difference %.4f\n",
              points.size(), shadowed, lit, sum / double(points.size()));
  EXPECT_GT(shadowed, 10u);
  EXPECT_GT(lit, 10u);
  EXPECT_LE(sum / double(points.size()), 0.02);
}

}  // namespace
}  // namespace afterglow::baker
