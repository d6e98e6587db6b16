// The whole bake (texels, clusters, links, direct, solve, dilation) on closed and small scenes
// with known answers: the white furnace (built in code, and as a glTF level with
// KHR_materials_specular), bounce intensity 0, linearity in a light's intensity,
// and bit-identical output whatever the thread count.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/baker/bake.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/material_eval.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/uv/unwrap.h"
#include "post/lightmap_post.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/baker/sky.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::baker {
namespace {

// The Cornell box lit by a directional light through its open side, with the ceiling lamp
// switched off, so every texel's light comes from that one light.
scenes::Scene sunlitCornell(float intensity, float bounceIntensity) {
  scenes::Scene scene = scenes::makeCornellBox();
  for (scenes::Material& m : scene.materials) m.emissiveFactor = glm::vec3(0.0f);
  scenes::Light sun;
  sun.name = "sun";
  sun.type = scenes::LightType::Directional;
  sun.direction = glm::normalize(glm::vec3(0.25f, -0.6f, 1.0f));
  sun.intensity = intensity;
  sun.color = glm::vec3(1.0f, 0.9f, 0.8f);
  sun.bounceIntensity = bounceIntensity;
  scene.lights.push_back(sun);
  return scene;
}

class WhiteFurnace : public ::testing::TestWithParam<float> {};

TEST_P(WhiteFurnace, EveryValidTexelIsLeOverOneMinusAlbedo) {
  const float albedo = GetParam();
  scenes::FurnaceOptions f;
  f.albedo = glm::vec3(albedo);
  f.emission = glm::vec3(1.0f);
  scenes::Scene scene = scenes::makeFurnaceBox(f);
  // ρ is the bounce albedo the baker reflects with, which scales the base colour by 1 − F0 and
  // adds Unity's meta-pass specular share (0.02 for this dielectric): for metallic 0 it is
  // affine in the base colour, so pick the base colour that gives ρ.
  for (scenes::Material& m : scene.materials) {
    m.baseColorFactor = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    const glm::vec3 a0 = diffuseAlbedoFactor(m);
    m.baseColorFactor = glm::vec4(1.0f);
    const glm::vec3 a1 = diffuseAlbedoFactor(m);
    m.baseColorFactor = glm::vec4((glm::vec3(albedo) - a0) / (a1 - a0), 1.0f);
  }
  for (int m = 0; m < int(scene.materials.size()); ++m)
    ASSERT_NEAR(diffuseAlbedo(scene, m, glm::vec2(0.0f)).x, albedo, 1e-6f);
  unwrapAt(scene, 8.0f);
  BakeOptions options = draftOptions();
  // Enough samples that Monte Carlo noise stays well inside the 1% (the 0.9 furnace amplifies
  // any error tenfold).
  options.links.texelRays = 256;
  options.links.clusterRays = 1024;
  options.direct.emissiveSamples = 4096;
  options.solve.tolerance = 1e-7f;  // ρ = 0.9 converges slowly; the test is about transport
  BakeResult r = bakeOrDie(scene, options);
  ASSERT_GT(r.texels.size(), 300u);
  const float expected = 1.0f / (1.0f - albedo);
  size_t checked = 0;
  float worst = 0.0f;
  for (size_t a = 0; a < r.lightmaps.size(); ++a) {
    const runtime::AtlasLayout& layout = r.texels.atlases[a];
    for (size_t p = 0; p < layout.texelOfPixel.size(); ++p) {
      const uint32_t t = layout.texelOfPixel[p];
      if (t == runtime::kNoTexel || !r.texels.valid[t]) continue;
      const glm::vec3 v = r.lightmaps[a][p];
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(v[k] / expected - 1.0f));
      ++checked;
    }
  }
  EXPECT_LT(worst, 0.01f) << "worst relative error over " << checked << " texels";
  EXPECT_GT(checked, r.texels.size() * 9 / 10);
  std::printf("furnace rho %.1f: worst relative error %.4f over %zu texels\n", albedo, worst,
              checked);
}

INSTANTIATE_TEST_SUITE_P(Albedo, WhiteFurnace, ::testing::Values(0.5f, 0.9f));

// Every valid texel of a bake, per channel.
template <class F>
size_t forEachValidTexel(const BakeResult& r, F f) {
  size_t n = 0;
  for (size_t a = 0; a < r.lightmaps.size(); ++a) {
    const runtime::AtlasLayout& layout = r.texels.atlases[a];
    for (size_t p = 0; p < layout.texelOfPixel.size(); ++p) {
      const uint32_t t = layout.texelOfPixel[p];
      if (t == runtime::kNoTexel || !r.texels.valid[t]) continue;
      for (int k = 0; k < 3; ++k) f(r.lightmaps[a][p][k]);
      ++n;
    }
  }
  return n;
}

BakeOptions furnaceLevelOptions() {
  // As many samples as the procedural furnace above (the small level keeps it fast): the
  // direct light's noise must stay well inside 1%.
  BakeOptions options = draftOptions();
  options.links.texelRays = 256;
  options.links.clusterRays = 1024;
  options.direct.emissiveSamples = 4096;
  return options;
}

// specularFactor 0 makes the level's walls Lambertian: ρ is the base colour, and the furnace
// holds Le / (1 − ρ) everywhere.
class FurnaceLevel : public ::testing::TestWithParam<float> {};

TEST_P(FurnaceLevel, SpecularZeroIsLeOverOneMinusBaseColour) {
  const float rho = GetParam();
  const scenes::Scene scene =
      furnaceLevel(std::to_string(int(rho * 100)), rho, {{"specularFactor", 0.0}});
  ASSERT_EQ(scene.materials.size(), 1u);
  ASSERT_EQ(scene.materials[0].specularFactor, 0.0f);
  ASSERT_EQ(diffuseAlbedo(scene, 0, glm::vec2(0.5f)), glm::vec3(rho));
  BakeOptions options = furnaceLevelOptions();
  options.solve.tolerance = 1e-6f;
  const BakeResult r = bakeOrDie(scene, options);
  ASSERT_GT(r.texels.size(), 50u);
  const float expected = 1.0f / (1.0f - rho);
  float worst = 0.0f, sum = 0.0f;
  const size_t checked = forEachValidTexel(r, [&](float v) {
    worst = std::max(worst, std::abs(v / expected - 1.0f));
    sum += v;
  });
  EXPECT_GT(checked, r.texels.size() * 9 / 10);
  EXPECT_LT(worst, 0.01f) << "worst relative error over " << checked << " texels";
  std::printf("furnace level, base %.2f, specular 0: mean %.4f, Le/(1-rho) %.4f, worst %.4f\n",
              rho, sum / float(3 * checked), expected, worst);
}

INSTANTIATE_TEST_SUITE_P(BaseColour, FurnaceLevel, ::testing::Values(0.5f, 0.9f));

// With glTF's default specular, a bright dielectric keeps 4% of the light out of the diffuse
// part: a base colour of 0.98 stays below Le / (1 − 0.98) (the old meta-pass albedo, 0.98 +
// 0.02 = 1.0, never converged).
TEST(FurnaceLevelDefaultSpecular, BaseColour098StaysBelowItsLambertianFurnace) {
  const scenes::Scene scene = furnaceLevel("98", 0.98f, nullptr);
  ASSERT_EQ(scene.materials.size(), 1u);
  const float albedo = diffuseAlbedo(scene, 0, glm::vec2(0.5f)).x;
  EXPECT_NEAR(albedo, 0.98f * 0.96f + 0.02f, 1e-6f);
  const BakeResult r = bakeOrDie(scene, furnaceLevelOptions());
  ASSERT_GT(r.texels.size(), 50u);
  const float bound = 1.0f / (1.0f - 0.98f);
  const float limit = 1.0f / (1.0f - albedo);
  float highest = 0.0f, lowest = 1e30f;
  const size_t checked = forEachValidTexel(r, [&](float v) {
    ASSERT_TRUE(std::isfinite(v));
    highest = std::max(highest, v);
    lowest = std::min(lowest, v);
  });
  EXPECT_GT(checked, r.texels.size() * 9 / 10);
  EXPECT_LT(highest, bound);
  // And it is the furnace of its own albedo (the solve stops within 0.1% per pass, so a few
  // percent short of the limit).
  EXPECT_LT(highest, limit * 1.01f);
  EXPECT_GT(lowest, limit * 0.9f);
  std::printf("furnace level, base 0.98: albedo %.4f, texels %.3f..%.3f, Le/(1-albedo) %.3f\n",
              albedo, lowest, highest, limit);
}

// A white level (base colour 1, default specular) converges: the solve stops before its pass
// limit with finite texels no brighter than Le / (1 − albedo).
TEST(FurnaceLevelDefaultSpecular, WhiteConverges) {
  const scenes::Scene scene = furnaceLevel("white", 1.0f, nullptr);
  ASSERT_EQ(scene.materials.size(), 1u);
  const float albedo = diffuseAlbedo(scene, 0, glm::vec2(0.5f)).x;
  ASSERT_LT(albedo, 1.0f);
  const BakeOptions options = furnaceLevelOptions();
  const BakeResult r = bakeOrDie(scene, options);
  ASSERT_GT(r.texels.size(), 50u);
  const float limit = 1.0f / (1.0f - albedo);
  float highest = 0.0f;
  const size_t checked = forEachValidTexel(r, [&](float v) {
    ASSERT_TRUE(std::isfinite(v));
    highest = std::max(highest, v);
  });
  EXPECT_GT(checked, r.texels.size() * 9 / 10);
  EXPECT_LE(highest, limit);
  // The bake's solve, run again on its transport: it stops on the tolerance, not the limit.
  runtime::Solver solver(r.transport);
  solver.prepare();
  solver.reset();
  const int passes = solver.solve(options.solve);
  EXPECT_GT(passes, 10);
  EXPECT_LT(passes, 1000);
  std::printf("furnace level, base 1: albedo %.4f, highest texel %.3f, Le/(1-albedo) %.3f, "
              "%d passes\n", albedo, highest, limit, passes);
}

TEST(Bake, BounceIntensityZeroGivesDirectLightOnly) {
  scenes::Scene scene = sunlitCornell(3.0f, 0.0f);
  unwrapAt(scene, 24.0f);
  BakeResult r = bakeOrDie(scene, draftOptions());
  ASSERT_GT(r.texels.size(), 0u);

  // Direct light only: the same transport with no bounce pass at all.
  runtime::TransportData data = r.transport;
  runtime::Solver direct(data);
  direct.reset();
  std::vector<glm::vec3> directOnly;
  direct.gatherTexels(directOnly);
  float maxDirect = 0.0f;
  size_t compared = 0;
  for (size_t a = 0; a < r.lightmaps.size(); ++a) {
    const runtime::AtlasLayout& layout = r.texels.atlases[a];
    for (size_t p = 0; p < layout.texelOfPixel.size(); ++p) {
      const uint32_t t = layout.texelOfPixel[p];
      if (t == runtime::kNoTexel || !r.texels.valid[t]) continue;
      for (int k = 0; k < 3; ++k) ASSERT_EQ(r.lightmaps[a][p][k], directOnly[t][k]) << t;
      maxDirect = std::max(maxDirect, directOnly[t].x);
      ++compared;
    }
  }
  EXPECT_GT(compared, 0u);
  EXPECT_GT(maxDirect, 0.1f);

  // With the light's bounce back at 1 the same transport does carry indirect light, so the
  // equality above is not vacuous.
  for (runtime::Source& s : data.sources)
    if (s.kind == runtime::SourceKind::Light) s.bounceIntensity = 1.0f;
  runtime::Solver bounced(data);
  bounced.solve();
  std::vector<glm::vec3> withBounce;
  bounced.gatherTexels(withBounce);
  double gained = 0.0;
  for (uint32_t t = 0; t < r.texels.size(); ++t) gained += withBounce[t].x - directOnly[t].x;
  EXPECT_GT(gained / r.texels.size(), 1e-3);
}

TEST(Bake, DoublingALightDoublesEveryTexel) {
  scenes::Scene once = sunlitCornell(2.0f, 1.0f);
  unwrapAt(once, 24.0f);
  scenes::Scene twice = once;
  twice.lights[0].intensity = 4.0f;
  const BakeResult a = bakeOrDie(once, draftOptions());
  const BakeResult b = bakeOrDie(twice, draftOptions());
  ASSERT_EQ(a.lightmaps.size(), b.lightmaps.size());
  ASSERT_FALSE(a.lightmaps.empty());
  float peak = 0.0f;
  for (size_t i = 0; i < a.lightmaps.size(); ++i) {
    ASSERT_EQ(a.lightmaps[i].size(), b.lightmaps[i].size());
    for (size_t p = 0; p < a.lightmaps[i].size(); ++p)
      for (int k = 0; k < 3; ++k) {
        const float want = 2.0f * a.lightmaps[i][p][k];
        ASSERT_NEAR(b.lightmaps[i][p][k], want, 1e-5f * std::max(std::abs(want), 1e-20f))
            << "atlas " << i << " pixel " << p;
        peak = std::max(peak, want);
      }
  }
  EXPECT_GT(peak, 0.1f);
}

TEST(Bake, BitIdenticalWithOneAndTwoThreads) {
  scenes::Scene scene = scenes::makeCornellBox();
  scene.lights.push_back(sunlitCornell(1.0f, 1.0f).lights[0]);
  unwrapAt(scene, 24.0f);
  setThreadCount(1);
  const BakeResult one = bakeOrDie(scene, draftOptions());
  setThreadCount(2);
  const BakeResult two = bakeOrDie(scene, draftOptions());
  setThreadCount(0);
  ASSERT_EQ(one.lightmaps.size(), two.lightmaps.size());
  ASSERT_FALSE(one.lightmaps.empty());
  for (size_t i = 0; i < one.lightmaps.size(); ++i) {
    ASSERT_EQ(one.lightmaps[i].size(), two.lightmaps[i].size());
    EXPECT_EQ(0, std::memcmp(one.lightmaps[i].data(), two.lightmaps[i].data(),
                             one.lightmaps[i].size() * sizeof(glm::vec3)))
        << "atlas " << i;
  }
  EXPECT_EQ(one.raysTraced, two.raysTraced);
}

// A bake leaves nothing behind that changes the next one in the process: the Cornell box with
// a double-sided panel (whose underside gets back-side clusters, which trace rays of their own)
// bakes the same on a fresh thread as on one that just baked the same box with its walls and
// blocks dynamic, where the same geometry ids reflect nothing. (The back-side clusters' ray
// batch was once thread_local, and its cache of what each geometry id is outlived the bake:
// a Cornell box baked after Sponza in one process lost 11% of its links.)
TEST(Bake, ABakeDoesNotDependOnTheBakeBefore) {
  auto boxWithPanel = [](bool dynamicWalls) {
    scenes::Scene scene = scenes::makeCornellBox();
    scene.lights.push_back(sunlitCornell(1.0f, 1.0f).lights[0]);
    scenes::Material panel;
    panel.name = "panel";
    panel.baseColorFactor = glm::vec4(0.7f, 0.7f, 0.7f, 1.0f);
    panel.metallicFactor = 0.0f;
    panel.doubleSided = true;
    scene.materials.push_back(panel);
    scenes::Primitive quad;
    quad.material = int(scene.materials.size()) - 1;
    quad.positions = {{0.15f, 0.3f, 0.15f}, {0.15f, 0.3f, 0.4f}, {0.4f, 0.3f, 0.4f}, {0.4f, 0.3f, 0.15f}};
    quad.normals.assign(4, glm::vec3(0.0f, 1.0f, 0.0f));
    quad.indices = {0, 1, 2, 0, 2, 3};
    scene.meshes.push_back({"panel", {quad}});
    if (dynamicWalls)
      for (scenes::Instance& inst : scene.instances)
        inst.isStatic = inst.name == "floor" || inst.name == "light";  // (the floor sees backs)
    scenes::Instance inst;
    inst.name = "panel";
    inst.mesh = int(scene.meshes.size()) - 1;
    scene.instances.push_back(inst);
    return scene;
  };
  scenes::Scene box = boxWithPanel(false), other = boxWithPanel(true);
  unwrapAt(box, 24.0f);
  unwrapAt(other, 24.0f);
  // One thread, so each bake runs on the thread that calls it: the box baked on a fresh thread,
  // and on this one right after the other box, where anything the other left behind in the
  // thread's state would be found.
  setThreadCount(1);
  BakeResult first;
  std::thread fresh([&] { first = bakeOrDie(box, draftOptions()); });
  fresh.join();
  ASSERT_GT(first.transport.backRowCount(), 0u);
  ASSERT_GT(bakeOrDie(other, draftOptions()).transport.backRowCount(), 0u);
  const BakeResult again = bakeOrDie(box, draftOptions());
  setThreadCount(0);
  EXPECT_EQ(first.transport.links.link, again.transport.links.link);
  EXPECT_EQ(first.transport.clusterSky, again.transport.clusterSky);
  ASSERT_EQ(first.lightmaps.size(), again.lightmaps.size());
  for (size_t i = 0; i < first.lightmaps.size(); ++i)
    EXPECT_EQ(0, std::memcmp(first.lightmaps[i].data(), again.lightmaps[i].data(),
                             first.lightmaps[i].size() * sizeof(glm::vec3)))
        << "atlas " << i;
}

TEST(Bake, StagesAreTimedAndCancellationStops) {
  scenes::Scene scene = scenes::makeFurnaceBox();
  unwrapAt(scene, 4.0f);
  const BakeResult r = bakeOrDie(scene, draftOptions());
  std::vector<std::string> names;
  for (const StageTime& s : r.stages) {
    names.push_back(stageName(s.stage));
    EXPECT_GE(s.seconds, 0.0);
  }
  for (const char* want : {"raytracer", "texels", "clusters", "links", "direct", "solve", "dilate"})
    EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want;
  EXPECT_GT(r.raysTraced, 0u);

  Progress cancelled;
  cancelled.cancel();
  Result<BakeResult> stopped = bake(scene, draftOptions(), cancelled);
  ASSERT_FALSE(stopped);
  EXPECT_EQ(stopped.message(), "cancelled");
}

// Writes a lat-long EXR whose radiance is f(direction) (the image layout of projectEquirectSky).
template <class F>
std::string writeSky(const std::string& path, int w, int h, F f) {
  std::vector<float> px(size_t(w) * size_t(h) * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double theta = 3.14159265358979 * (y + 0.5) / h;
      const double phi = 2.0 * 3.14159265358979 * (x + 0.5) / w;
      const glm::vec3 d(float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                        float(std::sin(theta) * std::sin(phi)));
      const glm::vec3 v = f(d);
      for (int k = 0; k < 3; ++k) px[(size_t(y) * size_t(w) + size_t(x)) * 3 + size_t(k)] = v[k];
    }
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out);
  EXPECT_TRUE(out->open(path, OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::FLOAT)));
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
  out->close();
  return path;
}

TEST(SkyImage, ConstantSkyMatchesConstantShAndAGradientLandsInY1) {
  const std::string dir = test::tempDir("bake_sky_image");
  glm::vec3 sh[runtime::kShCount], want[runtime::kShCount];
  const glm::vec3 colour(0.5f, 1.0f, 2.0f);
  ASSERT_TRUE(projectEquirectSky(writeSky(dir + "/constant.exr", 128, 64,
                                          [&](glm::vec3) { return colour; }),
                                 sh));
  runtime::constantSkySh(colour, want);
  for (int i = 0; i < runtime::kShCount; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(sh[i][k], want[i][k], 2e-3f * want[0][k]) << i;
  // L = 1 + y: the y term projects onto Y1-1 with 0.488603 · 4π/3.
  ASSERT_TRUE(projectEquirectSky(writeSky(dir + "/gradient.exr", 128, 64,
                                          [](glm::vec3 d) { return glm::vec3(1.0f + d.y); }),
                                 sh));
  EXPECT_NEAR(sh[1].x, 0.488603f * 4.0f * 3.14159265f / 3.0f, 5e-3f);
  EXPECT_NEAR(sh[2].x, 0.0f, 5e-3f);
  EXPECT_NEAR(sh[3].x, 0.0f, 5e-3f);
  EXPECT_FALSE(projectEquirectSky(dir + "/missing.exr", sh));
}

// A 6×2 atlas: instance 0 owns columns 0-2 of row 0 (valid, invalid, valid), instance 1 owns
// column 5 of row 0 (invalid, with no valid texel of its own); the rest is padding.
TEST(LightmapPost, InvalidTexelsFillFromTheirInstanceThenChartsDilate) {
  TexelSet texels;
  runtime::AtlasLayout layout;
  layout.width = 6;
  layout.height = 2;
  layout.texelOfPixel.assign(12, runtime::kNoTexel);
  const uint32_t pixel[4] = {0, 1, 2, 5};
  const uint32_t instance[4] = {0, 0, 0, 1};
  const uint8_t valid[4] = {1, 0, 1, 0};
  for (uint32_t t = 0; t < 4; ++t) {
    layout.texelOfPixel[pixel[t]] = t;
    texels.instance.push_back(instance[t]);
    texels.valid.push_back(valid[t]);
  }
  texels.atlases.push_back(layout);
  PostOptions post;
  post.dilation = 1;
  computeAtlasMixes(texels, scenes::Scene{}, post);
  const std::vector<glm::vec3> values = {glm::vec3(1.0f), glm::vec3(100.0f), glm::vec3(3.0f),
                                         glm::vec3(50.0f)};
  std::vector<glm::vec3> image;
  runtime::resolveAtlas(texels.atlases[0], values, image);
  ASSERT_EQ(image.size(), 12u);
  EXPECT_FLOAT_EQ(image[0].x, 1.0f);
  EXPECT_FLOAT_EQ(image[1].x, 2.0f);   // the invalid texel: mean of its valid neighbours
  EXPECT_FLOAT_EQ(image[2].x, 3.0f);
  EXPECT_FLOAT_EQ(image[3].x, 3.0f);   // padding, one ring deep, from the nearest chart
  EXPECT_FLOAT_EQ(image[4].x, 0.0f);   // two rings away: left black
  EXPECT_FLOAT_EQ(image[5].x, 0.0f);   // instance 1 has nothing valid to take light from
  EXPECT_FLOAT_EQ(image[6].x, 1.5f);   // below pixels 0 and 1: mean of 1 and 2 (pixel 1's mix)
  // Linear in the values: doubling them doubles every pixel.
  std::vector<glm::vec3> doubled = values, twice;
  for (glm::vec3& v : doubled) v *= 2.0f;
  runtime::resolveAtlas(texels.atlases[0], doubled, twice);
  for (size_t p = 0; p < image.size(); ++p) EXPECT_FLOAT_EQ(twice[p].x, 2.0f * image[p].x);
}

}  // namespace
}  // namespace afterglow::baker
