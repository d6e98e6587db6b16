// How bright `afterglow render`'s picture is and why (preview/exposure.h): the lights' scale of
// each kind of source, the exposure printed in stops and as a scale (chosen, or --exposure),
// and the warning for lightmaps that are essentially black: a closed room lit by a sky only
// gets it, a normal bake does not.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "afterglow/core/math.h"
#include "afterglow/preview/exposure.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::test {
namespace {

// A 2 m static box (reach 1 m) and nothing lighting it.
scenes::Scene darkBox() {
  scenes::Scene scene;
  scene.materials.emplace_back();
  baker::addBox(scene, "box", glm::vec3(0.0f), glm::vec3(2.0f), 0);
  return scene;
}

TEST(RenderBrightness, TheLightsScaleIsTheBrightestSourceAcrossTheLevel) {
  scenes::Scene scene = darkBox();
  baker::Environment none;
  EXPECT_EQ(preview::lightsScale(scene, none), 0.0f);
  scenes::Light sun;
  sun.type = scenes::LightType::Directional;
  sun.intensity = 10.0f;
  scene.lights.push_back(sun);
  EXPECT_NEAR(preview::lightsScale(scene, none), 10.0 / kPiDouble, 1e-5);
  scenes::Light lamp;  // a point light, 1 m away: 100 cd / (π m²)
  lamp.intensity = 100.0f;
  lamp.color = glm::vec3(1.0f, 0.0f, 0.0f);  // its luminance: 0.2126 of it
  scene.lights.push_back(lamp);
  EXPECT_NEAR(preview::lightsScale(scene, none), 21.26 / kPiDouble, 1e-4);
  // A sky of radiance 50 gives E/π = 50 to a surface facing it.
  baker::Environment sky;
  runtime::constantSkySh(glm::vec3(50.0f), sky.skySh);
  EXPECT_NEAR(preview::lightsScale(scene, sky), 50.0f, 1e-3f);
  // An emitter: its radiance × its area (the box's six 4 m² faces) / (π reach²), at most its
  // radiance.
  scene.lights.clear();
  scene.materials[0].emissiveFactor = glm::vec3(0.01f);
  EXPECT_NEAR(preview::lightsScale(scene, none), 0.01f, 1e-6f);
  scene.materials[0].emissiveFactor = glm::vec3(0.0f);
  scene.materials.emplace_back().emissiveFactor = glm::vec3(1000.0f);
  baker::addBox(scene, "led", glm::vec3(1.0f), glm::vec3(1.001f), 1);
  EXPECT_NEAR(preview::lightsScale(scene, none), 1000.0 * 6e-6 / kPiDouble, 1e-5);
}

TEST(RenderBrightness, BlackLightmapsAreWarnedAboutUnderALitLevel) {
  scenes::Scene scene = darkBox();
  baker::Environment sky;
  runtime::constantSkySh(glm::vec3(1.0f), sky.skySh);
  bakefiles::LightmapImage black;
  black.width = black.height = 100;
  black.pixels.assign(10000, glm::vec3(0.0f));
  black.pixels[7] = glm::vec3(0.5f);  // a leak: under 1% of the texels
  EXPECT_EQ(preview::lightmapQuantile({black}, 0.99), 0.0f);
  const std::string warning = preview::blackLightmapsWarning(scene, {black}, sky, "room.gltf");
  EXPECT_EQ(warning.rfind("room.gltf: the lightmaps are essentially black", 0), 0u) << warning;
  EXPECT_EQ(warning.find('\n'), std::string::npos);
  // Lit at 1e-3 of the sky: dark, but light.
  bakefiles::LightmapImage dim = black;
  for (glm::vec3& t : dim.pixels) t = glm::vec3(1e-3f);
  EXPECT_EQ(preview::blackLightmapsWarning(scene, {dim}, sky, "room.gltf"), "");
  // Nothing lights it at all.
  EXPECT_NE(preview::blackLightmapsWarning(scene, {black}, baker::Environment(), "room.gltf")
                .find("no light, emissive surface or sky"),
            std::string::npos);
}

TEST(RenderBrightness, ExposuresArePrintedInStopsAndAsAScale) {
  const preview::Exposure given = preview::chooseExposure({glm::vec3(1.0f)}, 1.0f);
  EXPECT_EQ(given.scale, 2.0f);
  EXPECT_EQ(preview::describeExposure(given), "+1.00 stops (x2), from --exposure");
  // Automatic: the 99th percentile (luminance 0.5 here) maps to 0.8 after x / (1 + x).
  const preview::Exposure automatic =
      preview::chooseExposure(std::vector<glm::vec3>(10, glm::vec3(0.5f)), std::nanf(""));
  EXPECT_TRUE(automatic.automatic);
  EXPECT_NEAR(automatic.scale, 8.0f, 1e-5f);
  EXPECT_NEAR(automatic.stops, 3.0f, 1e-5f);
  EXPECT_EQ(preview::describeExposure(automatic).rfind("+3.00 stops (x8), automatic", 0), 0u);
}

TEST(RenderBrightness, AClosedRoomUnderASkyIsWarnedAboutAndALitBakeIsNot) {
  const std::string dir = tempDir("cli_render_brightness");
  scenes::FurnaceOptions closed;
  closed.emission = glm::vec3(0.0f);
  ASSERT_TRUE(scenes::saveGltf(scenes::makeFurnaceBox(closed), dir + "/room/room.gltf"));
  const std::string draft = " --quality draft --texels-per-unit 16 --quiet";
  CliRun bake = runCli(dir, "bake '" + dir + "/room/room.gltf' -o '" + dir + "/dark' --sky 1,1,1" +
                                draft);
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  CliRun dark = runCli(dir, "render '" + dir + "/dark/scene.gltf' -o '" + dir +
                                "/dark.png' --width 64 --height 48");
  ASSERT_EQ(dark.exitCode, 0) << dark.err;
  EXPECT_NE(dark.out.find("exposure      "), std::string::npos) << dark.out;
  EXPECT_NE(dark.out.find("warning       " + dir + "/dark/scene.gltf: the lightmaps are "
                          "essentially black"),
            std::string::npos)
      << dark.out;

  bake = runCli(dir, "bake builtin:cornell -o '" + dir + "/lit'" + draft);
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  CliRun lit = runCli(dir, "render '" + dir + "/lit/scene.gltf' -o '" + dir +
                               "/lit.png' --width 64 --height 48");
  ASSERT_EQ(lit.exitCode, 0) << lit.err;
  EXPECT_NE(lit.out.find("automatic: the 99th percentile"), std::string::npos) << lit.out;
  EXPECT_EQ(lit.out.find("warning"), std::string::npos) << lit.out;
  CliRun given = runCli(dir, "render '" + dir + "/lit/scene.gltf' -o '" + dir +
                                 "/given.png' --width 64 --height 48 --exposure -1.5");
  ASSERT_EQ(given.exitCode, 0) << given.err;
  EXPECT_NE(given.out.find("exposure      -1.50 stops (x0.3536), from --exposure"),
            std::string::npos)
      << given.out;
  // A linear EXR has no exposure.
  CliRun exr = runCli(dir, "render '" + dir + "/lit/scene.gltf' -o '" + dir +
                               "/lit.exr' --width 64 --height 48");
  ASSERT_EQ(exr.exitCode, 0) << exr.err;
  EXPECT_EQ(exr.out.find("exposure"), std::string::npos) << exr.out;
}

}  // namespace
}  // namespace afterglow::test
