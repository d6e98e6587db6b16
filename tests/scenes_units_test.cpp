// A level's unit judged by what it holds (scenes/units.h): a furnished room in metres is in
// metres, the same room ×100 in centimetres and ×1000 in millimetres, a lone 500-unit box in
// millimetres, and each warning names its fix; --unit-scale's scaleScene moves everything the
// level places (lights, cameras, probe volumes, reflection probes) with its geometry, and a
// room scaled back is in metres again. On the shared scenes: Bevy's Cornell box is in
// millimetres, Sponza, the McGuire box, the mixed-lighting room and the gas station in metres.
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/units.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::test {
namespace {

using scenes::LengthUnit;

// A 6 × 3 × 4 m room (its shell one mesh, as architecture is often exported) with a 0.5 m
// wide door, a table, four chairs, a shelf, a lamp and a cup; every length × `scale`.
scenes::Scene furnishedRoom(float scale) {
  scenes::Scene scene;
  scene.materials.emplace_back();
  auto add = [&](const char* name, glm::vec3 lo, glm::vec3 hi) {
    baker::addBox(scene, name, lo * scale, hi * scale, 0);
  };
  add("shell", {0, 0, 0}, {6, 3, 4});
  add("door", {2, 0, 0}, {2.5f, 2, 0.04f});
  add("table", {3, 0, 1.5f}, {4.2f, 0.75f, 2.3f});
  for (int i = 0; i < 4; ++i) {
    const glm::vec3 at(3.0f + 0.6f * float(i % 2), 0.0f, i < 2 ? 1.0f : 2.4f);
    add("chair", at, at + glm::vec3(0.45f, 0.9f, 0.45f));
  }
  add("shelf", {0.1f, 0, 3.6f}, {1.0f, 1.8f, 3.9f});
  add("lamp", {5, 0, 3}, {5.3f, 0.5f, 3.3f});
  add("cup", {3.5f, 0.75f, 1.8f}, {3.58f, 0.85f, 1.88f});
  return scene;
}

TEST(Units, AFurnishedRoomIsJudgedInMetresCentimetresAndMillimetres) {
  const scenes::UnitsGuess metres = scenes::guessUnits(furnishedRoom(1.0f));
  EXPECT_EQ(metres.unit, LengthUnit::Metres);
  EXPECT_EQ(metres.objects, 10u);
  EXPECT_FLOAT_EQ(metres.levelSize, 6.0f);
  EXPECT_EQ(scenes::unitsWarning(metres, "room.gltf"), "");

  const scenes::UnitsGuess cm = scenes::guessUnits(furnishedRoom(100.0f));
  EXPECT_EQ(cm.unit, LengthUnit::Centimetres);
  const std::string cmWarning = scenes::unitsWarning(cm, "room.gltf");
  EXPECT_EQ(cmWarning.rfind("room.gltf: ", 0), 0u) << cmWarning;
  EXPECT_NE(cmWarning.find("in centimetres"), std::string::npos) << cmWarning;
  EXPECT_NE(cmWarning.find("root node by 0.01, or pass --unit-scale 0.01"), std::string::npos)
      << cmWarning;

  const scenes::UnitsGuess mm = scenes::guessUnits(furnishedRoom(1000.0f));
  EXPECT_EQ(mm.unit, LengthUnit::Millimetres);
  const std::string mmWarning = scenes::unitsWarning(mm, "room.gltf");
  EXPECT_NE(mmWarning.find("in millimetres"), std::string::npos) << mmWarning;
  EXPECT_NE(mmWarning.find("--unit-scale 0.001"), std::string::npos) << mmWarning;
  EXPECT_EQ(mmWarning.find('\n'), std::string::npos);
  // The typical object is the same piece of furniture at every scale.
  EXPECT_FLOAT_EQ(cm.typicalSize, 100.0f * metres.typicalSize);
  EXPECT_FLOAT_EQ(mm.typicalSize, 1000.0f * metres.typicalSize);
}

TEST(Units, ALoneBoxOfHundredsOfUnitsIsInMillimetresAndOneOfAFewInMetres) {
  scenes::Scene box;
  box.materials.emplace_back();
  baker::addBox(box, "box", glm::vec3(0.0f), glm::vec3(500.0f), 0);
  EXPECT_EQ(scenes::guessUnits(box).unit, LengthUnit::Millimetres);
  scenes::Scene small;
  small.materials.emplace_back();
  baker::addBox(small, "box", glm::vec3(0.0f), glm::vec3(5.0f), 0);
  EXPECT_EQ(scenes::guessUnits(small).unit, LengthUnit::Metres);
  // Nothing static: nothing to judge, no warning.
  box.instances[0].isStatic = false;
  EXPECT_EQ(scenes::guessUnits(box).unit, LengthUnit::Metres);
  EXPECT_EQ(scenes::guessUnits(box).objects, 0u);
}

TEST(Units, ScalingMovesEverythingTheLevelPlaces) {
  scenes::Scene scene = furnishedRoom(100.0f);
  scenes::Light lamp;
  lamp.position = {500, 250, 300};
  lamp.range = 400;
  lamp.radius = 5;
  lamp.intensity = 80;
  scene.lights.push_back(lamp);
  scenes::Camera camera;
  camera.transform[3] = glm::vec4(300, 160, -200, 1);
  camera.znear = 1;
  camera.xmag = 50;
  scene.cameras.push_back(camera);
  scenes::ProbeVolume volume;
  volume.transform[3] = glm::vec4(300, 150, 200, 1);
  volume.size = {600, 300, 400};
  volume.spacing = 50;
  scene.probeVolumes.push_back(volume);
  scenes::ReflectionProbe probe;
  probe.transform[3] = glm::vec4(300, 150, 200, 1);
  probe.blendDistance = 100;
  scene.reflectionProbes.push_back(probe);

  scenes::scaleScene(scene, 0.01f);
  EXPECT_EQ(scenes::guessUnits(scene).unit, LengthUnit::Metres);
  EXPECT_NEAR(scene.staticBounds().size().x, 6.0f, 1e-5f);
  const scenes::Light& l = scene.lights[0];
  EXPECT_NEAR(glm::length(l.position - glm::vec3(5, 2.5f, 3)), 0.0f, 1e-5f);
  EXPECT_FLOAT_EQ(l.range, 4.0f);
  EXPECT_FLOAT_EQ(l.radius, 0.05f);
  EXPECT_EQ(l.intensity, 80.0f);  // candela do not depend on the unit of length
  const scenes::Camera& c = scene.cameras[0];
  EXPECT_NEAR(glm::length(glm::vec3(c.transform[3]) - glm::vec3(3, 1.6f, -2)), 0.0f, 1e-5f);
  EXPECT_EQ(glm::vec3(c.transform[0]), glm::vec3(1, 0, 0));  // its axes stay unit length
  EXPECT_FLOAT_EQ(c.znear, 0.01f);
  EXPECT_FLOAT_EQ(c.xmag, 0.5f);
  const scenes::ProbeVolume& v = scene.probeVolumes[0];
  EXPECT_NEAR(glm::length(glm::vec3(v.transform * glm::vec4(v.size * 0.5f, 1.0f)) -
                          glm::vec3(6, 3, 4)),
              0.0f, 1e-5f);
  EXPECT_FLOAT_EQ(v.spacing, 0.5f);
  const scenes::ReflectionProbe& r = scene.reflectionProbes[0];
  EXPECT_NEAR(glm::length(glm::vec3(r.transform[3]) - glm::vec3(3, 1.5f, 2)), 0.0f, 1e-5f);
  EXPECT_FLOAT_EQ(r.transform[0][0], 0.01f);
  EXPECT_FLOAT_EQ(r.blendDistance, 1.0f);
}

scenes::Scene sharedLevel(const std::string& path) {
  scenes::LoadOptions options;
  options.loadTextures = false;
  Result<scenes::Scene> scene = scenes::loadGltf(path, options);
  EXPECT_TRUE(scene) << scene.message();
  return scene ? std::move(scene.value()) : scenes::Scene{};
}

TEST(Units, BevysCornellBoxIsInMillimetres) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_bevy/CornellBox.glb");
  const scenes::UnitsGuess guess = scenes::guessUnits(sharedLevel(path));
  EXPECT_EQ(guess.unit, LengthUnit::Millimetres);
  EXPECT_NEAR(guess.levelSize, 559.2f, 0.1f);
  const std::string warning = scenes::unitsWarning(guess, path);
  EXPECT_NE(warning.find("millimetres"), std::string::npos) << warning;
  EXPECT_NE(warning.find("scale its root node by 0.001, or pass --unit-scale 0.001"),
            std::string::npos)
      << warning;
}

// Each in metres; the levels of many objects also read as centimetres ×100 and millimetres
// ×1000 (the McGuire box, one 2 m object, is as plausible a 2 m room in centimetres as a 20 cm
// box in millimetres ×100: it is left out of that).
TEST(Units, SharedLevelsInMetresGetNoWarningAndScaledTheirUnit) {
  const std::pair<const char*, bool> levels[] = {
      {"sponza/Sponza.gltf", true},
      {"sponza/Sponza-sun.gltf", true},
      {"cornell_box_mcguire/CornellBox-Original.gltf", false},
      {"mixed_lighting_bevy/MixedLightingExample.gltf", true},
      {"gas_station/GasStation.gltf", true}};
  for (const auto& [relative, scaled] : levels) {
    AG_REQUIRE_SHARED_SCENE(path, relative);
    scenes::Scene level = sharedLevel(path);
    const scenes::UnitsGuess guess = scenes::guessUnits(level);
    EXPECT_EQ(guess.unit, LengthUnit::Metres) << relative << ": " << guess.typicalSize << " of "
                                              << guess.levelSize;
    EXPECT_EQ(scenes::unitsWarning(guess, path), "");
    if (!scaled) continue;
    scenes::scaleScene(level, 100.0f);
    EXPECT_EQ(scenes::guessUnits(level).unit, LengthUnit::Centimetres) << relative << " x100";
    scenes::scaleScene(level, 10.0f);
    EXPECT_EQ(scenes::guessUnits(level).unit, LengthUnit::Millimetres) << relative << " x1000";
  }
}

}  // namespace
}  // namespace afterglow::test
