// The sky as EXT_lights_image_based (baker/ext_lights_image_based.h): the irradiance
// coefficients for a constant sky and, for any SH, under Babylon.js's evaluation; the RGBD
// encoding; the face images against a model of Babylon's cube upload and lookup written out
// independently of the table in the code; and the JSON the glTF gains.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "afterglow/bakefiles/ext_lights_image_based.h"
#include "afterglow/core/math.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::bakefiles {
namespace {


// Babylon.js's shading of irradianceCoefficients C, from its source: the loader scales by
// intensity and 1/π (convertIrradianceToLambertianRadiance), the SH shader path sums
// H_i · Y^B_i(n) with its signed basis constants (sphericalPolynomial.ts SH3ylmBasisConstants),
// the normal in Babylon's frame: glTF's (x, y, z) is (−x, y, z) there (the loader's __root__).
glm::vec3 babylonIrradianceOverPi(const std::array<glm::vec3, 9>& c, float intensity,
                                  glm::vec3 gltfNormal) {
  const glm::vec3 n(-gltfNormal.x, gltfNormal.y, gltfNormal.z);
  const float k0 = std::sqrt(1.0f / (4 * kPi)), k1 = std::sqrt(3.0f / (4 * kPi));
  const float k2 = std::sqrt(15.0f / (4 * kPi)), k20 = std::sqrt(5.0f / (16 * kPi));
  const float k22 = std::sqrt(15.0f / (16 * kPi));
  const float y[9] = {k0,           -k1 * n.y,       k1 * n.z,
                      -k1 * n.x,    k2 * n.x * n.y,  -k2 * n.y * n.z,
                      k20 * (3 * n.z * n.z - 1), -k2 * n.x * n.z, k22 * (n.x * n.x - n.y * n.y)};
  glm::vec3 e(0.0f);
  for (int i = 0; i < 9; ++i) e += c[size_t(i)] * intensity / kPi * y[i];
  return e;
}

// Babylon's lookup of a glTF direction in the extension's faces: the cube is sampled with the
// direction in its left-handed frame, S = (−x, y, z); GL's cube-face table gives the face and
// (s, t); the face's memory row t came from the PNG row size − 1 − row (uploaded with
// invertY). Returns (slot, column, row).
std::array<int, 3> babylonPixel(glm::vec3 gltfDir, int size) {
  const glm::vec3 s(-gltfDir.x, gltfDir.y, gltfDir.z);
  const glm::vec3 a = glm::abs(s);
  int slot;
  float sc, tc, ma;
  if (a.x >= a.y && a.x >= a.z) {
    slot = s.x > 0 ? 0 : 1;
    ma = a.x;
    sc = s.x > 0 ? -s.z : s.z;
    tc = -s.y;
  } else if (a.y >= a.z) {
    slot = s.y > 0 ? 2 : 3;
    ma = a.y;
    sc = s.x;
    tc = s.y > 0 ? s.z : -s.z;
  } else {
    slot = s.z > 0 ? 4 : 5;
    ma = a.z;
    sc = s.z > 0 ? s.x : -s.x;
    tc = -s.y;
  }
  const float u = (sc / ma + 1) / 2, t = (tc / ma + 1) / 2;
  const int column = std::clamp(int(u * float(size)), 0, size - 1);
  const int memoryRow = std::clamp(int(t * float(size)), 0, size - 1);
  return {slot, column, size - 1 - memoryRow};
}

// A PNG's bytes as stored: OpenImageIO premultiplies the colour by the alpha on reading unless
// told the alpha is unassociated (here it is RGBD's divisor).
std::unique_ptr<OIIO::ImageInput> openRgbd(const std::string& path) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  return OIIO::ImageInput::open(path, &config);
}

runtime::ShL2 constantSky(glm::vec3 radiance) {
  runtime::ShL2 sh;
  sh.c[0] = radiance * 2.0f * std::sqrt(kPi);  // ∫ L Y00 dω
  return sh;
}

TEST(ExtLightsImageBased, ConstantSkyCoefficientsAreAnalytic) {
  const glm::vec3 sky(0.2f, 0.5f, 1.5f);
  const auto c = extLightsIrradianceCoefficients(constantSky(sky));
  // C_0 = Â_0 · L_00 = π · 2√π · L, every other coefficient 0.
  const float c0 = 2.0f * kPi * std::sqrt(kPi);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(c[0][k], c0 * sky[k], 1e-5f * c0);
  for (int i = 1; i < 9; ++i) EXPECT_EQ(c[size_t(i)], glm::vec3(0.0f)) << i;
  // Babylon then shades every normal with E/π = L: a white surface shows the sky's radiance.
  for (glm::vec3 n : {glm::vec3(1, 0, 0), glm::vec3(0, -1, 0), glm::normalize(glm::vec3(1, 2, 3))})
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(babylonIrradianceOverPi(c, 1.0f, n)[k], sky[k], 1e-5f);
}

// Any SH: what Babylon shades from the coefficients is our irradianceOverPi for the same glTF
// normal, so the signs (its Condon–Shortley phase, its mirrored x) and Â_l are right.
TEST(ExtLightsImageBased, BabylonShadesOurIrradiance) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 20; ++trial) {
    runtime::ShL2 sh;
    for (glm::vec3& c : sh.c) c = {u(rng), u(rng), u(rng)};
    const auto c = extLightsIrradianceCoefficients(sh);
    for (int k = 0; k < 10; ++k) {
      const glm::vec3 n = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
      const glm::vec3 ours = runtime::irradianceOverPi(sh, n);
      const glm::vec3 babylon = babylonIrradianceOverPi(c, 1.0f, n);
      EXPECT_LT(glm::length(ours - babylon), 1e-5f) << "trial " << trial;
    }
  }
}

TEST(ExtLightsImageBased, RgbdMatchesBabylonsEncoding) {
  // Within [0, 1] D = 1 and the colour is gamma encoded.
  std::array<uint8_t, 4> e = encodeRgbd({1.0f, 0.5f, 0.0f});
  EXPECT_EQ(e[3], 255);
  EXPECT_EQ(e[0], 255);
  EXPECT_EQ(e[1], std::lround(std::pow(0.5f, 1 / 2.2f) * 255));
  EXPECT_EQ(e[2], 0);
  // max 10: D = floor(25.5) / 255 = 25 / 255.
  e = encodeRgbd({10.0f, 1.0f, 0.1f});
  EXPECT_EQ(e[3], 25);
  EXPECT_EQ(e[0], std::lround(std::pow(10.0f * 25 / 255, 1 / 2.2f) * 255));
  // Beyond 255 it clips; negative and NaN are 0.
  e = encodeRgbd({1000.0f, -1.0f, std::nanf("")});
  EXPECT_EQ(e[3], 1);
  EXPECT_EQ(e[0], 255);
  EXPECT_EQ(e[1], 0);
  EXPECT_EQ(e[2], 0);
  // Round trip within the 8-bit steps (relative ~1.5% at worst for the brightest channel).
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> v(0.0f, 200.0f);
  for (int i = 0; i < 1000; ++i) {
    const glm::vec3 c(v(rng), v(rng), v(rng));
    const glm::vec3 back = decodeRgbd(encodeRgbd(c));
    const float top = std::max(c.r, std::max(c.g, c.b));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(back[k], c[k], 0.015f * top) << c[k];
  }
}

// The table in extLightsFaceTexel against the model of Babylon's upload and lookup above, for
// every texel centre of every face.
TEST(ExtLightsImageBased, FaceTableMatchesBabylonsLookup) {
  for (int size : {1, 2, 4, 16}) {
    for (int face = 0; face < runtime::kCubeFaceCount; ++face)
      for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
          const glm::vec3 d = runtime::cubemapTexelDirection(face, x, y, size);
          const std::array<int, 3> p = babylonPixel(d, size);
          const runtime::CubeTexel t = extLightsFaceTexel(p[0], p[1], p[2], size);
          EXPECT_EQ(t.face, face) << size << " " << x << "," << y;
          EXPECT_EQ(t.x, x) << "face " << face << " size " << size;
          EXPECT_EQ(t.y, y) << "face " << face << " size " << size;
        }
  }
}

TEST(ExtLightsImageBased, BabylonsRoughnessPerMip) {
  EXPECT_NEAR(babylonRoughnessOfMip(0, 7, 128), std::sqrt(1.0f / 128), 1e-6f);
  EXPECT_NEAR(babylonRoughnessOfMip(6, 7, 128), 1.0f, 1e-6f);
  EXPECT_NEAR(babylonRoughnessOfMip(3, 7, 128), std::pow(2.0f, -1.75f), 1e-5f);  // α = 2^-3.5
  EXPECT_EQ(babylonRoughnessOfMip(0, 1, 128), 0.0f);
  // Within a tenth of Unity's mapping at every mip of a 7-mip 128² chain.
  for (int m = 0; m < 7; ++m)
    EXPECT_LT(std::abs(babylonRoughnessOfMip(m, 7, 128) - runtime::roughnessOfMip(float(m))), 0.1f);
}

json minimalGltf() {
  return json::parse(R"({"asset": {"version": "2.0"}, "scene": 0,
                         "scenes": [{"nodes": []}], "images": [{"uri": "albedo.png"}]})");
}

// The document and files for a constant sky with the five mips of a 16² chain.
TEST(ExtLightsImageBased, ConstantSkyDocumentAndImages) {
  const std::string dir = test::tempDir("ext_lights_ibl");
  const glm::vec3 sky(0.25f, 0.5f, 2.0f);
  std::vector<runtime::Cubemap> mips;
  for (int m = 0; m < 5; ++m) mips.push_back(runtime::makeCubemap(16 >> m, sky));
  json doc = minimalGltf();
  AtomicOutput out;
  Result<std::vector<std::string>> written =
      attachImageBasedLight(doc, dir, constantSky(sky), mips, out);
  ASSERT_TRUE(written.isOk()) << written.message();
  ASSERT_TRUE(out.commit().isOk());
  EXPECT_EQ(written->size(), 5u * 6u);

  ASSERT_TRUE(doc["extensionsUsed"].is_array());
  EXPECT_EQ(doc["extensionsUsed"], json::array({"EXT_lights_image_based"}));
  EXPECT_FALSE(doc.contains("extensionsRequired"));
  const json& lights = doc["extensions"]["EXT_lights_image_based"]["lights"];
  ASSERT_EQ(lights.size(), 1u);
  const json& light = lights[0];
  EXPECT_EQ(light["name"], "sky");
  EXPECT_EQ(light["rotation"], json::array({0.0, 0.0, 0.0, 1.0}));
  EXPECT_EQ(light["intensity"], 1.0);
  EXPECT_EQ(light["specularImageSize"], 16);
  ASSERT_EQ(light["irradianceCoefficients"].size(), 9u);
  const double c0 = 2.0 * M_PI * std::sqrt(M_PI);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(light["irradianceCoefficients"][0][k].get<double>(), c0 * sky[k], 1e-5 * c0);
  for (int i = 1; i < 9; ++i)
    EXPECT_EQ(light["irradianceCoefficients"][size_t(i)], json::array({0.0, 0.0, 0.0}));
  EXPECT_EQ(doc["scenes"][0]["extensions"]["EXT_lights_image_based"]["light"], 0);

  // mips × 6 images after the one already there, each a 4-channel PNG of its mip's size whose
  // RGBD decodes to the sky.
  ASSERT_EQ(light["specularImages"].size(), 5u);
  ASSERT_EQ(doc["images"].size(), 1u + 30u);
  EXPECT_EQ(doc["images"][0]["uri"], "albedo.png");
  for (int m = 0; m < 5; ++m) {
    ASSERT_EQ(light["specularImages"][size_t(m)].size(), 6u);
    for (int s = 0; s < 6; ++s) {
      const int index = light["specularImages"][size_t(m)][size_t(s)];
      EXPECT_EQ(index, 1 + m * 6 + s);
      const json& image = doc["images"][size_t(index)];
      EXPECT_EQ(image["uri"], format("probes/sky_specular_m%d_f%d.png", m, s));
      EXPECT_EQ(image["mimeType"], "image/png");
      const std::string path = dir + "/" + image["uri"].get<std::string>();
      auto in = openRgbd(path);
      ASSERT_TRUE(in) << path;
      EXPECT_EQ(in->spec().width, 16 >> m);
      EXPECT_EQ(in->spec().height, 16 >> m);
      ASSERT_EQ(in->spec().nchannels, 4);
      std::vector<uint8_t> px(size_t(16 >> m) * size_t(16 >> m) * 4);
      ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, px.data()));
      const glm::vec3 back = decodeRgbd({px[0], px[1], px[2], px[3]});
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(back[k], sky[k], 0.02f * sky.b);
    }
  }
}

// The PNGs on disk, read back and looked up the way Babylon does, show our cube's radiance in
// each glTF direction (the whole path: table, flips, PNG rows, RGBD, OIIO's alpha handling).
TEST(ExtLightsImageBased, WrittenFacesShowOurCubeThroughBabylonsLookup) {
  const std::string dir = test::tempDir("ext_lights_ibl_faces");
  const int size = 8;
  runtime::Cubemap cube = runtime::makeCubemap(size);
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x)
        cube.at(f, x, y) = (runtime::cubemapTexelDirection(f, x, y, size) + 1.1f) * 3.0f;
  json doc = minimalGltf();
  AtomicOutput out;
  ASSERT_TRUE(attachImageBasedLight(doc, dir, runtime::ShL2{}, {cube}, out).isOk());
  ASSERT_TRUE(out.commit().isOk());
  std::vector<std::vector<uint8_t>> faces;
  for (int s = 0; s < 6; ++s) {
    auto in = openRgbd(dir + format("/probes/sky_specular_m0_f%d.png", s));
    ASSERT_TRUE(in);
    faces.emplace_back(size_t(size) * size * 4);
    ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, faces.back().data()));
  }
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < 500; ++i) {
    glm::vec3 d(u(rng), u(rng), u(rng));
    if (glm::length(d) < 0.1f) continue;
    d = glm::normalize(d);
    const runtime::CubeTexel ours = runtime::cubemapTexel(d, size);
    // Away from texel boundaries only: the two conventions place a boundary direction alike
    // but rounding may not.
    const glm::vec3 centre = runtime::cubemapTexelDirection(ours.face, ours.x, ours.y, size);
    const std::array<int, 3> p = babylonPixel(centre, size);
    const uint8_t* px = faces[size_t(p[0])].data() + (size_t(p[2]) * size + size_t(p[1])) * 4;
    const glm::vec3 shown = decodeRgbd({px[0], px[1], px[2], px[3]});
    const glm::vec3 expected = cube.at(ours.face, ours.x, ours.y);
    const float top = std::max(expected.r, std::max(expected.g, expected.b));
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(shown[k], expected[k], 0.02f * top) << "direction " << i;
  }
}

TEST(ExtLightsImageBased, BadInputLeavesTheDocumentAlone) {
  const std::string dir = test::tempDir("ext_lights_ibl_bad");
  const json original = minimalGltf();
  auto refuse = [&](json doc, const std::vector<runtime::Cubemap>& mips,
                    const std::string& words) {
    AtomicOutput out;
    Result<std::vector<std::string>> r =
        attachImageBasedLight(doc, dir, constantSky(glm::vec3(1.0f)), mips, out);
    ASSERT_FALSE(r.isOk()) << words;
    EXPECT_NE(r.message().find(words), std::string::npos) << r.message();
    if (doc.contains("scenes")) {
      EXPECT_EQ(doc, original) << words;
    }
  };
  refuse(minimalGltf(), {runtime::makeCubemap(12, glm::vec3(1.0f))}, "not a power of two");
  refuse(minimalGltf(), {runtime::makeCubemap(8), runtime::makeCubemap(2)}, "mip 1 has size 2");
  refuse(minimalGltf(), {}, "no specular mips");
  json noScene = minimalGltf();
  noScene.erase("scenes");
  refuse(noScene, {runtime::makeCubemap(4)}, "no scene");
  runtime::Cubemap nan = runtime::makeCubemap(4);
  nan.texels[7].r = std::nanf("");
  refuse(minimalGltf(), {nan}, "not finite");
  EXPECT_FALSE(fs::exists(dir + "/probes") && fs::directory_iterator(dir + "/probes") !=
                                                   fs::directory_iterator());
}

// A second light (a document that already has one) is appended, and scenes point at it.
TEST(ExtLightsImageBased, AppendsToExistingLights) {
  const std::string dir = test::tempDir("ext_lights_ibl_append");
  json doc = minimalGltf();
  doc["extensions"]["EXT_lights_image_based"]["lights"] = json::array({json::object()});
  doc["extensionsUsed"] = json::array({"KHR_materials_ior", "EXT_lights_image_based"});
  AtomicOutput out;
  ImageBasedLightOptions options;
  options.name = "baked sky";
  options.imagePrefix = "baked";
  options.intensity = 2.0f;
  ASSERT_TRUE(attachImageBasedLight(doc, dir, constantSky(glm::vec3(1.0f)),
                                    {runtime::makeCubemap(2, glm::vec3(1.0f))}, out, options)
                  .isOk());
  EXPECT_EQ(doc["extensions"]["EXT_lights_image_based"]["lights"].size(), 2u);
  EXPECT_EQ(doc["extensions"]["EXT_lights_image_based"]["lights"][1]["name"], "baked sky");
  EXPECT_EQ(doc["extensions"]["EXT_lights_image_based"]["lights"][1]["intensity"], 2.0);
  EXPECT_EQ(doc["scenes"][0]["extensions"]["EXT_lights_image_based"]["light"], 1);
  EXPECT_EQ(doc["extensionsUsed"].size(), 2u);
  EXPECT_EQ(doc["images"][1]["uri"], "probes/baked_m0_f0.png");
}

// Detaching a light by name removes it, the images only it used (renumbering the others in
// textures, texture extensions and the remaining lights), and the scenes' pointers to it; a
// light kept renumbers, and with none left the extension goes. Then attaching again gives the
// document one light of that name, as a relight needs of a baked glTF.
TEST(ExtLightsImageBased, DetachRemovesTheLightAndOnlyItsImages) {
  const std::string dir = test::tempDir("ext_lights_ibl_detach");
  json doc = minimalGltf();
  doc["images"] = json::array({{{"uri", "a.png"}}, {{"uri", "b.png"}}});
  AtomicOutput out;
  const std::vector<runtime::Cubemap> mips = {runtime::makeCubemap(2, glm::vec3(1.0f)),
                                              runtime::makeCubemap(1, glm::vec3(1.0f))};
  ImageBasedLightOptions other;
  other.name = "studio";
  other.imagePrefix = "studio";
  ASSERT_TRUE(attachImageBasedLight(doc, dir, constantSky(glm::vec3(1.0f)), mips, out).isOk());
  ASSERT_TRUE(attachImageBasedLight(doc, dir, constantSky(glm::vec3(2.0f)), mips, out, other).isOk());
  // Images: a, b, 12 of "sky", 12 of "studio"; textures after them, one sharing a sky face.
  doc["images"].push_back({{"uri", "c.png"}});  // 26
  doc["textures"] = json::array({{{"source", 26}},
                                 {{"source", 1}, {"extensions", {{"EXT_texture_webp", {{"source", 26}}}}}},
                                 {{"source", 3}}});
  doc["scenes"].push_back({{"extensions", {{"EXT_lights_image_based", {{"light", 0}}}}}});
  doc["scenes"][0]["extensions"]["EXT_lights_image_based"]["light"] = 1;

  EXPECT_EQ(detachImageBasedLights(doc, "nobody"), 0u);
  EXPECT_EQ(detachImageBasedLights(doc, "sky"), 1u);
  // 11 of the sky's images went (image 3, a face a texture uses, stays).
  ASSERT_EQ(doc["images"].size(), 27u - 11u);
  EXPECT_EQ(doc["images"][2]["uri"], "probes/sky_specular_m0_f1.png");
  EXPECT_EQ(doc["images"][15]["uri"], "c.png");
  EXPECT_EQ(doc["textures"][0]["source"], 15);
  EXPECT_EQ(doc["textures"][1]["source"], 1);
  EXPECT_EQ(doc["textures"][1]["extensions"]["EXT_texture_webp"]["source"], 15);
  EXPECT_EQ(doc["textures"][2]["source"], 2);
  const json& lights = doc["extensions"]["EXT_lights_image_based"]["lights"];
  ASSERT_EQ(lights.size(), 1u);
  EXPECT_EQ(lights[0]["name"], "studio");
  EXPECT_EQ(lights[0]["specularImages"][0][0], 3);  // was 14
  EXPECT_EQ(doc["images"][3]["uri"], "probes/studio_m0_f0.png");
  EXPECT_EQ(doc["scenes"][0]["extensions"]["EXT_lights_image_based"]["light"], 0);
  EXPECT_FALSE(doc["scenes"][1].contains("extensions"));  // it pointed at the sky

  EXPECT_EQ(detachImageBasedLights(doc, "studio"), 1u);
  EXPECT_FALSE(doc.contains("extensions"));
  EXPECT_FALSE(doc["scenes"][0].contains("extensions"));
  const json used = doc.value("extensionsUsed", json::array());
  EXPECT_EQ(std::find(used.begin(), used.end(), "EXT_lights_image_based"), used.end());
  ASSERT_EQ(doc["images"].size(), 4u);  // a, b, the sky face a texture uses, c
  EXPECT_EQ(doc["textures"][0]["source"], 3);

  ASSERT_TRUE(attachImageBasedLight(doc, dir, constantSky(glm::vec3(3.0f)), mips, out).isOk());
  EXPECT_EQ(doc["extensions"]["EXT_lights_image_based"]["lights"].size(), 1u);
  EXPECT_EQ(doc["scenes"][1]["extensions"]["EXT_lights_image_based"]["light"], 0);
}

}  // namespace
}  // namespace afterglow::bakefiles
