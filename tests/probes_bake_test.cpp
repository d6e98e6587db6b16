// Light probes baked from the transport (baker::computeProbeTransfer, Solver::probeRadiance)
// against answers known without the baker: the glTF furnace (Le / (1 − ρ) from every
// direction), a probe in the open under a constant sky (E/π = L for every normal), one
// directional light (its clamped cosine's SH), the Cornell box against the reference path
// tracer at free points; the probes the same for any thread count, sampled at their own
// positions, and refreshed alone within a budget. (Relit probes against a fresh bake's:
// relight_test.cpp through the API, cli_relight_test.cpp through the CLI.)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/core/parallel.h"
#include <memory>
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/scenes/gltf.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::baker {
namespace {

const glm::vec3 kAxes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

runtime::ProbeTetrahedra meshOf(const std::vector<glm::vec3>& positions) {
  Result<runtime::ProbeTetrahedra> mesh = probes::tetrahedralize(positions);
  EXPECT_TRUE(mesh) << mesh.message();
  return mesh ? mesh.value() : runtime::ProbeTetrahedra{};
}

// A 3×3×3 grid of probes filling [-extent, extent]³.
std::vector<glm::vec3> gridProbes(float extent) {
  std::vector<glm::vec3> out;
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x) out.emplace_back(float(x) * extent, float(y) * extent, float(z) * extent);
  return out;
}

// In the glTF furnace (specularFactor 0, so ρ is the base colour) every probe sees Le / (1 − ρ)
// from every direction: E/π is that for every normal.
TEST(ProbesBake, FurnaceEveryProbeAndNormalIsLeOverOneMinusRho) {
  const float rho = 0.5f;
  const scenes::Scene scene = furnaceLevel("probes", rho, {{"specularFactor", 0.0}});
  BakeOptions options = draftOptions();
  options.links.texelRays = 256;
  options.links.clusterRays = 1024;
  options.direct.emissiveSamples = 1024;
  options.solve.tolerance = 1e-6f;
  options.probes = meshOf(gridProbes(0.3f));
  const BakeResult r = bakeOrDie(scene, options);
  ASSERT_EQ(r.probeSh.size(), 27u);
  const float expected = 1.0f / (1.0f - rho);
  float worst = 0.0f;
  for (const runtime::ShL2& sh : r.probeSh)
    for (const glm::vec3& n : kAxes) {
      const glm::vec3 e = runtime::irradianceOverPi(sh, n);
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(e[k] / expected - 1.0f));
    }
  EXPECT_LT(worst, 0.01f);
  std::printf("probe furnace rho %.1f: worst relative error %.4f over 27 probes x 6 normals\n", rho,
              worst);
}

// A ground plate of side 4 m (specularFactor 0): under a probe far above it, it covers a sliver
// of the probe's sphere, so the probe sees the sky's constant radiance L as E/π = L for every
// normal; under a sun, nothing stands between probes above it and the light.
scenes::Scene groundPlate(float albedo) { return groundQuad("plate", 2.0f, albedo, 0.0f); }

// A directional light from above, unit colour and intensity unless given.
scenes::Light sunLight(float intensity = 1.0f, glm::vec3 color = glm::vec3(1.0f)) {
  scenes::Light sun;
  sun.name = "sun";
  sun.type = scenes::LightType::Directional;
  sun.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
  sun.intensity = intensity;
  sun.color = color;
  return sun;
}

TEST(ProbesBake, ProbeInTheOpenSeesTheConstantSky) {
  scenes::Scene scene = groundPlate(0.0f);
  unwrapAt(scene, 4.0f);
  BakeOptions options = draftOptions();
  const glm::vec3 sky(0.3f, 0.5f, 0.9f);
  options.skyColor = sky;
  // Probes high above the plate: it covers a sliver of their sphere.
  std::vector<glm::vec3> positions;
  for (glm::vec3 p : gridProbes(1.0f)) positions.push_back(p + glm::vec3(0.0f, 1000.0f, 0.0f));
  options.probes = meshOf(positions);
  const BakeResult r = bakeOrDie(scene, options);
  ASSERT_EQ(r.probeSh.size(), positions.size());
  float worst = 0.0f;
  for (const runtime::ShL2& sh : r.probeSh)
    for (const glm::vec3& n : kAxes) {
      const glm::vec3 e = runtime::irradianceOverPi(sh, n);
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(e[k] / sky[k] - 1.0f));
    }
  EXPECT_LT(worst, 1e-3f);
}

// A closed room 4 × 3 × 4 m (grey walls facing in, specularFactor 0), or the same with a 1 × 1 m
// window cut in the middle of its ceiling.
scenes::Scene roomUnderTheSky(bool window) {
  scenes::Scene scene = groundQuad("room", 2.0f, 0.5f, 0.0f);  // the floor, y = 0, facing up
  scenes::Primitive& p = scene.meshes[0].primitives[0];
  // A quad a b c d, counter-clockwise seen from the room, facing n.
  auto quad = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 n) {
    addQuad(p, a, b, c, d, n);
  };
  const float h = 3.0f;
  addRoomWalls(p, 2.0f, h);
  // The ceiling facing down, whole or as four slabs around the window |x|, |z| < 0.5.
  auto ceiling = [&](float x0, float x1, float z0, float z1) {
    quad({x0, h, z0}, {x1, h, z0}, {x1, h, z1}, {x0, h, z1}, {0, -1, 0});
  };
  if (!window) {
    ceiling(-2, 2, -2, 2);
  } else {
    ceiling(-2, 2, -2, -0.5f);
    ceiling(-2, 2, 0.5f, 2);
    ceiling(-2, -0.5f, -0.5f, 0.5f);
    ceiling(0.5f, 2, -0.5f, 0.5f);
  }
  return scene;
}

// A closed room has no sky: under a sky of radiance 1 and no other light, every probe inside
// reads E/π below 1e-6 for every normal (its rays all hit the walls; the grid's quadrature error
// once read as a sky of a few thousandths, some of it negative). Cut a window in the ceiling
// and the probe half a metre under it sees the sky through it: E/π upwards at least the window's
// form factor (0.554: four 0.5 × 0.5 m corner rectangles at 0.5 m, the sky's radiance 1), the
// walls' bounce on top.
TEST(ProbesBake, AClosedRoomHasNoSkyAndAWindowLetsItIn) {
  std::vector<glm::vec3> positions;
  for (glm::vec3 p : gridProbes(1.2f)) positions.push_back(p + glm::vec3(0.0f, 1.5f, 0.0f));
  positions.emplace_back(0.0f, 2.5f, 0.0f);  // under the window
  BakeOptions options = draftOptions();
  options.skyColor = glm::vec3(1.0f);
  options.probes = meshOf(positions);

  scenes::Scene closed = roomUnderTheSky(false);
  unwrapAt(closed, 4.0f);
  const BakeResult dark = bakeOrDie(closed, options);
  ASSERT_EQ(dark.probeSh.size(), positions.size());
  float brightest = 0.0f;
  for (const runtime::ShL2& sh : dark.probeSh)
    for (const glm::vec3& n : kAxes) {
      const glm::vec3 e = runtime::irradianceOverPi(sh, n);
      brightest = std::max({brightest, std::abs(e.r), std::abs(e.g), std::abs(e.b)});
    }
  EXPECT_LT(brightest, 1e-6f);

  scenes::Scene open = roomUnderTheSky(true);
  unwrapAt(open, 4.0f);
  const BakeResult lit = bakeOrDie(open, options);
  ASSERT_EQ(lit.probeSh.size(), positions.size());
  const glm::vec3 up = runtime::irradianceOverPi(lit.probeSh.back(), glm::vec3(0, 1, 0));
  EXPECT_GT(up.g, 0.554f * 0.95f);
  std::printf("closed room: brightest probe |E/pi| %.2g; with a window, E/pi up under it %.3f\n",
              double(brightest), double(up.g));
}

// One directional light and nothing in its way: a probe's SH is the light's E⊥ times the basis
// at the direction to the light, so E/π is the clamped cosine's L2 series.
TEST(ProbesBake, DirectionalLightGivesItsClampedCosine) {
  scenes::Scene scene = groundPlate(0.0f);
  unwrapAt(scene, 4.0f);
  scenes::Light sun = sunLight(3.0f, glm::vec3(1.0f, 0.8f, 0.6f));
  sun.angularDiameter = 0.0f;  // a point on the sky: its SH is the basis at one direction
  scene.lights.push_back(sun);
  BakeOptions options = draftOptions();
  std::vector<glm::vec3> positions;
  for (glm::vec3 p : gridProbes(1.0f)) positions.push_back(p + glm::vec3(0.0f, 2.0f, 0.0f));
  options.probes = meshOf(positions);
  const BakeResult r = bakeOrDie(scene, options);
  ASSERT_EQ(r.probeSh.size(), positions.size());
  const glm::vec3 toSun = -sun.direction;
  float y[runtime::kShCount];
  runtime::shBasis(toSun, y);
  float worst = 0.0f;
  for (const runtime::ShL2& sh : r.probeSh)
    for (int i = 0; i < runtime::kShCount; ++i) {
      const glm::vec3 expected = sun.color * sun.intensity * y[i];
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(sh.c[i][k] - expected[k]));
    }
  EXPECT_LT(worst, 1e-4f * sun.intensity);
}

// Relative errors over (point, normal) pairs as the accuracy bench measures texels
// (reference.h, compareToReference): per pair ‖bake − ref‖ / max(‖ref‖, floor) and the signed
// relative difference of the channel sums, the floor 10% of the mean.
struct PairErrors {
  double rmse = 0.0, bias = 0.0;
};
PairErrors compare(const std::vector<glm::vec3>& baked, const std::vector<glm::vec3>& ref) {
  double mean = 0.0;
  for (const glm::vec3& v : ref) mean += double(v.x + v.y + v.z);
  mean /= double(ref.size());
  const double floor = 0.1 * mean;
  PairErrors e;
  for (size_t k = 0; k < ref.size(); ++k) {
    const glm::vec3 d = baked[k] - ref[k];
    const double scale = std::max(double(glm::length(ref[k])), floor / std::sqrt(3.0));
    e.rmse += double(glm::dot(d, d)) / (scale * scale);
    e.bias += double(d.x + d.y + d.z) / std::max(double(ref[k].x + ref[k].y + ref[k].z), floor);
  }
  e.rmse = std::sqrt(e.rmse / double(ref.size()));
  e.bias /= double(ref.size());
  return e;
}

// McGuire's Cornell box lit by its ceiling lamp, 20 free points × 6 axis normals. Against the
// reference path tracer's irradiance the probes carry two errors: the transport's, and SH L2's
// own (three bands cannot hold a lamp's sharp edge: a normal facing away from the lamp reads
// 15-20% dark, as in every engine's L2 probes). So the reference's radiance is also projected
// onto SH L2 at each point: the bake must match that within 3% (RMSE) and 1% (bias), and be no
// further from the true irradiance than that projection is.
TEST(ProbesBake, CornellMatchesTheReferenceAtFreePoints) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  Result<scenes::Scene> loaded = scenes::loadGltf(path);
  ASSERT_TRUE(loaded) << loaded.message();
  scenes::Scene scene = std::move(loaded.value());
  // The lamp lights the room from its front only, as in the lightmaps' accuracy figures (issue
  // 3): its back, 1 cm below the ceiling, lights a cavity whose light leaves through a slit the
  // probes' rays rarely find (see the README: with it the probes read about 5% dark).
  for (scenes::Material& m : scene.materials) m.singleSidedEmission = true;
  unwrapAt(scene, 16.0f);
  BakeOptions options;  // the default quality
  // Probes on a grid inside the box, above the tall block.
  const scenes::Bounds box = scene.bounds();
  const glm::vec3 size = box.max - box.min;
  std::vector<glm::vec3> positions;
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x)
        positions.push_back(box.min + size * glm::vec3(0.15f + 0.233f * float(x),
                                                       0.62f + 0.09f * float(y),
                                                       0.15f + 0.233f * float(z)));
  options.probes = meshOf(positions);
  const BakeResult r = bakeOrDie(scene, options);
  ASSERT_EQ(r.probeSh.size(), positions.size());
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  std::vector<glm::vec3> points, pointNormals, normals;
  std::vector<size_t> which;
  for (size_t i = 0; i < positions.size() && which.size() < 20; i += 3) which.push_back(i);
  for (size_t i : which) {
    points.push_back(positions[i]);
    for (const glm::vec3& n : kAxes) {
      pointNormals.push_back(positions[i]);
      normals.push_back(n);
    }
  }
  ReferenceOptions ro;
  ro.samples = 4096;
  Result<ReferencePoints> ref = referenceIrradiance(scene, *tracer.value(), {}, pointNormals, normals, ro);
  ASSERT_TRUE(ref) << ref.message();
  ro.samples = 1 << 16;
  Result<std::vector<runtime::ShL2>> refSh = referenceRadianceSh(scene, *tracer.value(), {}, points, ro);
  ASSERT_TRUE(refSh) << refSh.message();
  std::vector<glm::vec3> baked, projected;
  for (size_t k = 0; k < normals.size(); ++k) {
    baked.push_back(runtime::irradianceOverPi(r.probeSh[which[k / 6]], normals[k]));
    projected.push_back(runtime::irradianceOverPi(refSh.value()[k / 6], normals[k]));
  }
  const PairErrors vsSh = compare(baked, projected);
  const PairErrors vsIrradiance = compare(baked, ref->irradiance);
  const PairErrors shItself = compare(projected, ref->irradiance);
  std::printf("probes, McGuire's Cornell box, %zu points x 6 normals:\n"
              "  bake vs the reference projected on SH L2: relative RMSE %.2f%%, bias %+.2f%%\n"
              "  bake vs the reference's irradiance:       relative RMSE %.2f%%, bias %+.2f%%\n"
              "  SH L2 itself (projected vs irradiance):   relative RMSE %.2f%%, bias %+.2f%%\n",
              which.size(), 100 * vsSh.rmse, 100 * vsSh.bias, 100 * vsIrradiance.rmse,
              100 * vsIrradiance.bias, 100 * shItself.rmse, 100 * shItself.bias);
  EXPECT_LT(vsSh.rmse, 0.03);
  EXPECT_LT(std::abs(vsSh.bias), 0.01);
  // Against the irradiance itself the bake is as far off as SH L2 is, and no further.
  EXPECT_LT(vsIrradiance.rmse, shItself.rmse + 0.01);
  EXPECT_LT(std::abs(vsIrradiance.bias - shItself.bias), 0.01);
}

// The probes come out the same for any thread count, and the runtime's sampling at a probe's
// own position returns that probe, relit from the transport exactly as baked.
TEST(ProbesBake, DeterministicAndSampledAtTheProbesThemselves) {
  scenes::Scene scene = scenes::makeCornellBox();
  unwrapAt(scene, 16.0f);
  BakeOptions options = draftOptions();
  const scenes::Bounds box = scene.bounds();
  std::vector<glm::vec3> positions;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 3; ++x)
        positions.push_back(box.min + (box.max - box.min) *
                                          glm::vec3(0.2f + 0.3f * float(x), 0.65f + 0.1f * float(y),
                                                    0.2f + 0.3f * float(z)));
  options.probes = meshOf(positions);
  setThreadCount(1);
  const BakeResult one = bakeOrDie(scene, options);
  setThreadCount(2);
  const BakeResult two = bakeOrDie(scene, options);
  setThreadCount(0);
  ASSERT_EQ(one.probeSh.size(), positions.size());
  ASSERT_EQ(two.probeSh.size(), positions.size());
  for (size_t p = 0; p < positions.size(); ++p)
    for (int i = 0; i < runtime::kShCount; ++i)
      ASSERT_EQ(one.probeSh[p].c[i], two.probeSh[p].c[i]) << "probe " << p << " coefficient " << i;

  std::string error;
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::fromData(one.transport, &error);
  ASSERT_TRUE(rt) << error;
  runtime::UpdateOptions update;
  update.fromScratch = true;
  const runtime::UpdateStats stats = rt->update(update);
  EXPECT_EQ(stats.probes, int(positions.size()));
  ASSERT_EQ(rt->probeCount(), int(positions.size()));
  int hint = 0;
  for (size_t p = 0; p < positions.size(); ++p) {
    EXPECT_EQ(rt->probePosition(int(p)), positions[p]);
    runtime::ShL2 own;
    ASSERT_TRUE(rt->probeSh(int(p), &own));
    const runtime::ShL2 sampled = rt->sampleProbes(positions[p], &hint);
    for (int i = 0; i < runtime::kShCount; ++i) {
      EXPECT_EQ(own.c[i], one.probeSh[p].c[i]) << "probe " << p;
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(sampled.c[i][k], own.c[i][k], 1e-5f * (1.0f + std::abs(own.c[0][k])))
            << "probe " << p << " coefficient " << i;
    }
  }
}

// An engine may refresh the probes apart from the lightmaps, a few at a time: after a light
// changes, updates without the probes leave them as they were, and budgeted updateProbes() calls
// (one block of 256 each, at a budget no block fits) come round to every probe, ending equal
// to a full refresh.
TEST(ProbesBake, ProbesRefreshAloneWithinABudget) {
  scenes::Scene scene = groundPlate(0.5f);
  unwrapAt(scene, 4.0f);
  scene.lights.push_back(sunLight());
  BakeOptions options = draftOptions();
  std::vector<glm::vec3> positions;
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 10; ++x)
        positions.emplace_back(-1.5f + 0.3f * float(x), 0.2f + 0.3f * float(y), -1.5f + 0.4f * float(z));
  options.probes = meshOf(positions);
  const BakeResult r = bakeOrDie(scene, options);
  std::string error;
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::fromData(r.transport, &error);
  ASSERT_TRUE(rt) << error;
  rt->update();
  runtime::ShL2 before;
  ASSERT_TRUE(rt->probeSh(0, &before));
  ASSERT_TRUE(rt->setLightColor("sun", glm::vec3(0.2f, 0.4f, 1.0f)));
  runtime::UpdateOptions noProbes;
  noProbes.probes = false;
  EXPECT_EQ(rt->update(noProbes).probes, 0);
  runtime::ShL2 unchanged;
  ASSERT_TRUE(rt->probeSh(0, &unchanged));
  for (int i = 0; i < runtime::kShCount; ++i) EXPECT_EQ(unchanged.c[i], before.c[i]);

  const int n = rt->probeCount();
  ASSERT_EQ(n, 640);
  int refreshed = 0, calls = 0;
  while (refreshed < n && calls < 100) {
    const runtime::UpdateStats s = rt->updateProbes(1e-9);
    EXPECT_EQ(s.probes, std::min(256, n - refreshed)) << "call " << calls;
    refreshed += s.probes;
    ++calls;
  }
  EXPECT_EQ(calls, 3);
  std::vector<runtime::ShL2> budgeted(static_cast<size_t>(n));
  for (int p = 0; p < n; ++p) ASSERT_TRUE(rt->probeSh(p, &budgeted[size_t(p)]));
  EXPECT_EQ(rt->updateProbes().probes, n);
  for (int p = 0; p < n; ++p) {
    runtime::ShL2 full;
    ASSERT_TRUE(rt->probeSh(p, &full));
    for (int i = 0; i < runtime::kShCount; ++i) ASSERT_EQ(budgeted[size_t(p)].c[i], full.c[i]);
  }
  EXPECT_NE(budgeted[0].c[0], before.c[0]) << "the light's change must show";
}

}  // namespace
}  // namespace afterglow::baker
