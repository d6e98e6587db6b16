// Glass in the ray tracer (raytracer.h): what a transmissive surface lets through along a
// segment, occlusion as light sees it, and the chance a Glass::Light ray passes, stops or is
// absorbed: its rates, and the same fate for a ray on any thread, single or batched.
#include <cmath>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/scenes/material_eval.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/trace/raytracer.h"

namespace afterglow::trace {
namespace {

using scenes::Scene;

// A horizontal unit quad x, z ∈ [0, 1] at height y, front +Y.
scenes::Primitive quadAt(float y, int material) {
  scenes::Primitive p;
  p.material = material;
  p.positions = {{0.0f, y, 0.0f}, {0.0f, y, 1.0f}, {1.0f, y, 1.0f}, {1.0f, y, 0.0f}};
  p.normals.assign(4, glm::vec3(0.0f, 1.0f, 0.0f));
  p.uv0 = {{0.0f, 0.0f}, {0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}};
  p.indices = {0, 1, 2, 0, 2, 3};
  return p;
}

void addQuad(Scene& scene, float y, int material) {
  scenes::Mesh mesh;
  mesh.name = "quad" + std::to_string(scene.meshes.size());
  mesh.primitives = {quadAt(y, material)};
  scene.meshes.push_back(mesh);
  scenes::Instance inst;
  inst.name = mesh.name;
  inst.mesh = int(scene.meshes.size()) - 1;
  scene.instances.push_back(inst);
}

const glm::vec3 kTint(0.5f, 1.0f, 0.25f);

// Material 0: BLEND glass of alpha 0.4 (60% passes) tinted kTint; 1: KHR_materials_transmission
// 0.5, white; 2: opaque. Glass panes at y = 3 (material 0) and y = 2 (material 1), an opaque
// floor at y = 0.
Scene glassStack() {
  Scene scene;
  scenes::Material blend;
  blend.name = "blend";
  blend.alphaMode = scenes::AlphaMode::Blend;
  blend.baseColorFactor = glm::vec4(kTint, 0.4f);
  blend.doubleSided = true;
  scenes::Material transmission;
  transmission.name = "transmission";
  transmission.transmissionFactor = 0.5f;
  scenes::Material opaque;
  opaque.name = "opaque";
  scene.materials = {blend, transmission, opaque};
  addQuad(scene, 3.0f, 0);
  addQuad(scene, 2.0f, 1);
  addQuad(scene, 0.0f, 2);
  return scene;
}

Ray downFrom(float x, float z, float y, float tfar = std::numeric_limits<float>::infinity()) {
  Ray r;
  r.origin = glm::vec3(x, y, z);
  r.direction = glm::vec3(0.0f, -1.0f, 0.0f);
  r.tfar = tfar;
  return r;
}

void expectNear(glm::vec3 a, glm::vec3 b) {
  EXPECT_NEAR(a.x, b.x, 1e-6f);
  EXPECT_NEAR(a.y, b.y, 1e-6f);
  EXPECT_NEAR(a.z, b.z, 1e-6f);
}

std::unique_ptr<RayTracer> build(const Scene& scene) {
  auto result = RayTracer::build(scene);
  EXPECT_TRUE(result.isOk()) << result.message();
  return result.isOk() ? std::move(result.value()) : nullptr;
}

TEST(TraceGlass, TransmittanceIsTheProductOfThePanesAndZeroAtAnOpaqueSurface) {
  const Scene scene = glassStack();
  auto tracer = build(scene);
  ASSERT_TRUE(tracer);
  EXPECT_TRUE(tracer->hasGlass());
  EXPECT_EQ(tracer->stats().transmissiveGeometries, 2u);
  const glm::vec3 first = 0.6f * kTint, second(0.5f);
  expectNear(tracer->transmittance(downFrom(0.3f, 0.6f, 4.0f, 0.5f)), glm::vec3(1.0f));
  expectNear(tracer->transmittance(downFrom(0.3f, 0.6f, 4.0f, 1.5f)), first);
  expectNear(tracer->transmittance(downFrom(0.3f, 0.6f, 4.0f, 3.0f)), first * second);
  expectNear(tracer->transmittance(downFrom(0.3f, 0.6f, 4.0f, 5.0f)), glm::vec3(0.0f));
  // Grey: each pane's mean over the channels, multiplied.
  const float greyFirst = 0.6f * (0.5f + 1.0f + 0.25f) / 3.0f;
  std::vector<Ray> rays;
  for (float tfar : {0.5f, 1.5f, 3.0f, 5.0f})
    for (float x : {0.1f, 0.5f, 0.9f}) rays.push_back(downFrom(x, 0.3f, 4.0f, tfar));
  std::vector<float> grey(rays.size());
  tracer->greyTransmittance(rays.data(), grey.data(), rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    const float want = i < 3 ? 1.0f : i < 6 ? greyFirst : i < 9 ? greyFirst * 0.5f : 0.0f;
    EXPECT_NEAR(grey[i], want, 1e-6f) << i;
  }
  // A lone ray (the single-ray path of the batch) agrees.
  float lone = -1.0f;
  tracer->greyTransmittance(&rays[7], &lone, 1);
  EXPECT_NEAR(lone, greyFirst * 0.5f, 1e-6f);
  // Through the panes light gets to the floor, so only the floor occludes as light sees it;
  // as geometry the first pane does.
  EXPECT_FALSE(tracer->occluded(downFrom(0.3f, 0.6f, 4.0f, 3.0f), Glass::Light));
  EXPECT_TRUE(tracer->occluded(downFrom(0.3f, 0.6f, 4.0f, 5.0f), Glass::Light));
  EXPECT_TRUE(tracer->occluded(downFrom(0.3f, 0.6f, 4.0f, 1.5f)));
  EXPECT_EQ(tracer->intersect(downFrom(0.3f, 0.6f, 4.0f)).instance, 0u);
  const scenes::Transmission t =
      tracer->transmission(tracer->intersect(downFrom(0.3f, 0.6f, 4.0f)));
  EXPECT_NEAR(t.open, 0.6f, 1e-6f);
}

// Seventeen panes of glass that lets everything through: past the sixteenth a segment counts
// as blocked (see raytracer.h), short of it as open. The rays cross every pane on the edge its
// two triangles share: one crossing each.
TEST(TraceGlass, MoreThanSixteenPanesBlock) {
  Scene scene;
  scenes::Material clear;
  clear.alphaMode = scenes::AlphaMode::Blend;
  clear.baseColorFactor = glm::vec4(1.0f, 1.0f, 1.0f, 0.0f);
  scene.materials = {clear};
  for (int k = 0; k < 17; ++k) addQuad(scene, float(k), 0);
  auto tracer = build(scene);
  ASSERT_TRUE(tracer);
  expectNear(tracer->transmittance(downFrom(0.5f, 0.5f, 15.5f)), glm::vec3(1.0f));
  expectNear(tracer->transmittance(downFrom(0.5f, 0.5f, 17.5f)), glm::vec3(0.0f));
  // The same in packets (greyTransmittance), every ray on the edge.
  std::vector<Ray> rays;
  for (int k = 0; k < 16; ++k) {
    const float at = (float(k) + 0.5f) / 16.0f;
    rays.push_back(downFrom(at, at, k % 2 ? 15.5f : 17.5f));
  }
  std::vector<float> grey(rays.size());
  tracer->greyTransmittance(rays.data(), grey.data(), rays.size());
  for (int k = 0; k < 16; ++k) EXPECT_EQ(grey[size_t(k)], k % 2 ? 1.0f : 0.0f) << k;
}

// Rays straight down through the BLEND pane onto the floor below it, from a grid of origins.
std::vector<Ray> gridRays(size_t side) {
  std::vector<Ray> rays;
  for (size_t i = 0; i < side; ++i)
    for (size_t j = 0; j < side; ++j)
      rays.push_back(
          downFrom((float(i) + 0.5f) / float(side), (float(j) + 0.5f) / float(side), 4.0f));
  return rays;
}

TEST(TraceGlass, LightRaysPassStopOrAreAbsorbedAtTheGlassesRates) {
  Scene scene = glassStack();
  scene.instances.erase(scene.instances.begin() + 1);  // the BLEND pane over the floor alone
  auto tracer = build(scene);
  ASSERT_TRUE(tracer);
  const std::vector<Ray> rays = gridRays(300);
  std::vector<Hit> hits(rays.size());
  tracer->intersect(rays.data(), hits.data(), rays.size(), Glass::Light);
  size_t stopped = 0, passed = 0, absorbed = 0;
  for (const Hit& hit : hits) {
    ASSERT_TRUE(hit.valid());
    if (hit.instance == 1) {
      EXPECT_FALSE(hit.absorbed);
      ++passed;
    } else {
      (hit.absorbed ? absorbed : stopped) += 1;
    }
  }
  // Stop 1 − open = 0.4; pass open × mean(tint) = 0.35; absorbed the rest, 0.25. Binomial
  // standard deviations at 90,000 rays are under 0.0017; allow four.
  const double n = double(rays.size());
  EXPECT_NEAR(double(stopped) / n, 0.4, 0.007);
  EXPECT_NEAR(double(passed) / n, 0.35, 0.007);
  EXPECT_NEAR(double(absorbed) / n, 0.25, 0.007);
  // As geometry every ray stops at the pane.
  std::vector<Hit> solid(rays.size());
  tracer->intersect(rays.data(), solid.data(), rays.size());
  for (const Hit& hit : solid) ASSERT_TRUE(hit.instance == 0 && !hit.absorbed);
}

TEST(TraceGlass, ARayMeetsTheSameFateSingleOrBatchedOnAnyThread) {
  const Scene scene = glassStack();
  auto tracer = build(scene);
  ASSERT_TRUE(tracer);
  std::vector<Ray> rays = gridRays(100);
  for (size_t i = 0; i < rays.size(); ++i)  // steeply down, most of them onto the floor
    rays[i].direction =
        glm::normalize(glm::vec3(0.1f * std::sin(float(i)), -1.0f, 0.1f * std::cos(float(i))));
  std::vector<Hit> batched(rays.size()), threaded(rays.size());
  tracer->intersect(rays.data(), batched.data(), rays.size(), Glass::Light);
  auto work = [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) threaded[i] = tracer->intersect(rays[i], Glass::Light);
  };
  std::thread a(work, 0, rays.size() / 2), b(work, rays.size() / 2, rays.size());
  a.join();
  b.join();
  size_t reachedFloor = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(batched[i].instance, threaded[i].instance) << i;
    ASSERT_EQ(batched[i].t, threaded[i].t) << i;
    ASSERT_EQ(batched[i].absorbed, threaded[i].absorbed) << i;
    reachedFloor += batched[i].instance == 2 ? 1 : 0;
  }
  EXPECT_GT(reachedFloor, 0u);
}

// Without glass the grey transmittance is occlusion and nothing else.
TEST(TraceGlass, WithoutGlassGreyTransmittanceIsOcclusion) {
  const Scene scene = scenes::makeCornellBox();
  auto tracer = build(scene);
  ASSERT_TRUE(tracer);
  EXPECT_FALSE(tracer->hasGlass());
  std::vector<Ray> rays = gridRays(40);
  for (size_t i = 0; i < rays.size(); ++i) {
    rays[i].origin = glm::vec3(0.28f, 0.27f, 0.28f);
    rays[i].direction =
        glm::normalize(glm::vec3(std::sin(float(i)), std::cos(0.7f * float(i)), 0.3f));
    rays[i].tfar = 0.2f + 0.0003f * float(i);
  }
  std::vector<float> grey(rays.size());
  std::unique_ptr<bool[]> blocked(new bool[rays.size()]);
  tracer->greyTransmittance(rays.data(), grey.data(), rays.size());
  tracer->occluded(rays.data(), blocked.get(), rays.size());
  size_t both[2] = {};
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(grey[i], blocked[i] ? 0.0f : 1.0f) << i;
    ++both[blocked[i] ? 1 : 0];
  }
  EXPECT_GT(both[0], 100u);
  EXPECT_GT(both[1], 100u);
}

}  // namespace
}  // namespace afterglow::trace
