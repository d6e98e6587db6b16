// Light through glass (issue 28): a closed room whose one window, in the ceiling, is a pane of
// alphaMode BLEND glass. The sun straight through it lights the floor below with the sun's
// E/π × (1 − alpha) × tint (the bake's grey of the tint, the reference path tracer's in
// colour);
// a constant sky through it lights the room as the reference path tracer finds, and the bake
// is the same for any thread count.
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/baker/reference.h"
#include "afterglow/core/math.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/trace/raytracer.h"
#include "bake_fixtures.h"
#include "precompute/glass_sky.h"
#include "shading/emitters.h"

namespace afterglow::baker {
namespace {

constexpr float kAlpha = 0.4f;

// The room's inside is [0, 2] × [0, 1] × [0, 2] (metres, y up), its walls, floor and ceiling
// 10 cm boxes of a Lambertian 0.7 white; the window [0.3, 1.7]² in the ceiling holds a pane of
// double-sided BLEND glass (alpha kAlpha, base colour `tint`, Lambertian) at y = 1.05.
scenes::Scene glassRoom(glm::vec3 tint) {
  scenes::Scene scene;
  scenes::Material wall;
  wall.name = "wall";
  wall.baseColorFactor = glm::vec4(0.7f, 0.7f, 0.7f, 1.0f);
  wall.metallicFactor = 0.0f;
  wall.specularFactor = 0.0f;
  scenes::Material glass = wall;
  glass.name = "glass";
  glass.baseColorFactor = glm::vec4(tint, kAlpha);
  glass.alphaMode = scenes::AlphaMode::Blend;
  glass.doubleSided = true;
  scene.materials = {wall, glass};
  addBox(scene, "floor", {-0.1f, -0.1f, -0.1f}, {2.1f, 0.0f, 2.1f}, 0);
  addBox(scene, "west", {-0.1f, 0.0f, -0.1f}, {0.0f, 1.0f, 2.1f}, 0);
  addBox(scene, "east", {2.0f, 0.0f, -0.1f}, {2.1f, 1.0f, 2.1f}, 0);
  addBox(scene, "north", {0.0f, 0.0f, -0.1f}, {2.0f, 1.0f, 0.0f}, 0);
  addBox(scene, "south", {0.0f, 0.0f, 2.0f}, {2.0f, 1.0f, 2.1f}, 0);
  addBox(scene, "ceiling_west", {-0.1f, 1.0f, -0.1f}, {0.3f, 1.1f, 2.1f}, 0);
  addBox(scene, "ceiling_east", {1.7f, 1.0f, -0.1f}, {2.1f, 1.1f, 2.1f}, 0);
  addBox(scene, "ceiling_north", {0.3f, 1.0f, -0.1f}, {1.7f, 1.1f, 0.3f}, 0);
  addBox(scene, "ceiling_south", {0.3f, 1.0f, 1.7f}, {1.7f, 1.1f, 2.1f}, 0);
  scenes::Primitive pane;
  pane.material = 1;
  pane.positions = {
      {0.3f, 1.05f, 0.3f}, {0.3f, 1.05f, 1.7f}, {1.7f, 1.05f, 1.7f}, {1.7f, 1.05f, 0.3f}};
  pane.normals.assign(4, glm::vec3(0.0f, 1.0f, 0.0f));
  pane.indices = {0, 1, 2, 0, 2, 3};
  scenes::Mesh mesh;
  mesh.name = "window";
  mesh.primitives = {pane};
  scene.meshes.push_back(mesh);
  scenes::Instance inst;
  inst.name = "window";
  inst.mesh = int(scene.meshes.size()) - 1;
  scene.instances.push_back(inst);
  unwrapAt(scene, 8.0f);
  return scene;
}

bool inside(glm::vec3 p) {
  return p.x > 0.0f && p.x < 2.0f && p.y > -1e-3f && p.y < 1.0f + 1e-3f && p.z > 0.0f && p.z < 2.0f;
}

// The valid texels on the room's inside (walls, floor and ceiling facing in).
std::vector<uint32_t> roomTexels(const BakeResult& b) {
  std::vector<uint32_t> out;
  for (uint32_t t = 0; t < b.texels.size(); ++t)
    if (b.texels.valid[t] && inside(b.texels.position[t])) out.push_back(t);
  return out;
}

// Floor texels well inside the window's sunlit patch, [0.5, 1.5]².
std::vector<uint32_t> underTheWindow(const BakeResult& b) {
  std::vector<uint32_t> out;
  for (uint32_t t : roomTexels(b)) {
    const glm::vec3 p = b.texels.position[t];
    if (p.y < 0.01f && p.x > 0.5f && p.x < 1.5f && p.z > 0.5f && p.z < 1.5f) out.push_back(t);
  }
  return out;
}

Environment skyOf(glm::vec3 radiance) {
  Environment env;
  runtime::constantSkySh(radiance, env.skySh);
  return env;
}

TEST(BakeGlass, SunStraightThroughTheWindowLightsTheFloorByAlphaAndTint) {
  const glm::vec3 tint(0.9f, 0.6f, 0.3f);
  for (const glm::vec3 colour : {glm::vec3(1.0f), tint}) {
    scenes::Scene scene = glassRoom(colour);
    scene.lights.push_back(hardSun({0.0f, -1.0f, 0.0f}));
    scene.lights.back().intensity = 3.0f;
    const BakeResult b = bakeOrDie(scene, draftOptions());
    const std::vector<uint32_t> lit = underTheWindow(b);
    ASSERT_GT(lit.size(), 10u);
    const ReferenceTexels ref = referenceOrDie(scene, b.texels, Environment(), 64, lit);
    ASSERT_EQ(ref.texels.size(), lit.size());
    // E/π = 3 lux / π × (1 − alpha) × tint: in colour by the reference, as the tint's mean by
    // the bake (exact for the white pane).
    const glm::vec3 want = 3.0f / kPi * (1.0f - kAlpha) * colour;
    const float grey = (want.x + want.y + want.z) / 3.0f;
    for (size_t i = 0; i < lit.size(); ++i) {
      const glm::vec3 baked = b.texelDirect[lit[i]], path = ref.direct[i];
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(path[c], want[c], 1e-4f * want[c]) << "texel " << lit[i];
        EXPECT_NEAR(baked[c], grey, 1e-4f * grey) << "texel " << lit[i];
      }
    }
  }
}

// A constant sky through the window, against the reference path tracer over the room's inside:
// the sky seen through the pane, the pane's own reflection and every bounce. (With the window
// open, no pane, the same bake is 3.6% off the reference, bias +1.5%: most of the error is the
// gather's own, not the glass's.)
TEST(BakeGlass, SkyThroughTheWindowMatchesTheReferencePathTracer) {
  const scenes::Scene scene = glassRoom(glm::vec3(1.0f));
  BakeOptions options;
  options.skyColor = glm::vec3(1.0f);
  const BakeResult b = bakeOrDie(scene, options);
  std::vector<uint32_t> subset;
  const std::vector<uint32_t> room = roomTexels(b);
  for (size_t k = 0; k < room.size(); k += 2) subset.push_back(room[k]);
  ASSERT_GT(subset.size(), 300u);
  const ReferenceComparison c = compareToReference(
      referenceOrDie(scene, b.texels, skyOf(glm::vec3(1.0f)), 8192, subset), b.texelDirect,
      b.texelIndirect);
  ASSERT_EQ(c.texels, subset.size());
  printComparison("glass room under a sky", c);
  EXPECT_LT(c.total.referenceNoise, 0.025);
  EXPECT_LE(c.total.relativeRmse, 0.05);
  EXPECT_LE(std::abs(c.total.bias), 0.03);
}

// The sky through glass sampled through the glass alone (no cosine rays to share it with)
// converges to the window's form factor × what it lets through; behind an opaque roof to 0.
// With as many cosine rays to share each direction with, the samples converge to their share by the
// balance heuristic, 1 − rayWeight, integrated over the pane apart (the midpoint rule).
TEST(BakeGlass, GlassSkySamplesFindTheWindowsFormFactorAndTheirShareOfIt) {
  scenes::Scene scene;
  scenes::Material glass;
  glass.alphaMode = scenes::AlphaMode::Blend;
  glass.baseColorFactor = glm::vec4(1.0f, 1.0f, 1.0f, kAlpha);
  glass.doubleSided = true;
  scene.materials = {glass, scenes::Material()};
  addBox(scene, "pane", {-0.5f, 1.0f, -0.5f}, {0.5f, 1.0f, 0.5f}, 0);  // a flat box: two faces
  const glm::vec3 p(0.1f, 0.0f, -0.2f), up(0.0f, 1.0f, 0.0f);
  Emitter window;
  for (const scenes::Instance& inst : scene.instances)
    addTriangles(inst, scene.meshes[size_t(inst.mesh)].primitives[0], {}, window);
  double formFactor = 0.0;  // (1/π) ∫ cosθ dω over the pane, the upper face's triangles
  for (const EmitterTriangle& tri : window.triangles)
    if (tri.normal.y > 0.5f) formFactor += double(triangleTransfer(tri, true, p, up));
  // One face's crossing of the flat box and the other's are one (raytracer.h): 1 − alpha.
  const double y00 = 0.28209479177387814;
  const double want = y00 * double(1.0f - kAlpha) * formFactor;
  constexpr uint32_t kSamples = 4096;
  auto estimate = [&](const scenes::Scene& s, uint32_t rays) {
    Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(s);
    EXPECT_TRUE(tracer) << tracer.message();
    double sky[runtime::kShCount] = {};
    if (tracer) GlassSky(s).addTo(*tracer.value(), p, up, up, 7, kSamples, rays, 0.0f, sky);
    return sky[0];
  };
  EXPECT_NEAR(estimate(scene, 0), want, 0.01 * want);

  constexpr uint32_t kRays = kSamples;  // as many rays as samples: each keeps a fair share
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  const GlassSky glassSky(scene);
  std::vector<float> chances;
  glassSky.chances(p, up, chances);
  constexpr int kGrid = 256;
  const double cell = 1.0 / double(kGrid * kGrid);
  double share = 0.0;
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j) {
      const glm::vec3 q(-0.5f + (float(i) + 0.5f) / kGrid, 1.0f, -0.5f + (float(j) + 0.5f) / kGrid);
      const float d = glm::length(q - p);
      const glm::vec3 dir = (q - p) / d;
      trace::Ray ray;
      ray.origin = p;
      ray.direction = dir;
      const trace::Hit first = tracer.value()->intersect(ray);
      const int k = glassSky.triangleOf(first);
      ASSERT_GE(k, 0);
      const float w = glassSky.rayWeight(chances, up, dir, k, first.t, dir.y, kRays, kSamples);
      share += double(dir.y * dir.y) / (kPi * double(d) * double(d)) * cell * double(1.0f - w);
    }
  share *= y00 * double(1.0f - kAlpha);
  const double shared = estimate(scene, kRays);
  EXPECT_GT(shared, 0.05 * want);
  EXPECT_LT(shared, 0.95 * want);
  EXPECT_NEAR(shared, share, 0.01 * want);

  scenes::Scene roofed = scene;
  addBox(roofed, "roof", {-2.0f, 2.0f, -2.0f}, {2.0f, 2.1f, 2.0f}, 1);
  EXPECT_EQ(estimate(roofed, 0), 0.0);
}

// Each ray's fate at the glass is its own: one thread or two, the same lightmaps.
TEST(BakeGlass, BitIdenticalWithOneAndTwoThreads) {
  scenes::Scene scene = glassRoom(glm::vec3(0.9f, 0.6f, 0.3f));
  scene.lights.push_back(hardSun({0.3f, -1.0f, 0.2f}));
  BakeOptions options = draftOptions();
  options.skyColor = glm::vec3(0.5f);
  setThreadCount(1);
  const BakeResult one = bakeOrDie(scene, options);
  setThreadCount(2);
  const BakeResult two = bakeOrDie(scene, options);
  setThreadCount(0);
  ASSERT_FALSE(one.lightmaps.empty());
  ASSERT_EQ(one.lightmaps.size(), two.lightmaps.size());
  for (size_t i = 0; i < one.lightmaps.size(); ++i) {
    ASSERT_EQ(one.lightmaps[i].size(), two.lightmaps[i].size());
    EXPECT_EQ(0, std::memcmp(one.lightmaps[i].data(), two.lightmaps[i].data(),
                             one.lightmaps[i].size() * sizeof(glm::vec3)));
  }
}

}  // namespace
}  // namespace afterglow::baker
