// Reflection probes baked (issue 15), against answers known without the baker: the glTF furnace
// (Le / (1 − ρ) in every texel of every mip), and two facing mirrors whose radiance follows the
// geometric series of their reflectance, pass by pass.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "afterglow/baker/reference.h"
#include "afterglow/runtime/reflection_capture.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/trace/raytracer.h"
#include "test_util.h"
#include "bake_fixtures.h"

namespace afterglow::baker {
namespace {

scenes::ReflectionProbe probeAt(glm::vec3 position, glm::vec3 size, int resolution) {
  scenes::ReflectionProbe p;
  p.name = "probe";
  p.transform = glm::mat4(1.0f);
  p.transform[3] = glm::vec4(position, 1.0f);
  p.size = size;
  p.resolution = resolution;
  return p;
}

// In the glTF furnace with specularFactor 0 (no specular: the walls' radiance is diffuse ×
// lightmap + emission = Le / (1 − ρ)), a probe sees that in every texel of every mip, whether
// its box is given or fitted.
TEST(ReflectionBake, FurnaceEveryTexelOfEveryMipIsLeOverOneMinusRho) {
  const float rho = 0.5f;
  scenes::Scene scene = furnaceLevel("reflection", rho, {{"specularFactor", 0.0}});
  scene.reflectionProbes.push_back(probeAt(glm::vec3(0.1f, -0.15f, 0.05f), glm::vec3(0.0f), 16));
  scene.reflectionProbes.push_back(probeAt(glm::vec3(0.0f), glm::vec3(1.0f), 8));
  BakeOptions options = draftOptions();
  options.links.texelRays = 256;
  options.links.clusterRays = 1024;
  options.direct.emissiveSamples = 1024;
  options.solve.tolerance = 1e-6f;
  const BakeResult r = bakeOrDie(scene, options);
  ASSERT_EQ(r.reflectionChains.size(), 3u);
  const float expected = 1.0f / (1.0f - rho);
  float worst = 0.0f;
  for (size_t p = 1; p < r.reflectionChains.size(); ++p) {
    ASSERT_EQ(r.reflectionChains[p].size(), size_t(runtime::kReflectionMipCount));
    for (const runtime::Cubemap& mip : r.reflectionChains[p])
      for (const glm::vec3& t : mip.texels)
        for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(t[k] / expected - 1.0f));
  }
  EXPECT_LT(worst, 0.01f);
  // The fitted projection box is the furnace's inside (a unit cube centred on the origin), the
  // influence box that grown by the blend distance.
  const runtime::ReflectionProbeBox& fitted = r.transport.reflections.probes[0].box;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(fitted.projectionHalfSize[a], 0.5f, 0.01f) << "axis " << a;
    EXPECT_NEAR(fitted.projectionCentre[a], 0.0f, 0.01f) << "axis " << a;
    EXPECT_NEAR(fitted.halfSize[a], 0.5f + fitted.blendDistance, 0.01f) << "axis " << a;
  }
  std::printf("reflection furnace rho %.1f: worst relative error %.4f over 2 probes x 7 mips\n",
              rho, worst);
}

// A corridor between two facing mirrors: the walls x = ±0.5 are mirrors (metallic, roughness 0,
// base colour R, emitting Le), the four others black (no albedo, no emission), 40 m across so
// that rays near the corridor's axis bounce between the mirrors many times before leaving.
scenes::Scene mirrorCorridor(float reflectance, float emission) {
  scenes::Scene scene;
  scenes::Material mirror;
  mirror.name = "mirror";
  mirror.baseColorFactor = glm::vec4(glm::vec3(reflectance), 1.0f);
  mirror.metallicFactor = 1.0f;
  mirror.roughnessFactor = 0.0f;
  mirror.emissiveFactor = glm::vec3(emission);
  scenes::Material black;
  black.name = "black";
  black.baseColorFactor = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
  black.metallicFactor = 0.0f;
  black.specularFactor = 0.0f;
  scene.materials = {mirror, black};
  const glm::vec3 half(0.5f, 20.0f, 20.0f);
  // One quad per face of the box, facing in: axis a, side s.
  for (int a = 0; a < 3; ++a)
    for (int s = -1; s <= 1; s += 2) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      scenes::Primitive prim;
      prim.material = a == 0 ? 0 : 1;
      for (int k = 0; k < 4; ++k) {
        glm::vec3 p(0.0f);
        p[a] = float(s) * half[a];
        p[b] = ((k == 1 || k == 2) ? 1.0f : -1.0f) * half[b];
        p[c] = (k >= 2 ? 1.0f : -1.0f) * half[c];
        prim.positions.push_back(p);
      }
      glm::vec3 n(0.0f);
      n[a] = -float(s);
      prim.normals.assign(4, n);
      // Counter-clockwise seen from inside (the normal's side).
      prim.indices = s > 0 ? std::vector<uint32_t>{0, 2, 1, 0, 3, 2}
                           : std::vector<uint32_t>{0, 1, 2, 0, 2, 3};
      scenes::Mesh mesh;
      mesh.name = "wall" + std::to_string(2 * a + (s > 0));
      mesh.primitives.push_back(prim);
      scene.meshes.push_back(mesh);
      scenes::Instance inst;
      inst.name = mesh.name;
      inst.mesh = int(scene.meshes.size()) - 1;
      scene.instances.push_back(inst);
    }
  unwrapAt(scene, 2.0f);
  return scene;
}

// The probe at the corridor's centre looks at a mirror within 15° of its normal: there the
// mirror emits Le and reflects (Schlick's Fresnel is R within 1e-6 that close to normal
// incidence) what the other mirror showed in the previous pass, so after n passes past the
// first it shows Le (1 + R + ... + R^n). Box projection sends each reflected ray to the wall
// point the real reflection reaches; but that point's texel was shaded as seen from the capture
// position, at a steeper angle, so each pass's lookups land farther out (at 15°, tan θ grows
// 0.27 → 0.80 → 2.4 over three passes: the third still lands 3.6 m out, on the mirror, while
// at 30° it would reach the black walls, the approximation every engine's probes share).
TEST(ReflectionBake, FacingMirrorsFollowTheGeometricSeries) {
  const float reflectance = 0.8f, emission = 1.0f;
  scenes::Scene scene = mirrorCorridor(reflectance, emission);
  // The box fitted to the corridor: its walls for box projection, its influence beyond them.
  scene.reflectionProbes.push_back(probeAt(glm::vec3(0.0f), glm::vec3(0.0f), 32));
  BakeOptions options = draftOptions();
  options.reflections.bounces = 0;
  BakeResult r = bakeOrDie(scene, options);
  ASSERT_EQ(r.transport.reflections.count(), 1u);
  const float cos15 = std::cos(15.0f * 3.14159265f / 180.0f);
  float geometric = 0.0f;
  for (uint32_t bounces = 0; bounces <= 3; ++bounces) {
    geometric += std::pow(reflectance, float(bounces));
    r.transport.reflections.bounces = bounces;
    const std::vector<runtime::CubemapChain> chains =
        runtime::solveReflectionProbes(r.transport, r.lightmaps, r.dfg, runtime::kDfgSize);
    const runtime::Cubemap& mip0 = chains[1][0];
    double sum = 0.0;
    size_t count = 0;
    for (int face = 0; face < runtime::kCubeFaceCount; ++face)
      for (int y = 0; y < mip0.size; ++y)
        for (int x = 0; x < mip0.size; ++x)
          if (std::abs(runtime::cubemapTexelDirection(face, x, y, mip0.size).x) >= cos15) {
            sum += double(mip0.at(face, x, y).x);
            ++count;
          }
    ASSERT_GT(count, 0u);
    const double mean = sum / double(count);
    const double expected = double(emission) * double(geometric);
    std::printf("facing mirrors R %.1f, %u bounces: mean radiance %.4f, series %.4f (%+.2f%%)\n",
                reflectance, bounces, mean, expected, 100.0 * (mean / expected - 1.0));
    EXPECT_NEAR(mean / expected, 1.0, 0.02) << bounces << " bounces";
  }
}

// The runtime relights the cubemaps: a full round after a change of emission equals a fresh bake
// with that emission, texel for texel, through update() and readCubemap().
TEST(ReflectionBake, RelitCubemapsEqualAFreshBake) {
  const glm::vec3 relit(2.0f, 1.0f, 0.5f);
  BakeOptions options = draftOptions();
  options.reflections.bounces = 2;
  scenes::Scene scene = mirrorCorridor(0.8f, 1.0f);
  scene.reflectionProbes.push_back(probeAt(glm::vec3(0.1f, 0.2f, 0.0f), glm::vec3(0.0f), 8));
  scene.reflectionProbes.push_back(probeAt(glm::vec3(-0.1f, 3.0f, 1.0f), glm::vec3(1.0f, 4.0f, 4.0f), 4));
  const BakeResult baked = bakeOrDie(scene, options);
  scene.materials[0].emissiveFactor = relit;
  const BakeResult fresh = bakeOrDie(scene, options);
  ASSERT_EQ(fresh.reflectionChains.size(), 3u);

  std::string error;
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::fromData(baked.transport, &error);
  ASSERT_TRUE(rt) << error;
  ASSERT_EQ(rt->reflectionProbeCount(), 3);
  ASSERT_TRUE(rt->setEmission("mirror", relit));
  runtime::UpdateOptions update;
  update.fromScratch = true;
  update.maxBounces = 0;
  update.tolerance = options.solve.tolerance;
  const runtime::UpdateStats stats = rt->update(update);
  EXPECT_EQ(stats.reflectionPasses, 6);  // (2 bounces + 1) × 2 probes
  size_t compared = 0, differ = 0;
  for (int probe = 0; probe < rt->reflectionProbeCount(); ++probe)
    for (int mip = 0; mip < rt->reflectionMipCount(); ++mip)
      for (int face = 0; face < runtime::kCubeFaceCount; ++face) {
        const int size = rt->reflectionFaceSize(probe, mip);
        const runtime::Cubemap& want = fresh.reflectionChains[size_t(probe)][size_t(mip)];
        ASSERT_EQ(size, want.size);
        std::vector<float> rgb(size_t(size) * size_t(size) * 3);
        ASSERT_TRUE(rt->readCubemap(probe, mip, face, rgb.data()));
        for (int y = 0; y < size; ++y)
          for (int x = 0; x < size; ++x)
            for (int c = 0; c < 3; ++c, ++compared)
              differ += rgb[(size_t(y) * size_t(size) + size_t(x)) * 3 + size_t(c)] !=
                        want.at(face, x, y)[c];
      }
  EXPECT_EQ(differ, 0u) << "of " << compared << " values";
  // Units spread over calls reach the same round: one at a time, a round later, equal again.
  rt->setEmission("mirror", glm::vec3(1.0f));
  rt->update({});
  rt->setEmission("mirror", relit);
  update.reflectionPasses = 0;
  rt->update(update);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(rt->updateReflectionProbes(1).reflectionPasses, 1);
  const runtime::CubemapChain again = rt->reflectionChain(2);
  EXPECT_EQ(again[0].texels, fresh.reflectionChains[2][0].texels);
  // A budget smaller than one unit still runs one, and no more.
  EXPECT_EQ(rt->updateReflectionProbes(-1, 1e-6).reflectionPasses, 1);
}

// McGuire's Cornell box: a probe's mirror mip against the reference path tracer's radiance
// along the very rays of its texels, the reference following one GGX reflection as the bake's
// one reflection bounce does (PathTracer::probeRadiance). The walls are rough dielectrics: the
// texels are mostly diffuse × lightmap (the lightmaps' own error, issue 3's figures) plus a
// rough specular share that the split sum, box projection and the probes' view from their
// capture position approximate (without the corrections in ReflectionLighting::specular, 9.6%).
TEST(ReflectionBake, CornellMirrorMipMatchesTheReference) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  Result<scenes::Scene> loaded = scenes::loadGltf(path);
  ASSERT_TRUE(loaded) << loaded.message();
  scenes::Scene scene = std::move(loaded.value());
  for (scenes::Material& m : scene.materials) m.singleSidedEmission = true;  // as issue 3's
  unwrapAt(scene, 16.0f);
  const scenes::Bounds bounds = scene.bounds();
  const glm::vec3 centre = bounds.min + (bounds.max - bounds.min) * glm::vec3(0.5f, 0.6f, 0.5f);
  const int resolution = 128, stride = 8;  // Unity's default face; a 16² grid of its texels
  scene.reflectionProbes.push_back(probeAt(centre, glm::vec3(0.0f), resolution));
  const BakeResult r = bakeOrDie(scene, BakeOptions());
  ASSERT_EQ(r.reflectionChains.size(), 2u);
  const runtime::Cubemap& mip0 = r.reflectionChains[1][0];
  std::vector<trace::Ray> rays;
  std::vector<glm::vec3> baked;
  for (int face = 0; face < runtime::kCubeFaceCount; ++face)
    for (int y = stride / 2; y < mip0.size; y += stride)
      for (int x = stride / 2; x < mip0.size; x += stride) {
        trace::Ray ray;
        ray.origin = r.transport.reflections.probes[0].box.capturePosition;
        ray.direction = runtime::cubemapTexelDirection(face, x, y, mip0.size);
        rays.push_back(ray);
        baked.push_back(mip0.at(face, x, y));
      }
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  ReferenceOptions ref;
  ref.samples = 4096;
  ref.specularDepth = 1;  // the bake's one reflection bounce
  Result<ReferencePoints> reference = referenceRadiance(scene, *tracer.value(), Environment(), rays, ref);
  ASSERT_TRUE(reference) << reference.message();
  // compareToReference's relative error: per texel against its own reference, with a floor of
  // 10% of the mean (the open side's black texels).
  double mean = 0.0;
  for (const glm::vec3& v : reference->irradiance) mean += double(glm::length(v));
  mean /= double(rays.size());
  const double floor = 0.1 * mean;
  double squares = 0.0, bias = 0.0, noise = 0.0;
  for (size_t k = 0; k < rays.size(); ++k) {
    const glm::vec3 mine = baked[k], want = reference->irradiance[k];
    const double scale = std::max(double(glm::length(want)), floor);
    squares += std::pow(double(glm::length(mine - want)) / scale, 2.0);
    bias += (double(mine.x + mine.y + mine.z) - double(want.x + want.y + want.z)) /
            std::max(double(want.x + want.y + want.z), floor * std::sqrt(3.0));
    const glm::vec3 v = reference->variance[k];
    noise += double(v.x + v.y + v.z) / (scale * scale);
  }
  const double rmse = std::sqrt(squares / double(rays.size()));
  bias /= double(rays.size());
  noise = std::sqrt(noise / double(rays.size()));
  std::printf("reflection probe, McGuire's Cornell box, 128² probe, 6 x 16² texels: relative "
              "RMSE %.2f%%, bias %+.2f%% (the reference's own noise %.2f%%)\n",
              100 * rmse, 100 * bias, 100 * noise);
  EXPECT_LT(rmse, 0.05);
}

}  // namespace
}  // namespace afterglow::baker
