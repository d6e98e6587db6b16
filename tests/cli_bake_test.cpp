// `afterglow bake` and `afterglow render` run as a user would: the files a bake writes, the
// memory budget refusal that writes nothing, settings precedence, the rendered picture, and the
// path-traced reference picture it is compared with.
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/baker/bake.h"
#include "afterglow/bakefiles/cube_exr.h"
#include "test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::test {
namespace {

// Every file under dir, relative, sorted.
std::vector<std::string> tree(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) names.push_back(fs::relative(e.path(), dir).generic_string());
  std::sort(names.begin(), names.end());
  return names;
}

// A render PNG's 8-bit RGB, row 0 at the top.
struct Picture {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
  int at(int x, int y, int k) const { return rgb[(size_t(y) * size_t(width) + size_t(x)) * 3 + size_t(k)]; }
};

Picture readPng(const std::string& path) {
  Picture p;
  auto in = OIIO::ImageInput::open(path);
  if (!in) return p;
  p.width = in->spec().width;
  p.height = in->spec().height;
  p.rgb.resize(size_t(p.width) * size_t(p.height) * 3);
  if (!in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, p.rgb.data())) p = Picture();
  return p;
}

// The linear radiance behind one byte of a picture written with `--exposure stops`: undoes the
// sRGB encoding, the Reinhard curve x / (1 + x) and the exposure.
double linearValue(int byte, double stops) {
  const double v = byte / 255.0;
  const double m = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
  return m / (1.0 - m) / std::exp2(stops);
}

// Mean linear radiance (RGB summed) of two pictures of one view, over the pixels where neither
// is near white (≥ 230 in a channel): there, on the lamp, one 8-bit step is several percent of
// the inverse tone curve, and the lamp's emission is the same in both renders anyway.
std::pair<double, double> linearMeans(const Picture& a, const Picture& b, double stops) {
  double sumA = 0.0, sumB = 0.0;
  size_t n = 0;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      bool nearWhite = false;
      for (int k = 0; k < 3; ++k) nearWhite |= a.at(x, y, k) >= 230 || b.at(x, y, k) >= 230;
      if (nearWhite) continue;
      for (int k = 0; k < 3; ++k) {
        sumA += linearValue(a.at(x, y, k), stops);
        sumB += linearValue(b.at(x, y, k), stops);
      }
      ++n;
    }
  }
  return n ? std::make_pair(sumA / double(n), sumB / double(n)) : std::make_pair(0.0, 0.0);
}

// A draft bake of the Cornell box, shared by the tests below that run in one process (each bake
// takes a second). ctest runs every test in a process of its own and two at a time, so the
// folder is named for the test that bakes it: one process must not clear another's bake.
const std::string& bakedCornell() {
  static const std::string out = [] {
    const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::string dir =
        tempDir(std::string("cli_bake_cornell_") + (test ? test->name() : "shared"));
    const std::string o = dir + "/out";
    CliRun r = runCli(dir, "bake builtin:cornell -o '" + o +
                            "' --quality draft --texels-per-unit 48 --quiet");
    EXPECT_EQ(r.exitCode, 0) << r.err;
    return o;
  }();
  return out;
}

TEST(CliBake, CornellWritesLightmapsGltfAndReport) {
  const std::string out = bakedCornell();
  const std::vector<std::string> files = tree(out);
  // A default bake proposes a reflection probe for the room, so the sky's specular images
  // (EXT_lights_image_based: 7 mips of 6 faces) and the probes' cube EXRs come too; the
  // directional lightmaps are on by default.
  std::vector<std::string> expected = {"lightmaps/lightmap0.exr", "lightmaps/lightmap0.png",
                                       "lightmaps/lightmap0_dx.exr", "lightmaps/lightmap0_dy.exr",
                                       "lightmaps/lightmap0_dz.exr",
                                       "probes/dfg.exr", "probes/light_probes.json",
                                       "probes/light_probes_sh.bin", "probes/reflection_1.exr",
                                       "probes/reflection_probes.json",
                                       "probes/reflection_sky.exr", "report.json",
                                       "scene.bin", "scene.gltf", "transport.agt"};
  for (int mip = 0; mip < 7; ++mip)
    for (int face = 0; face < 6; ++face)
      expected.push_back("probes/sky_specular_m" + std::to_string(mip) + "_f" +
                         std::to_string(face) + ".png");
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(files, expected);

  const json report = json::parse(slurp(out + "/report.json"));
  const size_t texels = report.at("texels").get<size_t>();
  EXPECT_GT(texels, 1000u);
  EXPECT_LE(report.at("validTexels").get<size_t>(), texels);
  EXPECT_GT(report.at("validTexels").get<size_t>(), texels * 8 / 10);
  EXPECT_GT(report.at("clusters").get<size_t>(), 7u);  // at least one per wall, block and lamp
  // Gather points: at most one per valid texel, at least one per 2×2 block.
  const size_t points = report.at("gatherPoints").get<size_t>();
  EXPECT_LE(points, report.at("validTexels").get<size_t>());
  EXPECT_GE(points, report.at("validTexels").get<size_t>() / 4);
  EXPECT_GT(report.at("links").get<size_t>(), points);
  // The transport for the runtime: the report gives its size, the file has it.
  EXPECT_EQ(report.at("transport").at("bytes").get<uintmax_t>(), fs::file_size(out + "/transport.agt"));
  EXPECT_GT(report.at("raysTraced").get<uint64_t>(), points * 64);  // draft: 64 rays a point
  for (const char* stage : {"load", "uv", "texels", "clusters", "links", "direct", "solve"})
    EXPECT_TRUE(report.at("stages").contains(stage)) << stage;
  // Every ray traced belongs to one stage.
  uint64_t stageRays = 0;
  for (const auto& [stage, rays] : report.at("stageRays").items())
    stageRays += rays.get<uint64_t>();
  EXPECT_EQ(stageRays, report.at("raysTraced").get<uint64_t>());
  EXPECT_GT(report.at("stageRays").at("gather").get<uint64_t>(), points * 64);
  EXPECT_GT(report.at("peakMemoryBytes").get<size_t>(), 1000000u);
  EXPECT_TRUE(report.at("warnings").is_array());
  EXPECT_EQ(report.at("settings").at("texelRays").get<int>(), 64);

  // The EXR is linear half float at the atlas size the report gives.
  auto in = OIIO::ImageInput::open(out + "/lightmaps/lightmap0.exr");
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().format, OIIO::TypeDesc::HALF);
  EXPECT_EQ(in->spec().nchannels, 3);
  EXPECT_EQ(in->spec().width, report.at("atlases").at(0).at("width").get<int>());
  EXPECT_EQ(in->spec().height, report.at("atlases").at(0).at("height").get<int>());

  // Every lightmapped primitive uses a material carrying MOZ_lightmap on TEXCOORD_1, whose
  // texture is the PNG preview.
  const json gltf = json::parse(slurp(out + "/scene.gltf"));
  const auto& used = gltf.at("extensionsUsed");
  EXPECT_NE(std::find(used.begin(), used.end(), "MOZ_lightmap"), used.end());
  EXPECT_EQ(gltf.at("buffers").at(0).at("uri"), "scene.bin");
  size_t lightmapped = 0;
  for (const json& node : gltf.at("nodes")) {
    if (!node.contains("mesh")) continue;
    for (const json& prim : gltf.at("meshes").at(node.at("mesh").get<size_t>()).at("primitives")) {
      ASSERT_TRUE(prim.at("attributes").contains("TEXCOORD_1"));
      const json& mat = gltf.at("materials").at(prim.at("material").get<size_t>());
      const json& moz = mat.at("extensions").at("MOZ_lightmap");
      EXPECT_EQ(moz.at("texCoord").get<int>(), 1);
      const json& tex = gltf.at("textures").at(moz.at("index").get<size_t>());
      EXPECT_EQ(gltf.at("images").at(tex.at("source").get<size_t>()).at("uri"),
                "lightmaps/lightmap0.png");
      ++lightmapped;
    }
  }
  EXPECT_EQ(lightmapped, 8u);  // 5 walls, 2 blocks, the lamp
}

// A level with a reflection probe (builtin:cornell-metal's 128² room probe) gets the files the
// README documents: per probe and the sky an OpenEXR cube map whose levels are the prefiltered
// mips (7) then OpenEXR's remaining levels down to 1×1 (floor(log2(6 × size)) + 1 in all), the
// DFG table, reflection_probes.json listing the probes, and the sky in the glTF.
TEST(CliBake, ReflectionProbesWriteCubeMapsDfgAndTheirJson) {
  const std::string dir = tempDir("cli_bake_reflections");
  const std::string out = dir + "/out";
  CliRun r = runCli(dir, "bake builtin:cornell-metal -o '" + out +
                          "' --quality draft --texels-per-unit 32 --quiet");
  ASSERT_EQ(r.exitCode, 0) << r.err;

  struct Cube {
    const char* file;
    int size;
    int fileLevels;  // floor(log2(6 size)) + 1
  };
  for (const Cube& c : {Cube{"reflection_sky.exr", 64, 9}, Cube{"reflection_1.exr", 128, 10}}) {
    SCOPED_TRACE(c.file);
    const std::string path = out + "/probes/" + c.file;
    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in) << OIIO::geterror();
    EXPECT_EQ(in->spec().width, c.size);
    EXPECT_EQ(in->spec().height, 6 * c.size);
    EXPECT_EQ(in->spec().get_string_attribute("textureformat"), "CubeFace Environment");
    EXPECT_EQ(in->spec().get_int_attribute("afterglow:prefilteredLevels"), 7);
    int levels = 0;
    while (in->seek_subimage(0, levels)) ++levels;
    EXPECT_EQ(levels, c.fileLevels);
    in->close();
    Result<std::vector<runtime::Cubemap>> mips = bakefiles::readCubemapExr(path);
    ASSERT_TRUE(mips) << mips.message();
    ASSERT_EQ(mips->size(), 7u);
    for (size_t m = 0; m < mips->size(); ++m) EXPECT_EQ((*mips)[m].size, c.size >> m) << m;
  }
  auto dfg = OIIO::ImageInput::open(out + "/probes/dfg.exr");
  ASSERT_TRUE(dfg);
  EXPECT_EQ(dfg->spec().width, 64);
  EXPECT_EQ(dfg->spec().height, 64);

  const json doc = json::parse(slurp(out + "/probes/reflection_probes.json"));
  EXPECT_EQ(doc.at("format"), "afterglow-reflection-probes");
  EXPECT_EQ(doc.at("mipCount"), 7);
  ASSERT_EQ(doc.at("mipRoughness").size(), 7u);
  EXPECT_EQ(doc["mipRoughness"][0].get<double>(), 0.0);
  EXPECT_NEAR(doc["mipRoughness"][6].get<double>(), 1.0, 1e-6);
  EXPECT_EQ(doc.at("dfg").at("file"), "dfg.exr");
  EXPECT_EQ(doc.at("bounces"), 1);
  const json& probes = doc.at("probes");
  ASSERT_EQ(probes.size(), 2u);
  EXPECT_EQ(probes[0].at("name"), "sky");
  EXPECT_EQ(probes[0].at("file"), "reflection_sky.exr");
  EXPECT_EQ(probes[0].at("faceSize"), 64);
  EXPECT_EQ(probes[0].at("fileMips"), 7);
  const json& room = probes[1];
  EXPECT_EQ(room.at("index"), 1);
  EXPECT_EQ(room.at("name"), "room_probe");
  EXPECT_EQ(room.at("file"), "reflection_1.exr");
  EXPECT_EQ(room.at("faceSize"), 128);
  EXPECT_EQ(room.at("fileMips"), 7);
  const double half[3] = {0.278, 0.2744, 0.2796};  // the room, 556 × 548.8 × 559.2 mm
  for (int a = 0; a < 3; ++a) {
    // Box projection onto the walls; the influence reaching the blend distance (0.1) past them.
    EXPECT_NEAR(room.at("projectionBox").at("halfSize")[size_t(a)].get<double>(), half[a], 1e-5)
        << a;
    EXPECT_NEAR(room.at("projectionBox").at("centre")[size_t(a)].get<double>(), half[a], 1e-5)
        << a;
    EXPECT_NEAR(room.at("box").at("halfSize")[size_t(a)].get<double>(), half[a] + 0.1, 1e-5) << a;
    EXPECT_NEAR(room.at("box").at("centre")[size_t(a)].get<double>(), half[a], 1e-5) << a;
    EXPECT_NEAR(room.at("capturePosition")[size_t(a)].get<double>(), half[a], 1e-5) << a;
  }
  EXPECT_NEAR(room.at("blendDistance").get<double>(), 0.1, 1e-6);
  EXPECT_EQ(room.at("importance"), 1);
  EXPECT_EQ(room.at("boxProjection"), true);

  // The sky in the glTF: one EXT_lights_image_based light, 7 mips of 6 face PNGs beside it.
  const json gltf = json::parse(slurp(out + "/scene.gltf"));
  const json& lights = gltf.at("extensions").at("EXT_lights_image_based").at("lights");
  ASSERT_EQ(lights.size(), 1u);
  EXPECT_EQ(lights[0].at("specularImageSize"), 64);
  ASSERT_EQ(lights[0].at("specularImages").size(), 7u);
  for (const json& mip : lights[0]["specularImages"]) {
    ASSERT_EQ(mip.size(), 6u);
    for (const json& face : mip)
      EXPECT_TRUE(fs::exists(out + "/" + gltf.at("images").at(face.get<size_t>()).at("uri").get<std::string>()));
  }
}

TEST(CliBake, OverTheMemoryBudgetRefusesAndWritesNothing) {
  const std::string dir = tempDir("cli_bake_budget");
  CliRun r = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' --memory-budget 0.000001");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("--yes"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--memory-budget"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/out"));
  EXPECT_TRUE(tree(dir).empty());
}

TEST(CliBake, SettingsFileOverridesThePresetAndTheCommandLineOverridesBoth) {
  const std::string dir = tempDir("cli_bake_settings");
  {
    std::ofstream s(dir + "/settings.json");
    s << R"({"quality": "draft", "texel-rays": 8, "cluster-rays": 16, "texels-per-unit": 16,
            "sky": [0.1, 0.2, 0.3]})";
  }
  CliRun r = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' --settings '" + dir +
                          "/settings.json' --cluster-rays 24 --quiet");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const json settings = json::parse(slurp(dir + "/out/report.json")).at("settings");
  EXPECT_EQ(settings.at("quality"), "draft");
  const baker::BakeOptions draft = baker::bakePreset(baker::Quality::Draft);
  ASSERT_NE(draft.links.texelRays, 8);
  EXPECT_EQ(settings.at("texelRays").get<int>(), 8);       // file over preset
  EXPECT_EQ(settings.at("clusterRays").get<int>(), 24);    // command line over file
  EXPECT_EQ(settings.at("lightSamples").get<int>(), draft.direct.lightSamples);  // preset
  EXPECT_FLOAT_EQ(settings.at("sky").at(2).get<float>(), 0.3f);

  std::ofstream(dir + "/bad.json") << R"({"no-such-setting": 1})";
  CliRun bad = runCli(dir, "bake builtin:cornell -o '" + dir + "/out2' --settings '" + dir +
                            "/bad.json'");
  EXPECT_EQ(bad.exitCode, 2);
  EXPECT_NE(bad.err.find("no-such-setting"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir + "/out2"));
}

// The signal is sent once the bake shows it has begun the precompute (the ray tracer's progress
// line, the first of baker::bake's stages), not after a guessed time: the CLI needs a good part
// of a second to start on a loaded machine, and a SIGINT before main would kill it outright.
// From there this bake runs for many seconds (128,000 texels at 256 gather rays each; its
// gather stage alone takes seconds on two cores), so the signal always lands inside the
// precompute; cancelled, it stops within a fraction of a second.
TEST(CliBake, CtrlCExits130AndWritesNothing) {
  const std::string dir = tempDir("cli_bake_interrupt");
  const std::string out = dir + "/out";
  CliChild child({"bake", "builtin:cornell", "-o", out, "--quality", "high", "--texels-per-unit",
                  "256"});
  ASSERT_TRUE(child.started());
  // The ray tracer is built: the bake is under way (its progress names come from stages.h).
  ASSERT_TRUE(child.waitForStderr(std::string(stageName(Stage::RayTracer)) + ": done"))
      << child.err();
  const int status = child.interruptAndWait();
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status) << "\n" << child.err();
  EXPECT_EQ(WEXITSTATUS(status), 130) << child.err();
  EXPECT_NE(child.err().find("interrupted; nothing written"), std::string::npos) << child.err();
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliBake, HelpListsTheOptions) {
  const std::string dir = tempDir("cli_bake_help");
  CliRun bake = runCli(dir, "bake --help");
  EXPECT_EQ(bake.exitCode, 0);
  for (const char* option : {"--quality", "--memory-budget", "--settings", "--yes", "--sky"})
    EXPECT_NE(bake.out.find(option), std::string::npos) << option;
  CliRun render = runCli(dir, "help render");
  EXPECT_EQ(render.exitCode, 0);
  EXPECT_NE(render.out.find("Usage: afterglow render"), std::string::npos) << render.out;
  CliRun missing = runCli(dir, "bake builtin:cornell");
  EXPECT_EQ(missing.exitCode, 2);
  EXPECT_NE(missing.err.find("-o"), std::string::npos) << missing.err;
}

TEST(CliRender, WritesAPictureOfTheRequestedSize) {
  const std::string out = bakedCornell();
  const std::string dir = tempDir("cli_render");
  CliRun r = runCli(dir, "render '" + out + "/scene.gltf' --camera Camera --width 64 --height 48 "
                          "-o '" + dir + "/view.png' --quiet");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const Picture view = readPng(dir + "/view.png");
  ASSERT_EQ(view.width, 64);
  ASSERT_EQ(view.height, 48);
  // The back wall at the centre is lit; the red wall is on the left of the view, green right.
  EXPECT_GT(view.at(32, 24, 0), 40);
  EXPECT_GT(view.at(12, 24, 0), view.at(12, 24, 1) + 20);  // red wall
  EXPECT_GT(view.at(52, 24, 1), view.at(52, 24, 0) + 20);  // green wall

  CliRun noCamera = runCli(dir, "render '" + out + "/scene.gltf' --camera Nope -o '" + dir +
                                 "/none.png'");
  EXPECT_EQ(noCamera.exitCode, 1);
  EXPECT_NE(noCamera.err.find("Camera"), std::string::npos) << noCamera.err;
  EXPECT_FALSE(fs::exists(dir + "/none.png"));

  CliRun lookAt = runCli(dir, "render '" + out + "/scene.gltf' --look-from 0.278,0.273,-0.8 "
                               "--look-at 0.278,0.273,0 --fov 40 --width 32 --height 32 -o '" +
                               dir + "/look.png' --quiet");
  EXPECT_EQ(lookAt.exitCode, 0) << lookAt.err;
  EXPECT_TRUE(fs::exists(dir + "/look.png"));
}

// A render's float RGB as written to an EXR, row 0 at the top.
struct LinearPicture {
  int width = 0, height = 0, channels = 0;
  std::string pixelType;
  std::vector<float> rgb;
  float at(int x, int y, int k) const { return rgb[(size_t(y) * size_t(width) + size_t(x)) * 3 + size_t(k)]; }
};

LinearPicture readExr(const std::string& path) {
  LinearPicture p;
  auto in = OIIO::ImageInput::open(path);
  if (!in) return p;
  p.width = in->spec().width;
  p.height = in->spec().height;
  p.channels = in->spec().nchannels;
  p.pixelType = in->spec().format.c_str();
  p.rgb.resize(size_t(p.width) * size_t(p.height) * 3);
  if (!in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, p.rgb.data())) p = LinearPicture();
  return p;
}

// The byte writeTonemappedPng makes of a linear value at exposure 1 (Reinhard, then sRGB).
int tonemappedByte(float linear) {
  const double x = std::max(0.0, double(linear));
  const double m = x / (1.0 + x);
  const double e = m <= 0.0031308 ? 12.92 * m : 1.055 * std::pow(m, 1.0 / 2.4) - 0.055;
  return int(std::lround(std::clamp(e, 0.0, 1.0) * 255.0));
}

// `-o VIEW.exr` writes the linear picture the PNG is tone mapped from: pushed through the PNG's
// tone curve (exposure 0 stops), every EXR pixel gives the PNG's byte within one step, so the
// two agree pixel for pixel, row for row (a flipped or tone-mapped EXR fails). The lamp's
// pixels hold its emitted radiance (17, 12, 4) plus its albedo x lightmap (the light bounced
// onto it, well under a tenth of that), in the top part of the picture.
TEST(CliRender, ExrHoldsTheLinearPicture) {
  const std::string out = bakedCornell();
  const std::string dir = tempDir("cli_render_exr");
  const std::string view = "render '" + out + "/scene.gltf' --camera Camera --width 64 "
                           "--height 48 --quiet ";
  CliRun png = runCli(dir, view + "--exposure 0 -o '" + dir + "/view.png'");
  ASSERT_EQ(png.exitCode, 0) << png.err;
  CliRun exr = runCli(dir, view + "-o '" + dir + "/view.exr'");
  ASSERT_EQ(exr.exitCode, 0) << exr.err;
  const Picture p = readPng(dir + "/view.png");
  const LinearPicture e = readExr(dir + "/view.exr");
  ASSERT_EQ(e.width, 64);
  ASSERT_EQ(e.height, 48);
  EXPECT_EQ(e.channels, 3);
  EXPECT_EQ(e.pixelType, "float");
  ASSERT_EQ(p.width, 64);
  ASSERT_EQ(p.height, 48);
  int worst = 0;
  for (int y = 0; y < e.height; ++y)
    for (int x = 0; x < e.width; ++x)
      for (int k = 0; k < 3; ++k)
        worst = std::max(worst, std::abs(tonemappedByte(e.at(x, y, k)) - p.at(x, y, k)));
  EXPECT_LE(worst, 1);

  // The brightest pixel is on the lamp, on the ceiling: in the top quarter of the picture.
  int lampX = 0, lampY = 0;
  for (int y = 0; y < e.height; ++y)
    for (int x = 0; x < e.width; ++x)
      if (e.at(x, y, 0) > e.at(lampX, lampY, 0)) lampX = x, lampY = y;
  EXPECT_LT(lampY, e.height / 4) << "the picture is upside down";
  const float emission[3] = {17.0f, 12.0f, 4.0f};
  for (int k = 0; k < 3; ++k) {
    EXPECT_GE(e.at(lampX, lampY, k), emission[k] * 0.99f) << k;
    EXPECT_LE(e.at(lampX, lampY, k), emission[k] * 1.10f) << k;
  }

  // The path-traced view as EXR too; other outputs are usage errors naming both kinds.
  CliRun reference = runCli(dir, view + "--reference --spp 4 -o '" + dir + "/reference.exr'");
  ASSERT_EQ(reference.exitCode, 0) << reference.err;
  const LinearPicture r = readExr(dir + "/reference.exr");
  ASSERT_EQ(r.width, 64);
  EXPECT_GE(r.at(lampX, lampY, 0), emission[0] * 0.99f);
  CliRun jpg = runCli(dir, view + "-o '" + dir + "/view.jpg'");
  EXPECT_EQ(jpg.exitCode, 2);
  EXPECT_NE(jpg.err.find(".png"), std::string::npos) << jpg.err;
  EXPECT_NE(jpg.err.find(".exr"), std::string::npos) << jpg.err;
  CliRun exposure = runCli(dir, view + "--exposure 1 -o '" + dir + "/bright.exr'");
  EXPECT_EQ(exposure.exitCode, 2);
  EXPECT_FALSE(fs::exists(dir + "/view.jpg"));
  EXPECT_FALSE(fs::exists(dir + "/bright.exr"));
  // Nothing but the two pictures and the reference: the EXRs were renamed into place.
  size_t files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) files += entry.is_regular_file();
  EXPECT_EQ(files, 3u);
}

// The path-traced reference of the baked view is as bright as the baked render: the bake is
// accurate to a few percent (measured: baked/reference = 1.006 over the picture at 256 paths per
// pixel, 1.007 at 4096, so the reference's own noise is negligible), and 10% still catches any
// real fault, such as lost bounced light (half of the light in this box), a factor of π, a
// camera that looks elsewhere, or a reference lit differently from the bake.
TEST(CliRender, ReferenceAgreesWithTheBakedRender) {
  const std::string out = bakedCornell();
  const std::string dir = tempDir("cli_render_reference");
  const std::string view = "render '" + out + "/scene.gltf' --camera Camera --width 64 "
                           "--height 48 --exposure 2 ";
  CliRun baked = runCli(dir, view + "-o '" + dir + "/baked.png'");
  ASSERT_EQ(baked.exitCode, 0) << baked.err;
  EXPECT_NE(baked.out.find("baked"), std::string::npos) << baked.out;
  CliRun ref = runCli(dir, view + "--reference --spp 256 -o '" + dir + "/reference.png'");
  ASSERT_EQ(ref.exitCode, 0) << ref.err;
  EXPECT_NE(ref.out.find("reference"), std::string::npos) << ref.out;
  EXPECT_NE(ref.out.find("256 paths per pixel"), std::string::npos) << ref.out;
  EXPECT_EQ(ref.out.find("no report.json"), std::string::npos) << ref.out;

  const Picture a = readPng(dir + "/baked.png"), b = readPng(dir + "/reference.png");
  ASSERT_EQ(a.width, 64);
  ASSERT_EQ(a.height, 48);
  ASSERT_EQ(b.width, 64);
  ASSERT_EQ(b.height, 48);
  const auto [bakedMean, referenceMean] = linearMeans(a, b, 2.0);
  ASSERT_GT(referenceMean, 0.05);
  EXPECT_NEAR(bakedMean / referenceMean, 1.0, 0.10)
      << "baked " << bakedMean << ", reference " << referenceMean;
}

TEST(CliRender, ReferenceIsTheSameForOneAndTwoThreads) {
  const std::string out = bakedCornell();
  const std::string dir = tempDir("cli_render_reference_threads");
  const std::string view = "render '" + out + "/scene.gltf' --reference --spp 16 --width 32 "
                           "--height 24 --exposure 2 --quiet ";
  ASSERT_EQ(runCli(dir, view + "--threads 1 -o '" + dir + "/one.png'").exitCode, 0);
  ASSERT_EQ(runCli(dir, view + "--threads 2 -o '" + dir + "/two.png'").exitCode, 0);
  const Picture one = readPng(dir + "/one.png"), two = readPng(dir + "/two.png");
  ASSERT_EQ(one.rgb.size(), size_t(32 * 24 * 3));
  EXPECT_TRUE(one.rgb == two.rgb);
}

// The reference lights the scene with the sky the report beside the glTF names, fails on a sky
// image it cannot read (naming it), and says so when there is no report.
TEST(CliRender, ReferenceUsesTheBakeReport) {
  const std::string out = bakedCornell();
  const std::string dir = tempDir("cli_render_reference_report");
  const std::string copy = dir + "/out";
  fs::copy(out, copy, fs::copy_options::recursive);
  const json report = json::parse(slurp(copy + "/report.json"));
  auto writeSettings = [&](const json& changes) {
    json r = report;
    for (auto it = changes.begin(); it != changes.end(); ++it) r["settings"][it.key()] = *it;
    std::ofstream(copy + "/report.json") << r.dump(2);
  };
  const std::string view = "render '" + copy + "/scene.gltf' --reference --spp 16 --width 32 "
                           "--height 24 --exposure 2 ";

  // The box is open toward the camera: a white sky brightens it (measured: 4.5 times).
  ASSERT_EQ(runCli(dir, view + "--quiet -o '" + dir + "/dark.png'").exitCode, 0);
  writeSettings({{"sky", {1.0, 1.0, 1.0}}});
  ASSERT_EQ(runCli(dir, view + "--quiet -o '" + dir + "/sky.png'").exitCode, 0);
  const auto [dark, sky] = linearMeans(readPng(dir + "/dark.png"), readPng(dir + "/sky.png"), 2.0);
  EXPECT_GT(sky, dark * 2.0) << "dark " << dark << ", sky " << sky;

  writeSettings({{"skyImage", dir + "/missing_sky.exr"}});
  CliRun missing = runCli(dir, view + "-o '" + dir + "/missing.png'");
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_NE(missing.err.find("missing_sky.exr"), std::string::npos) << missing.err;
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
  EXPECT_FALSE(fs::exists(dir + "/missing.png"));

  fs::remove(copy + "/report.json");
  CliRun noReport = runCli(dir, view + "-o '" + dir + "/noreport.png'");
  EXPECT_EQ(noReport.exitCode, 0) << noReport.err;
  EXPECT_NE(noReport.out.find("no report.json"), std::string::npos) << noReport.out;
  EXPECT_TRUE(fs::exists(dir + "/noreport.png"));
}

// A scene without lightmaps (not baked) would give a reference black but for emission.
TEST(CliRender, ReferenceNeedsABakedScene) {
  const std::string dir = tempDir("cli_render_reference_unbaked");
  CliRun r = runCli(dir, "render builtin:cornell --reference -o '" + dir + "/view.png'");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("afterglow bake"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/view.png"));
}

}  // namespace
}  // namespace afterglow::test
