// `afterglow relight` run as a user would: a relit sky equals a bake with that sky, file for
// file; relit light probes and reflection probes equal a fresh bake's; bad names and folders
// are refused with a message naming them and nothing written; the relit folder renders.
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/bakefiles/cube_exr.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"
#include "test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::test {
namespace {

std::vector<float> readExr(const std::string& path) {
  std::vector<float> pixels;
  auto in = OIIO::ImageInput::open(path);
  if (!in) return pixels;
  pixels.resize(size_t(in->spec().width) * size_t(in->spec().height) * 3);
  if (!in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, pixels.data())) pixels.clear();
  return pixels;
}

const char* kBake = "--quality draft --texels-per-unit 32 --quiet";

TEST(CliRelight, RelitSkyEqualsABakeWithThatSky) {
  const std::string dir = tempDir("cli_relight_sky");
  CliRun bake = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' " + kBake);
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  ASSERT_TRUE(fs::exists(dir + "/out/transport.agt"));
  CliRun sky = runCli(dir, "bake builtin:cornell -o '" + dir + "/sky' --sky 0.5,0.7,1.4 " + kBake);
  ASSERT_EQ(sky.exitCode, 0) << sky.err;
  CliRun relit = runCli(dir, "relight '" + dir + "/out' --sky 0.5,0.7,1.4 -o '" + dir + "/relit'");
  ASSERT_EQ(relit.exitCode, 0) << relit.err;
  EXPECT_NE(relit.out.find("bounces"), std::string::npos) << relit.out;

  const std::vector<float> want = readExr(dir + "/sky/lightmaps/lightmap0.exr");
  const std::vector<float> got = readExr(dir + "/relit/lightmaps/lightmap0.exr");
  const std::vector<float> before = readExr(dir + "/out/lightmaps/lightmap0.exr");
  ASSERT_FALSE(want.empty());
  EXPECT_EQ(got, want);     // the same half floats
  EXPECT_NE(before, want);  // and the sky did change them
  EXPECT_TRUE(fs::exists(dir + "/relit/lightmaps/lightmap0.png"));

  // The relit folder is a baked scene to render, lit by the new sky in its report.
  const json report = json::parse(slurp(dir + "/relit/report.json"));
  const json skyRecorded = report.at("settings").at("sky");
  ASSERT_EQ(skyRecorded.size(), 3u);
  EXPECT_NEAR(skyRecorded[1].get<double>(), 0.7, 1e-6);
  EXPECT_EQ(report.at("relight").at("changes").size(), 1u);
  CliRun render = runCli(dir, "render '" + dir + "/relit/scene.gltf' --camera Camera --width 32 "
                           "--height 24 -o '" + dir + "/view.png' --quiet");
  EXPECT_EQ(render.exitCode, 0) << render.err;
  EXPECT_TRUE(fs::exists(dir + "/view.png"));
}

// A relit albedo is the bounce albedo itself, and RELIT/scene.gltf carries the base colour that
// gives it (the Cornell box's materials are rough dielectrics: albedo = 0.96 base + 0.02), so
// baking the relit scene gives the relit lightmaps. White's 0.99 needs a base colour above 1:
// the material is written Lambertian (metallic 0, specularFactor 0), base colour = albedo.
TEST(CliRelight, RelitAlbedoEqualsABakeOfTheRelitScene) {
  const std::string dir = tempDir("cli_relight_albedo");
  CliRun bake = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' " + kBake);
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  // Lit by the sky alone: the lamp's penumbra samples are seeded by its material index, which
  // differs in a bake of a baked glTF (its lightmapped copies of the materials come after the
  // originals), and that noise, not the albedo, would tell the two apart.
  const std::string sky = " --sky 0.5,0.7,1.4 ";
  CliRun relit = runCli(dir, "relight '" + dir + "/out' --albedo red=0.2,0.5,0.8 --albedo "
                             "white=0.99,0.99,0.99 --emission light=0,0,0" + sky + "-o '" + dir +
                             "/relit'");
  ASSERT_EQ(relit.exitCode, 0) << relit.err;
  EXPECT_NE(relit.out.find("'white'"), std::string::npos) << relit.out;
  EXPECT_NE(relit.out.find("Lambertian"), std::string::npos) << relit.out;
  CliRun rebake = runCli(dir, "bake '" + dir + "/relit/scene.gltf' -o '" + dir + "/rebake'" + sky + kBake);
  ASSERT_EQ(rebake.exitCode, 0) << rebake.err;

  const std::vector<float> want = readExr(dir + "/rebake/lightmaps/lightmap0.exr");
  const std::vector<float> got = readExr(dir + "/relit/lightmaps/lightmap0.exr");
  const std::vector<float> before = readExr(dir + "/out/lightmaps/lightmap0.exr");
  ASSERT_FALSE(want.empty());
  EXPECT_EQ(got, want);     // the same half floats
  EXPECT_NE(before, want);  // and the albedo did change them

  // Every glTF material of red (the original and its lightmapped copies) has the inverted base
  // colour and keeps its alpha; white's are Lambertian.
  const json gltf = json::parse(slurp(dir + "/relit/scene.gltf"));
  int reds = 0, whites = 0;
  for (const json& m : gltf.at("materials")) {
    const std::string name = m.value("name", std::string());
    const json& pbr = m.at("pbrMetallicRoughness");
    const json& base = pbr.at("baseColorFactor");
    ASSERT_EQ(base.size(), 4u) << name;
    EXPECT_EQ(base[3].get<double>(), 1.0) << name;
    if (name.rfind("red", 0) == 0) {
      ++reds;
      const double v[3] = {0.2, 0.5, 0.8};
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(base[size_t(c)].get<double>(), (v[c] - 0.02) / 0.96, 1e-6) << name;
      EXPECT_EQ(pbr.value("metallicFactor", 1.0), 0.0) << name;
      EXPECT_FALSE(m.contains("extensions") && m["extensions"].contains("KHR_materials_specular"))
          << name;
    } else if (name.rfind("white", 0) == 0) {
      ++whites;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(base[size_t(c)].get<double>(), 0.99, 1e-6) << name;
      EXPECT_EQ(pbr.value("metallicFactor", 1.0), 0.0) << name;
      EXPECT_EQ(m.at("extensions").at("KHR_materials_specular").at("specularFactor").get<double>(),
                0.0) << name;
    }
  }
  EXPECT_EQ(reds, 2);
  EXPECT_EQ(whites, 2);
  const json used = gltf.at("extensionsUsed");
  EXPECT_NE(std::find(used.begin(), used.end(), "KHR_materials_specular"), used.end());
}

// The light probes' done-when through the CLI: relighting a bake with a light's colour changed
// writes RELIT/probes/ whose SH equal those of a fresh bake of the scene with that colour. The
// Cornell box gets a point light (the built-in box has only its emissive lamp, and `bake` takes
// no light colour), written as glTF twice, differing in that colour alone, so both bakes trace
// the very same rays.
TEST(CliRelight, RelitProbesEqualAFreshBakesProbes) {
  const std::string dir = tempDir("cli_relight_probes");
  scenes::Scene scene = scenes::makeCornellBox();
  scenes::Light lamp;
  lamp.name = "lamp";
  lamp.type = scenes::LightType::Point;
  lamp.position = glm::vec3(0.15f, 0.4f, 0.3f);
  lamp.radius = 0.02f;
  lamp.intensity = 0.5f;
  lamp.color = glm::vec3(1.0f, 0.8f, 0.6f);
  scene.lights.push_back(lamp);
  ASSERT_TRUE(scenes::saveGltf(scene, dir + "/warm/lamp.gltf"));
  scene.lights.back().color = glm::vec3(0.2f, 0.5f, 1.0f);
  ASSERT_TRUE(scenes::saveGltf(scene, dir + "/blue/lamp.gltf"));

  CliRun bake = runCli(dir, "bake '" + dir + "/warm/lamp.gltf' -o '" + dir + "/out' " + kBake);
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  CliRun fresh = runCli(dir, "bake '" + dir + "/blue/lamp.gltf' -o '" + dir + "/fresh' " + kBake);
  ASSERT_EQ(fresh.exitCode, 0) << fresh.err;
  CliRun relit = runCli(dir, "relight '" + dir + "/out' --light lamp=0.2,0.5,1.0 -o '" + dir +
                             "/relit'");
  ASSERT_EQ(relit.exitCode, 0) << relit.err;
  EXPECT_NE(relit.out.find("light probes"), std::string::npos) << relit.out;

  auto readSh = [](const std::string& path) {
    runtime::ProbeShFile file;
    std::string error;
    EXPECT_TRUE(runtime::readProbeSh(path, file, &error)) << error;
    return file.sh;
  };
  const std::vector<runtime::ShL2> want = readSh(dir + "/fresh/probes/light_probes_sh.bin");
  const std::vector<runtime::ShL2> got = readSh(dir + "/relit/probes/light_probes_sh.bin");
  const std::vector<runtime::ShL2> before = readSh(dir + "/out/probes/light_probes_sh.bin");
  ASSERT_GT(want.size(), 100u);
  ASSERT_EQ(got.size(), want.size());
  ASSERT_EQ(before.size(), want.size());
  // Per coefficient, relative to the probe's largest (its own small coefficients are rounding).
  auto worst = [](const std::vector<runtime::ShL2>& a, const std::vector<runtime::ShL2>& b) {
    double out = 0.0;
    for (size_t p = 0; p < a.size(); ++p) {
      double scale = 1e-30;
      for (const glm::vec3& c : b[p].c)
        for (int k = 0; k < 3; ++k) scale = std::max(scale, double(std::abs(c[k])));
      for (int i = 0; i < runtime::kShCount; ++i)
        for (int k = 0; k < 3; ++k)
          out = std::max(out, std::abs(double(a[p].c[i][k]) - double(b[p].c[i][k])) / scale);
    }
    return out;
  };
  const double diff = worst(got, want), changed = worst(before, want);
  std::printf("relit probes vs a fresh bake's: max relative difference %.2e (the change itself: "
              "%.2f)\n", diff, changed);
  EXPECT_LE(diff, 1e-5);
  EXPECT_GT(changed, 0.01);  // the colour did change them

  // The placement is OUT's, its settings noting the relight.
  const json outProbes = json::parse(slurp(dir + "/out/probes/light_probes.json"));
  const json relitProbes = json::parse(slurp(dir + "/relit/probes/light_probes.json"));
  for (const char* key : {"format", "positions", "kinds", "tetrahedra", "neighbours", "sh"})
    EXPECT_EQ(relitProbes.at(key), outProbes.at(key)) << key;
  const json& note = relitProbes.at("settings").at("relight");
  ASSERT_EQ(note.at("changes").size(), 1u);
  EXPECT_EQ(note["changes"][0].at("light"), "lamp");
  EXPECT_EQ(json::parse(slurp(dir + "/relit/report.json")).at("relight").at("probes"),
            want.size());
}

// The reflection probes' done-when through the CLI: a level with two reflection probes (the
// metal Cornell box, its front left open so the sky lights it, with a point light), baked with a
// warm light and one sky, relit with a blue light and another sky, equals a fresh bake of the
// level with that light and sky: every cubemap file (the sky's and both probes', every mip),
// dfg.exr, reflection_probes.json and the sky's EXT_lights_image_based in scene.gltf. The two
// glTFs differ in the light's colour alone, so both bakes trace the very same rays.
scenes::Scene reflectionLevel(glm::vec3 lampColor) {
  scenes::Scene scene = scenes::makeCornellMetalBox();
  // Open the front again (makeCornellMetalBox closes it last) so the sky reaches in.
  EXPECT_EQ(scene.instances.back().name, "front_wall");
  scene.instances.pop_back();
  scene.meshes.pop_back();
  // Small probes keep the test fast: the room's (authored box) and a fitted one by the mirror.
  EXPECT_EQ(scene.reflectionProbes.size(), 1u);
  scene.reflectionProbes[0].resolution = 16;
  scenes::ReflectionProbe fitted = scene.reflectionProbes[0];
  fitted.name = "corner_probe";
  fitted.size = glm::vec3(0.0f);  // fitted to the walls by the bake
  fitted.resolution = 32;
  fitted.importance = 2;
  fitted.transform[3] = glm::vec4(0.15f, 0.35f, 0.4f, 1.0f);
  scene.reflectionProbes.push_back(fitted);
  scenes::Light lamp;
  lamp.name = "lamp";
  lamp.type = scenes::LightType::Point;
  lamp.position = glm::vec3(0.35f, 0.4f, 0.25f);
  lamp.radius = 0.02f;
  lamp.intensity = 0.5f;
  lamp.color = lampColor;
  scene.lights.push_back(lamp);
  return scene;
}

// Per texel of two cube files' every mip: how many differ and by how many half-float steps at
// most (the files are half floats: a value read back is exactly a half).
struct CubeDiff {
  size_t values = 0, differ = 0;
  int worstSteps = 0;
};
CubeDiff compareCubes(const std::vector<runtime::Cubemap>& a, const std::vector<runtime::Cubemap>& b) {
  CubeDiff d;
  EXPECT_EQ(a.size(), b.size());
  for (size_t m = 0; m < std::min(a.size(), b.size()); ++m) {
    EXPECT_EQ(a[m].size, b[m].size) << "mip " << m;
    if (a[m].texels.size() != b[m].texels.size()) continue;
    for (size_t t = 0; t < a[m].texels.size(); ++t)
      for (int c = 0; c < 3; ++c, ++d.values) {
        const uint16_t x = runtime::floatToHalf(a[m].texels[t][c]);
        const uint16_t y = runtime::floatToHalf(b[m].texels[t][c]);
        if (x == y) continue;
        ++d.differ;
        // Non-negative halves order as their bits do.
        d.worstSteps = std::max(d.worstSteps, std::abs(int(x) - int(y)));
      }
  }
  return d;
}

std::vector<runtime::Cubemap> readCube(const std::string& path) {
  Result<std::vector<runtime::Cubemap>> cube = bakefiles::readCubemapExr(path);
  EXPECT_TRUE(cube) << cube.message();
  return cube ? std::move(cube.value()) : std::vector<runtime::Cubemap>();
}

// The scene.gltf's EXT_lights_image_based lights.
json imageBasedLights(const std::string& gltfPath) {
  const json gltf = json::parse(slurp(gltfPath));
  return gltf.at("extensions").at("EXT_lights_image_based").at("lights");
}

TEST(CliRelight, RelitReflectionProbesEqualAFreshBakes) {
  const std::string dir = tempDir("cli_relight_reflections");
  ASSERT_TRUE(scenes::saveGltf(reflectionLevel({1.0f, 0.8f, 0.6f}), dir + "/warm/level.gltf"));
  ASSERT_TRUE(scenes::saveGltf(reflectionLevel({0.2f, 0.5f, 1.0f}), dir + "/blue/level.gltf"));
  const std::string newSky = "0.5,0.7,1.4";
  CliRun bake = runCli(dir, "bake '" + dir + "/warm/level.gltf' -o '" + dir +
                            "/out' --sky 0.2,0.2,0.3 " + kBake);
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  CliRun fresh = runCli(dir, "bake '" + dir + "/blue/level.gltf' -o '" + dir + "/fresh' --sky " +
                             newSky + " " + kBake);
  ASSERT_EQ(fresh.exitCode, 0) << fresh.err;
  CliRun relit = runCli(dir, "relight '" + dir + "/out' --light lamp=0.2,0.5,1.0 --sky " + newSky +
                             " -o '" + dir + "/relit'");
  ASSERT_EQ(relit.exitCode, 0) << relit.err;
  EXPECT_NE(relit.out.find("2 reflection probes"), std::string::npos) << relit.out;

  // Every cube file, every mip: the relight's equals the fresh bake's, and the change did
  // change them.
  for (const char* file : {"reflection_sky.exr", "reflection_1.exr", "reflection_2.exr"}) {
    SCOPED_TRACE(file);
    const std::vector<runtime::Cubemap> want = readCube(dir + "/fresh/probes/" + file);
    const std::vector<runtime::Cubemap> got = readCube(dir + "/relit/probes/" + file);
    const std::vector<runtime::Cubemap> before = readCube(dir + "/out/probes/" + file);
    ASSERT_FALSE(want.empty());
    const CubeDiff diff = compareCubes(got, want);
    const CubeDiff change = compareCubes(before, want);
    std::printf("%s: relit vs fresh bake %zu of %zu half floats differ (at most %d steps); the "
                "change itself altered %zu\n", file, diff.differ, diff.values, diff.worstSteps,
                change.differ);
    EXPECT_EQ(diff.differ, 0u);
    EXPECT_GT(change.differ, diff.values / 2);
  }
  // The DFG table's pixels (the files differ in their capDate).
  const std::vector<float> dfg = readExr(dir + "/relit/probes/dfg.exr");
  EXPECT_EQ(dfg.size(), size_t(runtime::kDfgSize * runtime::kDfgSize * 3));
  EXPECT_TRUE(dfg == readExr(dir + "/fresh/probes/dfg.exr"));
  EXPECT_EQ(json::parse(slurp(dir + "/relit/probes/reflection_probes.json")),
            json::parse(slurp(dir + "/fresh/probes/reflection_probes.json")));

  // The glTF's sky: one light, the relit sky's coefficients and specular faces (the same PNGs
  // as the fresh bake's), its images in RELIT/probes/, not OUT's.
  const json relitLights = imageBasedLights(dir + "/relit/scene.gltf");
  const json freshLights = imageBasedLights(dir + "/fresh/scene.gltf");
  ASSERT_EQ(relitLights.size(), 1u);
  ASSERT_EQ(freshLights.size(), 1u);
  EXPECT_EQ(relitLights[0].at("irradianceCoefficients"), freshLights[0].at("irradianceCoefficients"));
  EXPECT_NE(relitLights[0].at("irradianceCoefficients"),
            imageBasedLights(dir + "/out/scene.gltf")[0].at("irradianceCoefficients"));
  const json relitGltf = json::parse(slurp(dir + "/relit/scene.gltf"));
  size_t faces = 0;
  for (const json& mip : relitLights[0].at("specularImages"))
    for (const json& face : mip) {
      const std::string uri = relitGltf.at("images").at(face.get<size_t>()).at("uri");
      ASSERT_EQ(uri.rfind("probes/sky_specular_", 0), 0u) << uri;
      EXPECT_TRUE(slurp(dir + "/relit/" + uri) == slurp(dir + "/fresh/" + uri)) << uri;
      ++faces;
    }
  EXPECT_EQ(faces, 7u * 6u);  // the 64² sky: 7 mips of 6 faces
  // The level's other images (the lightmaps) are still there and still found.
  for (const json& image : relitGltf.at("images")) {
    const std::string uri = image.at("uri");
    EXPECT_TRUE(fs::exists(fs::path(dir) / "relit" / uri)) << uri;
  }
  const json report = json::parse(slurp(dir + "/relit/report.json"));
  EXPECT_EQ(report.at("relight").at("reflectionProbes"), 2);  // the level's, the sky besides
  EXPECT_EQ(report.at("relight").at("reflectionPasses"), 4);  // (1 bounce + 1) × 2 probes

  // And the relit folder renders with its relit reflections.
  CliRun render = runCli(dir, "render '" + dir + "/relit/scene.gltf' --camera Camera --width 32 "
                              "--height 24 -o '" + dir + "/view.png' --quiet");
  EXPECT_EQ(render.exitCode, 0) << render.err;
}

TEST(CliRelight, BadNamesAndFoldersAreRefusedAndWriteNothing) {
  const std::string dir = tempDir("cli_relight_errors");
  CliRun bake = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' " + kBake);
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  const std::string out = "'" + dir + "/out'", relit = " -o '" + dir + "/relit'";

  CliRun light = runCli(dir, "relight " + out + " --light sun=1,0,0" + relit);
  EXPECT_EQ(light.exitCode, 2);
  EXPECT_NE(light.err.find("no light 'sun'"), std::string::npos) << light.err;

  CliRun material = runCli(dir, "relight " + out + " --albedo Nope=1,0,0" + relit);
  EXPECT_EQ(material.exitCode, 2);
  EXPECT_NE(material.err.find("no material 'Nope'"), std::string::npos) << material.err;
  EXPECT_NE(material.err.find("materials: "), std::string::npos) << material.err;

  // The white wall was not emissive when baked: its emission was never traced.
  CliRun emission = runCli(dir, "relight " + out + " --emission '#0=1,1,1'" + relit);
  EXPECT_EQ(emission.exitCode, 2);
  EXPECT_NE(emission.err.find("not emissive"), std::string::npos) << emission.err;

  CliRun malformed = runCli(dir, "relight " + out + " --sky 1,2" + relit);
  EXPECT_EQ(malformed.exitCode, 2);

  CliRun missing = runCli(dir, "relight '" + dir + "/nowhere'" + relit);
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_NE(missing.err.find("nowhere"), std::string::npos) << missing.err;

  // A damaged transport file: the error names it.
  fs::create_directories(dir + "/broken");
  for (const char* f : {"report.json", "scene.gltf", "scene.bin"})
    fs::copy_file(dir + "/out/" + f, dir + "/broken/" + f);
  std::string bytes = slurp(dir + "/out/transport.agt");
  bytes.resize(bytes.size() / 2);
  std::ofstream(dir + "/broken/transport.agt", std::ios::binary) << bytes;
  CliRun broken = runCli(dir, "relight '" + dir + "/broken'" + relit);
  EXPECT_EQ(broken.exitCode, 1);
  EXPECT_NE(broken.err.find("transport.agt"), std::string::npos) << broken.err;

  EXPECT_FALSE(fs::exists(dir + "/relit"));
}

}  // namespace
}  // namespace afterglow::test
