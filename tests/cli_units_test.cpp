// A level in millimetres through the CLI: `afterglow info` and `bake` warn about Bevy's Cornell
// box (556 × 549 × 559 units) naming the fix, not about Sponza; `bake --unit-scale 0.001` bakes
// it as the same box modelled in metres bakes (texel density, probes, clusters), records the
// scale in report.json and writes the level in metres; `probes place --unit-scale` places in
// metres too; a scale that is not a positive number is a usage error.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/scenes/gltf.h"
#include "test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::test {
namespace {

const char* kMillimetres = "looks like it is in millimetres";
const char* kFix = "scale its root node by 0.001, or pass --unit-scale 0.001";

TEST(CliUnits, InfoWarnsAboutAMillimetreLevelAndNamesTheFix) {
  AG_REQUIRE_SHARED_SCENE(bevy, "cornell_box_bevy/CornellBox.glb");
  const std::string dir = tempDir("cli_units_info");
  CliRun info = runCli(dir, "info '" + bevy + "'");
  ASSERT_EQ(info.exitCode, 0) << info.err;
  EXPECT_NE(info.out.find(kMillimetres), std::string::npos) << info.out;
  EXPECT_NE(info.out.find(kFix), std::string::npos) << info.out;
  CliRun scaled = runCli(dir, "info '" + bevy + "' --unit-scale 0.001");
  ASSERT_EQ(scaled.exitCode, 0) << scaled.err;
  EXPECT_EQ(scaled.out.find(kMillimetres), std::string::npos) << scaled.out;
  EXPECT_NE(scaled.out.find("size          0.556 x 0.549 x 0.559 m"), std::string::npos)
      << scaled.out;
  CliRun bad = runCli(dir, "info '" + bevy + "' --unit-scale -0.001");
  EXPECT_EQ(bad.exitCode, 2);
  EXPECT_NE(bad.err.find("--unit-scale"), std::string::npos) << bad.err;

  AG_REQUIRE_SHARED_SCENE(sponza, "sponza/Sponza.gltf");
  CliRun metres = runCli(dir, "info '" + sponza + "' --no-textures");
  ASSERT_EQ(metres.exitCode, 0) << metres.err;
  EXPECT_EQ(metres.out.find("looks like it is in"), std::string::npos) << metres.out;
}

// Bevy's box with every vertex and translation in metres, as if modelled so.
std::string boxInMetres(const std::string& bevy, const std::string& dir) {
  Result<scenes::Scene> loaded = scenes::loadGltf(bevy);
  EXPECT_TRUE(loaded) << loaded.message();
  if (!loaded) return "";
  scenes::Scene& scene = loaded.value();
  for (scenes::Mesh& mesh : scene.meshes)
    for (scenes::Primitive& p : mesh.primitives)
      for (glm::vec3& v : p.positions) v *= 0.001f;
  for (scenes::Instance& inst : scene.instances)
    inst.transform[3] = glm::vec4(glm::vec3(inst.transform[3]) * 0.001f, 1.0f);
  const std::string path = dir + "/box_in_metres.gltf";
  const Status saved = scenes::saveGltf(scene, path);
  EXPECT_TRUE(saved) << saved.message();
  return path;
}

TEST(CliUnits, BakeWithUnitScaleBakesTheBoxAsInMetres) {
  AG_REQUIRE_SHARED_SCENE(bevy, "cornell_box_bevy/CornellBox.glb");
  const std::string dir = tempDir("cli_units_bake");
  const std::string metres = boxInMetres(bevy, dir);
  ASSERT_FALSE(metres.empty());
  const std::string options = " --quality draft --quiet";
  CliRun scaled = runCli(dir, "bake '" + bevy + "' --unit-scale 0.001 -o '" + dir + "/scaled'" +
                                  options);
  ASSERT_EQ(scaled.exitCode, 0) << scaled.err;
  CliRun reference = runCli(dir, "bake '" + metres + "' -o '" + dir + "/metres'" + options);
  ASSERT_EQ(reference.exitCode, 0) << reference.err;
  const json a = json::parse(slurp(dir + "/scaled/report.json"));
  const json b = json::parse(slurp(dir + "/metres/report.json"));
  EXPECT_FLOAT_EQ(a["settings"]["unitScale"].get<float>(), 0.001f);
  EXPECT_EQ(b["settings"]["unitScale"].get<float>(), 1.0f);
  EXPECT_EQ(a["settings"]["texelsPerUnit"], b["settings"]["texelsPerUnit"]);
  EXPECT_EQ(a["settings"]["probeSpacing"], b["settings"]["probeSpacing"]);
  const double probes = b["probes"]["count"].get<double>();
  const double clusters = b["clusters"].get<double>();
  EXPECT_NEAR(a["probes"]["count"].get<double>(), probes, 0.02 * probes);
  EXPECT_NEAR(a["clusters"].get<double>(), clusters, 0.02 * clusters);
  // Neither warns: the scaled box is in metres.
  EXPECT_TRUE(a["warnings"].empty()) << a["warnings"];
  EXPECT_TRUE(b["warnings"].empty()) << b["warnings"];

  // The output is the level in metres, its lights, probes and all.
  Result<scenes::Scene> out = scenes::loadGltf(dir + "/scaled/scene.gltf");
  ASSERT_TRUE(out) << out.message();
  EXPECT_NEAR(out->staticBounds().size().z, 0.5592f, 1e-4f);
  const json placed = json::parse(slurp(dir + "/scaled/probes/light_probes.json"));
  for (const json& p : placed["positions"])
    for (size_t k = 0; k < 3; ++k) EXPECT_LT(std::abs(p[k].get<double>()), 0.6) << p;
}

TEST(CliUnits, BakeWithoutTheScaleWarnsAndRecordsIt) {
  AG_REQUIRE_SHARED_SCENE(bevy, "cornell_box_bevy/CornellBox.glb");
  const std::string dir = tempDir("cli_units_warn");
  // Few texels and no probes: the warning is what is looked at.
  CliRun bake = runCli(dir, "bake '" + bevy + "' -o '" + dir + "/out' --quality draft "
                            "--texels-per-unit 0.05 --probes none");
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  EXPECT_NE(bake.out.find("warning       " + bevy + ": the level " + kMillimetres),
            std::string::npos)
      << bake.out;
  const json report = json::parse(slurp(dir + "/out/report.json"));
  ASSERT_EQ(report["warnings"].size(), 1u) << report["warnings"];
  EXPECT_NE(report["warnings"][0].get<std::string>().find(kFix), std::string::npos);
  EXPECT_EQ(report["settings"]["unitScale"].get<float>(), 1.0f);
  CliRun zero = runCli(dir, "bake '" + bevy + "' -o '" + dir + "/zero' --unit-scale 0");
  EXPECT_EQ(zero.exitCode, 2) << zero.err;
  EXPECT_FALSE(fs::exists(dir + "/zero"));
}

TEST(CliUnits, ProbesPlaceScalesTheLevelFirst) {
  AG_REQUIRE_SHARED_SCENE(bevy, "cornell_box_bevy/CornellBox.glb");
  const std::string dir = tempDir("cli_units_place");
  CliRun place = runCli(dir, "probes place '" + bevy + "' --unit-scale 0.001 -o '" + dir +
                                 "/p.json'");
  ASSERT_EQ(place.exitCode, 0) << place.err;
  EXPECT_EQ(place.out.find(kMillimetres), std::string::npos) << place.out;
  const json placed = json::parse(slurp(dir + "/p.json"));
  EXPECT_FLOAT_EQ(placed["settings"]["unitScale"].get<float>(), 0.001f);
  EXPECT_LT(placed["settings"]["spacing"].get<double>(), 0.5);
  for (const json& p : placed["positions"])
    for (size_t k = 0; k < 3; ++k) EXPECT_LT(std::abs(p[k].get<double>()), 0.6) << p;
  CliRun unscaled = runCli(dir, "probes place '" + bevy + "' -o '" + dir + "/q.json'");
  ASSERT_EQ(unscaled.exitCode, 0) << unscaled.err;
  EXPECT_NE(unscaled.out.find(kMillimetres), std::string::npos) << unscaled.out;
  EXPECT_FALSE(json::parse(slurp(dir + "/q.json"))["settings"].contains("unitScale"));
}

}  // namespace
}  // namespace afterglow::test
