// The relighting runtime against the baker: a bake relit through runtime::Runtime with changed
// light colour, intensity, bounce intensity, a light switched off, albedo, emission or sky
// equals a fresh bake of the scene with the same change (max relative difference <= 1e-4, the
// lightmaps and, on the Cornell box, the light probes),
// on the Cornell box and on Sponza-sun; and relighting is linear in the lights.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/uv/indirect.h"
#include "afterglow/uv/unwrap.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::baker {
namespace {

struct Baked {
  scenes::Scene scene;
  BakeResult result;
};

// Loads and unwraps a shared scene at a small resolution (empty scene when it is absent).
scenes::Scene loadSmall(const std::string& path, int atlasSize) {
  Result<scenes::Scene> loaded = scenes::loadGltf(path);
  EXPECT_TRUE(loaded) << loaded.message();
  if (!loaded) return {};
  scenes::Scene scene = std::move(loaded.value());
  unwrapIntoAtlas(scene, atlasSize);
  return scene;
}

BakeOptions fastOptions() {
  BakeOptions o = bakePreset(Quality::Draft);
  o.direct.penumbraSamples = 16;
  return o;
}

// The largest per-channel difference between atlases and a bake's lightmaps, relative to the
// bake's value (floored at 1e-3 of the mean so black texels do not divide by 0).
double maxRelativeDifference(const std::vector<std::vector<glm::vec3>>& images,
                             const BakeResult& fresh) {
  EXPECT_EQ(images.size(), fresh.lightmaps.size());
  double worst = 0.0;
  for (size_t a = 0; a < fresh.lightmaps.size() && a < images.size(); ++a) {
    const std::vector<glm::vec3>& image = images[a];
    const std::vector<glm::vec3>& want = fresh.lightmaps[a];
    EXPECT_EQ(image.size(), want.size());
    if (image.size() != want.size()) return 1.0;
    double mean = 0.0;
    for (const glm::vec3& v : want) mean += double(v.x + v.y + v.z) / 3.0;
    mean /= double(std::max<size_t>(1, want.size()));
    const double floor = std::max(1e-3 * mean, 1e-30);
    for (size_t p = 0; p < want.size(); ++p)
      for (int k = 0; k < 3; ++k)
        worst = std::max(worst, std::abs(double(image[p][k]) - double(want[p][k])) /
                                    std::max(double(std::abs(want[p][k])), floor));
  }
  return worst;
}

// Relights `base` with `change` applied to a Runtime and compares with a fresh bake of `edited`
// under `options`.
void expectRelitEqualsFresh(const char* what, const BakeResult& base,
                            const scenes::Scene& edited, const BakeOptions& options,
                            const std::function<void(runtime::Runtime&, const BakeResult&)>& change) {
  const BakeResult fresh = bakeOrDie(edited, options);
  std::string error;
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::fromData(base.transport, &error);
  ASSERT_TRUE(rt) << error;
  change(*rt, fresh);
  runtime::UpdateOptions update;
  update.fromScratch = true;
  update.maxBounces = options.solve.maxBounces;
  update.tolerance = options.solve.tolerance;
  rt->update(update);
  std::vector<std::vector<glm::vec3>> relit(size_t(rt->atlasCount()));
  for (size_t a = 0; a < relit.size(); ++a) rt->readAtlas(int(a), relit[a]);
  const double diff = maxRelativeDifference(relit, fresh);
  // The change must show, or the comparison proves nothing.
  const double changed = maxRelativeDifference(base.lightmaps, fresh);
  std::printf("%-34s max relative difference %.2e (the change itself: %.2f)\n", what, diff,
              changed);
  EXPECT_LE(diff, 1e-4) << what;
  EXPECT_GT(changed, 0.01) << what;
  // The light probes alike: every SH coefficient relative to the probes' mean DC term.
  ASSERT_EQ(size_t(rt->probeCount()), fresh.probeSh.size()) << what;
  if (fresh.probeSh.empty()) return;
  double mean = 0.0;
  for (const runtime::ShL2& sh : fresh.probeSh) mean += double(glm::length(sh.c[0]));
  mean /= double(fresh.probeSh.size());
  const double floor = std::max(1e-3 * mean, 1e-30);
  double probeDiff = 0.0, probeChanged = 0.0;
  for (size_t p = 0; p < fresh.probeSh.size(); ++p) {
    runtime::ShL2 relitSh;
    ASSERT_TRUE(rt->probeSh(int(p), &relitSh));
    for (int i = 0; i < runtime::kShCount; ++i)
      for (int k = 0; k < 3; ++k) {
        const double want = double(fresh.probeSh[p].c[i][k]);
        const double scale = std::max(std::abs(want), floor);
        probeDiff = std::max(probeDiff, std::abs(double(relitSh.c[i][k]) - want) / scale);
        probeChanged = std::max(probeChanged, std::abs(double(base.probeSh[p].c[i][k]) - want) / scale);
      }
  }
  std::printf("%-34s probes: max relative difference %.2e (the change itself: %.2f)\n", what,
              probeDiff, probeChanged);
  EXPECT_LE(probeDiff, 1e-4) << what;
  EXPECT_GT(probeChanged, 0.01) << what;
}

int materialNamed(const scenes::Scene& scene, const std::string& name) {
  for (size_t m = 0; m < scene.materials.size(); ++m)
    if (scene.materials[m].name == name) return int(m);
  return -1;
}

// McGuire's Cornell box lit by its ceiling lamp and a point light added in the room, so light
// and emission changes are both there to test.
// The Cornell box's changes, with bounced light solved at the lightmap's texels or, with
// `twoResolutions`, on an indirect grid of about a quarter as many texels (the runtime then
// composes each source's direct light per lightmap texel with the grid's bounced light).
void expectCornellRelitEqualsFresh(const std::string& path, bool twoResolutions) {
  scenes::Scene scene = loadSmall(path, 96);
  ASSERT_FALSE(scene.meshes.empty());
  uv::clearIndirect(scene);
  if (twoResolutions) {
    Result<uv::IndirectLayout> grid = uv::packIndirect(scene, uv::texelsPerUnitFor(scene, 2500.0));
    ASSERT_TRUE(grid) << grid.message();
  }
  scenes::Light lamp;
  lamp.name = "lamp";
  lamp.type = scenes::LightType::Point;
  lamp.position = glm::vec3(-0.4f, 1.2f, 0.3f);
  lamp.radius = 0.05f;
  lamp.intensity = 0.8f;
  lamp.color = glm::vec3(1.0f, 0.8f, 0.6f);
  scene.lights.push_back(lamp);
  BakeOptions options = fastOptions();
  // Light probes on a grid in the room, relit with the lightmaps.
  const scenes::Bounds box = scene.bounds();
  std::vector<glm::vec3> probes;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 3; ++x)
        probes.push_back(box.min + (box.max - box.min) *
                                       glm::vec3(0.2f + 0.3f * float(x), 0.6f + 0.12f * float(y),
                                                 0.2f + 0.3f * float(z)));
  Result<runtime::ProbeTetrahedra> mesh = probes::tetrahedralize(probes);
  ASSERT_TRUE(mesh) << mesh.message();
  options.probes = mesh.value();
  const BakeResult base = bakeOrDie(scene, options);
  ASSERT_FALSE(base.lightmaps.empty());
  ASSERT_EQ(base.transport.lightmap.active(), twoResolutions);

  {
    scenes::Scene e = scene;
    e.lights[0].color = glm::vec3(0.2f, 0.5f, 1.0f);
    expectRelitEqualsFresh("cornell: light colour", base, e, options,
                           [](runtime::Runtime& rt, const BakeResult&) {
                             EXPECT_TRUE(rt.setLightColor("lamp", glm::vec3(0.2f, 0.5f, 1.0f)));
                           });
  }
  {
    scenes::Scene e = scene;
    e.lights[0].intensity = 3.5f;
    expectRelitEqualsFresh("cornell: light intensity", base, e, options,
                           [](runtime::Runtime& rt, const BakeResult&) {
                             EXPECT_TRUE(rt.setLightIntensity("lamp", 3.5f));
                           });
  }
  {
    scenes::Scene e = scene;
    e.lights[0].bounceIntensity = 2.5f;
    expectRelitEqualsFresh("cornell: bounce intensity", base, e, options,
                           [](runtime::Runtime& rt, const BakeResult&) {
                             EXPECT_TRUE(rt.setBounceIntensity("lamp", 2.5f));
                           });
  }
  {
    scenes::Scene e = scene;
    e.lights[0].intensity = 0.0f;  // a fresh bake with the light off
    expectRelitEqualsFresh("cornell: light disabled", base, e, options,
                           [](runtime::Runtime& rt, const BakeResult&) {
                             EXPECT_TRUE(rt.setLightEnabled("lamp", false));
                           });
  }
  {
    const int m = materialNamed(scene, "leftWall");
    ASSERT_GE(m, 0);
    scenes::Scene e = scene;
    e.materials[size_t(m)].baseColorFactor = glm::vec4(0.1f, 0.6f, 0.9f, 1.0f);
    // The runtime takes the diffuse albedo the bake derives from the material.
    expectRelitEqualsFresh("cornell: albedo", base, e, options,
                           [m](runtime::Runtime& rt, const BakeResult& fresh) {
                             EXPECT_TRUE(rt.setAlbedo(m, fresh.transport.materials[size_t(m)].albedo));
                           });
  }
  {
    const int m = materialNamed(scene, "Light");
    ASSERT_GE(m, 0);
    ASSERT_NE(scene.materials[size_t(m)].emissiveFactor, glm::vec3(0.0f));
    scenes::Scene e = scene;
    e.materials[size_t(m)].emissiveFactor *= glm::vec3(0.3f, 1.0f, 2.0f);
    expectRelitEqualsFresh("cornell: emission", base, e, options,
                           [m](runtime::Runtime& rt, const BakeResult& fresh) {
                             EXPECT_TRUE(rt.setEmission(m, fresh.transport.materials[size_t(m)].emission));
                           });
  }
  {
    BakeOptions sky = options;
    sky.skyColor = glm::vec3(0.4f, 0.6f, 1.2f);
    expectRelitEqualsFresh("cornell: sky", base, scene, sky,
                           [](runtime::Runtime& rt, const BakeResult&) {
                             EXPECT_TRUE(rt.setSky(glm::vec3(0.4f, 0.6f, 1.2f)));
                           });
  }
}

TEST(Relight, CornellRelitEqualsAFreshBake) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  expectCornellRelitEqualsFresh(path, false);
}

TEST(Relight, CornellOnAnIndirectGridRelitEqualsAFreshBake) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  expectCornellRelitEqualsFresh(path, true);
}

// Sponza with its sun at a small resolution: every change a level designer makes to a sun.
TEST(Relight, SponzaSunRelitEqualsAFreshBake) {
  AG_REQUIRE_SHARED_SCENE(path, "sponza/Sponza-sun.gltf");
  const scenes::Scene scene = loadSmall(path, 256);
  ASSERT_EQ(scene.lights.size(), 1u);
  const BakeOptions options = fastOptions();
  const BakeResult base = bakeOrDie(scene, options);
  ASSERT_FALSE(base.lightmaps.empty());
  {
    scenes::Scene e = scene;
    e.lights[0].color = glm::vec3(1.0f, 0.45f, 0.2f);
    e.lights[0].intensity *= 0.5f;
    const float intensity = e.lights[0].intensity;
    expectRelitEqualsFresh("sponza: sun colour and intensity", base, e, options,
                           [intensity](runtime::Runtime& rt, const BakeResult&) {
                             EXPECT_TRUE(rt.setLightColor(0, glm::vec3(1.0f, 0.45f, 0.2f)));
                             EXPECT_TRUE(rt.setLightIntensity(0, intensity));
                           });
  }
  {
    scenes::Scene e = scene;
    e.lights[0].bounceIntensity = 3.0f;
    expectRelitEqualsFresh("sponza: bounce intensity", base, e, options,
                           [](runtime::Runtime& rt, const BakeResult&) {
                             EXPECT_TRUE(rt.setBounceIntensity(0, 3.0f));
                           });
  }
  {
    scenes::Scene e = scene;
    e.lights[0].intensity = 0.0f;
    BakeOptions sky = options;  // something must still light the level
    sky.skyColor = glm::vec3(0.3f, 0.5f, 1.0f);
    expectRelitEqualsFresh("sponza: sun off, sky on", base, e, sky,
                           [](runtime::Runtime& rt, const BakeResult&) {
                             EXPECT_TRUE(rt.setLightEnabled(0, false));
                             EXPECT_TRUE(rt.setSky(glm::vec3(0.3f, 0.5f, 1.0f)));
                           });
  }
  {
    // The fabric hangings: big, coloured, and lit by the sun.
    int m = -1;
    for (size_t i = 0; i < scene.materials.size() && m < 0; ++i)
      if (scene.materials[i].name.rfind("Fabric", 0) == 0) m = int(i);
    ASSERT_GE(m, 0);
    scenes::Scene e = scene;
    e.materials[size_t(m)].baseColorFactor = glm::vec4(0.2f, 0.9f, 0.3f, 1.0f);
    expectRelitEqualsFresh("sponza: albedo", base, e, options,
                           [m](runtime::Runtime& rt, const BakeResult& fresh) {
                             EXPECT_TRUE(rt.setAlbedo(m, fresh.transport.materials[size_t(m)].albedo));
                           });
  }
}

// Linearity: every light scaled by k scales every texel by k; two single-light solves sum to
// the two-light solve (the Cornell box's lamp material and the added point light).
TEST(Relight, LinearInTheLights) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  scenes::Scene scene = loadSmall(path, 64);
  ASSERT_FALSE(scene.meshes.empty());
  scenes::Light lamp;
  lamp.name = "lamp";
  lamp.type = scenes::LightType::Point;
  lamp.position = glm::vec3(0.3f, 1.0f, -0.2f);
  lamp.intensity = 1.5f;
  scene.lights.push_back(lamp);
  const BakeResult base = bakeOrDie(scene, fastOptions());
  std::string error;
  auto solve = [&](float lampScale, float emissionScale) {
    std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::fromData(base.transport, &error);
    EXPECT_TRUE(rt) << error;
    std::vector<glm::vec3> texels(size_t(rt->texelCount()));
    if (!rt) return texels;
    rt->setLightIntensity(0, 1.5f * lampScale);
    for (int m = 0; m < rt->materialCount(); ++m)
      if (rt->canSetEmission(m)) rt->setEmission(m, rt->emission(m) * emissionScale);
    runtime::UpdateOptions u;
    u.fromScratch = true;
    u.tolerance = 1e-7f;  // converged well below the comparison's tolerance
    rt->update(u);
    rt->readTexels(texels.data());
    return texels;
  };
  const std::vector<glm::vec3> both = solve(1.0f, 1.0f), scaled = solve(3.0f, 3.0f);
  const std::vector<glm::vec3> lampOnly = solve(1.0f, 0.0f), emissionOnly = solve(0.0f, 1.0f);
  double peak = 0.0;
  for (const glm::vec3& v : both) peak = std::max(peak, double(std::max({v.x, v.y, v.z})));
  ASSERT_GT(peak, 0.0);
  for (size_t t = 0; t < both.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const double tolerance = 1e-5 * std::max(double(both[t][k]), 1e-3 * peak);
      EXPECT_NEAR(scaled[t][k], 3.0 * both[t][k], 3.0 * tolerance) << "texel " << t;
      EXPECT_NEAR(lampOnly[t][k] + emissionOnly[t][k], both[t][k], tolerance) << "texel " << t;
    }
}

}  // namespace
}  // namespace afterglow::baker
