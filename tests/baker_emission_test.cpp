// Emissive surfaces as glTF defines them: a double-sided emissive material emits from both sides
// (extras.afterglow.singleSidedEmission restricts it to its front). Checked where a mistake
// hides best, a lamp panel just below a ceiling (the McGuire Cornell box's lamp hangs 1 cm below
// its ceiling): the light its back pours into the thin cavity must be neither lost nor
// amplified. The check is a power balance, which needs no other renderer: in a closed room every
// watt the panel emits is absorbed somewhere, Σ (1 − ρ) E A over every surface (both sides of the
// panel) = 2 π Le A_panel, or in the lightmaps' E/π, Σ (1 − ρ) (E/π) A = 2 Le A_panel.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/material_eval.h"
#include "afterglow/uv/unwrap.h"
#include "reference/path_tracer.h"
#include "bake_fixtures.h"
#include "shading/sampling.h"

namespace afterglow::baker {
namespace {

constexpr float kRoom = 1.0f;    // metres: a closed cube [0, 1]³
constexpr float kPanel = 0.4f;   // metres: the lamp panel's side, centred under the ceiling
constexpr float kLe = 1.0f;      // the panel's emitted radiance
// Texels of 3 cm, three times the gap under the lamp: the cavity's texels are wider than the
// cavity is deep, and must stay in the bake all the same (gatherTexels keeps a texel whose whole
// footprint lies under an emitter shining on it). When they were buried as wedged in a gap,
// the light of the panel's back went nowhere: this room kept 66% of the power balance.
constexpr float kTexelsPerUnit = 32.0f;

// One axis-aligned rectangle of the room: its corner, two edges and its front normal.
struct Rect {
  glm::vec3 origin, u, v;
  glm::vec3 normal;
  int instance;  // which instance it belongs to (walls 0..5, the panel 6)
  float area() const { return glm::length(glm::cross(u, v)); }
};

// The room's six walls face inwards (single-sided), the panel hangs `gap` below the ceiling,
// its front facing down, double-sided, emitting kLe. Both materials are Lambertian.
struct LampRoom {
  scenes::Scene scene;
  std::vector<Rect> rects;  // the walls, then the panel's front (facing down)
};

void addRect(scenes::Scene& scene, std::vector<Rect>& rects, const char* name, int material,
             glm::vec3 origin, glm::vec3 u, glm::vec3 v, glm::vec3 front) {
  if (glm::dot(glm::cross(u, v), front) < 0.0f) std::swap(u, v);  // counter-clockwise front
  scenes::Primitive prim;
  prim.material = material;
  for (const glm::vec3& p : {origin, origin + u, origin + u + v, origin + v}) {
    prim.positions.push_back(p);
    prim.normals.push_back(front);
  }
  prim.indices = {0, 1, 2, 0, 2, 3};
  scenes::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(std::move(prim));
  scenes::Instance inst;
  inst.name = name;
  inst.mesh = int(scene.meshes.size());
  scene.meshes.push_back(std::move(mesh));
  scene.instances.push_back(std::move(inst));
  rects.push_back({origin, u, v, front, int(scene.instances.size()) - 1});
}

LampRoom lampRoom(float panelY, float wallColour, float lampColour, bool singleSidedEmission) {
  LampRoom room;
  scenes::Scene& s = room.scene;
  scenes::Material wall;
  wall.name = "wall";
  wall.baseColorFactor = glm::vec4(glm::vec3(wallColour), 1.0f);
  wall.metallicFactor = 0.0f;
  wall.roughnessFactor = 1.0f;
  wall.specularFactor = 0.0f;  // Lambertian: the bounce albedo is the base colour
  scenes::Material lamp = wall;
  lamp.name = "lamp";
  lamp.baseColorFactor = glm::vec4(glm::vec3(lampColour), 1.0f);
  lamp.doubleSided = true;
  lamp.singleSidedEmission = singleSidedEmission;
  lamp.emissiveFactor = glm::vec3(kLe);
  s.materials = {wall, lamp};
  const glm::vec3 x(kRoom, 0, 0), y(0, kRoom, 0), z(0, 0, kRoom), o(0.0f);
  addRect(s, room.rects, "floor", 0, o, x, z, {0, 1, 0});
  addRect(s, room.rects, "ceiling", 0, y, x, z, {0, -1, 0});
  addRect(s, room.rects, "left", 0, o, y, z, {1, 0, 0});
  addRect(s, room.rects, "right", 0, x, y, z, {-1, 0, 0});
  addRect(s, room.rects, "back", 0, o, x, y, {0, 0, 1});
  addRect(s, room.rects, "front", 0, z, x, y, {0, 0, -1});
  const float lo = 0.5f * (kRoom - kPanel);
  addRect(s, room.rects, "panel", 1, {lo, panelY, lo}, {kPanel, 0, 0}, {0, 0, kPanel},
          {0, -1, 0});
  return room;
}

// The bounce albedo of an instance's material (its red channel: the room is grey).
float albedoOf(const scenes::Scene& scene, uint32_t instance) {
  const int mesh = scene.instances[instance].mesh;
  return diffuseAlbedo(scene, scene.meshes[size_t(mesh)].primitives[0].material, glm::vec2(0.0f)).x;
}

// Σ (1 − ρ) (E/π) A as the bake sees it: the lightmaps over every covered texel (buried ones
// hold what the lightmap fills them with), and for the panel's back the back-side clusters'
// E/π = R/ρ over the panel's whole area.
double bakeAbsorbed(const scenes::Scene& scene, const BakeResult& b, int panelInstance) {
  double sum = 0.0;
  for (size_t a = 0; a < b.lightmaps.size(); ++a) {
    const runtime::AtlasLayout& layout = b.texels.atlases[a];
    for (size_t p = 0; p < layout.texelOfPixel.size(); ++p) {
      const uint32_t t = layout.texelOfPixel[p];
      if (t == runtime::kNoTexel) continue;
      sum += (1.0 - double(albedoOf(scene, b.texels.instance[t]))) *
             double(b.lightmaps[a][p].x) * double(b.texels.area[t]);
    }
  }
  runtime::TransportData data = b.transport;
  runtime::Solver solver(data);
  runtime::SolveOptions solve;
  solve.tolerance = 1e-6f;
  solver.solve(solve);
  double backArea = 0.0, backLight = 0.0;
  for (size_t c = 0; c < b.clusters.area.size(); ++c) {
    if (!b.clusters.back[c]) continue;
    const uint32_t t = b.clusters.memberTexels[b.clusters.firstTexel[c]];
    EXPECT_EQ(int(b.texels.instance[t]), panelInstance) << "only the panel is double-sided";
    backArea += double(b.clusters.area[c]);
    backLight += double(b.clusters.area[c]) * double(solver.clusterReflected()[c].x) /
                 double(solver.clusterAlbedo()[c].x);
  }
  // Rays from the ceiling see the whole back, so its clusters cover (nearly) all of it.
  EXPECT_GT(backArea, 0.95 * double(kPanel * kPanel));
  if (backArea > 0.0)
    sum += (1.0 - double(albedoOf(scene, uint32_t(panelInstance)))) * backLight / backArea *
           double(kPanel * kPanel);
  return sum;
}

// The same from the reference path tracer: stratified points over every surface, both sides
// of the panel, each estimating E/π with `paths` paths.
double referenceAbsorbed(const LampRoom& room, int pointsPerMetre, int paths) {
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(room.scene);
  EXPECT_TRUE(tracer) << tracer.message();
  if (!tracer) return 0.0;
  const PathTracer pt(room.scene, *tracer.value(), Environment(), 64);
  std::vector<Rect> surfaces = room.rects;
  Rect back = room.rects.back();
  back.normal = -back.normal;
  surfaces.push_back(back);
  double sum = 0.0;
  uint64_t item = 0;
  for (const Rect& r : surfaces) {
    const int nu = std::max(2, int(std::lround(glm::length(r.u) * float(pointsPerMetre))));
    const int nv = std::max(2, int(std::lround(glm::length(r.v) * float(pointsPerMetre))));
    double rectSum = 0.0;
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j, ++item) {
        sampling::Rng rng(sampling::Stream::Reference, item, 0);
        const glm::vec2 jitter = rng.next2();
        glm::vec3 p = r.origin + (float(i) + jitter.x) / float(nu) * r.u +
                      (float(j) + jitter.y) / float(nv) * r.v;
        p += r.normal * 1e-4f;
        glm::vec3 e(0.0f);
        for (int k = 0; k < paths; ++k) {
          sampling::Rng path(sampling::Stream::Reference, item, uint64_t(k) + 1);
          const PathTracer::Estimate est = pt.irradiance(
              p, r.normal, r.normal, sampling::stratified2(path, uint32_t(k), uint32_t(paths)),
              path);
          e += est.direct + est.indirect;
        }
        rectSum += double(e.x) / double(paths);
      }
    sum += (1.0 - double(albedoOf(room.scene, uint32_t(r.instance)))) * rectSum /
           double(nu * nv) * double(r.area());
  }
  return sum;
}

struct BalanceCase {
  float gap;     // metres between the panel and the ceiling
  float wall;    // the walls' albedo
  float lamp;    // the panel's
};

class PowerBalance : public ::testing::TestWithParam<BalanceCase> {};

TEST_P(PowerBalance, AbsorbedLightEqualsWhatBothSidesOfTheLampEmit) {
  const BalanceCase c = GetParam();
  LampRoom room = lampRoom(kRoom - c.gap, c.wall, c.lamp, false);
  const double emitted = 2.0 * double(kLe) * double(kPanel * kPanel);  // /π, both sides

  const double reference = referenceAbsorbed(room, 40, 64);
  unwrapAt(room.scene, kTexelsPerUnit);
  BakeOptions options;
  options.solve.tolerance = 1e-6f;
  const BakeResult b = bakeOrDie(room.scene, options);
  const double baked = bakeAbsorbed(room.scene, b, room.rects.back().instance);
  std::printf("gap %.3f m, albedo walls %.3f lamp %.3f: absorbed / emitted: bake %.4f, "
              "reference %.4f\n", c.gap, c.wall, c.lamp, baked / emitted, reference / emitted);
  EXPECT_NEAR(reference / emitted, 1.0, 0.01);
  EXPECT_NEAR(baked / emitted, 1.0, 0.01);
}

std::string balanceCaseName(const ::testing::TestParamInfo<BalanceCase>& info) {
  static const char* const kNames[] = {"Cavity", "NoCavity", "WhiteLampCavity"};
  return kNames[info.index];
}

// The panel 1 cm below the ceiling (a cavity) and halfway down the room (none); and the McGuire
// Cornell box's cavity, a white lamp under a ceiling of albedo 0.725, where light bounces many
// times before it escapes.
INSTANTIATE_TEST_SUITE_P(Gap, PowerBalance,
                         ::testing::Values(BalanceCase{0.01f, 0.5f, 0.5f},
                                           BalanceCase{0.5f, 0.5f, 0.5f},
                                           BalanceCase{0.01f, 0.725f, 1.0f}),
                         balanceCaseName);

// The ceiling above the middle of the panel, 1 cm away: the panel's back fills nearly its whole
// hemisphere, so it gets about Le plus what the cavity bounces. The bake must give what the
// reference path tracer gives there; a front-only lamp leaves it dark.
TEST(DoubleSidedEmission, TheCeilingAboveALampPanelGetsTheLightOfItsBack) {
  for (bool singleSided : {false, true}) {
    LampRoom room = lampRoom(kRoom - 0.01f, 0.5f, 0.5f, singleSided);
    unwrapAt(room.scene, kTexelsPerUnit);
    const BakeResult b = bakeOrDie(room.scene, BakeOptions());
    const uint32_t ceiling = uint32_t(room.rects[1].instance);
    std::vector<uint32_t> above, dark;
    for (uint32_t t = 0; t < b.texels.size(); ++t) {
      const glm::vec3 p = b.texels.position[t];
      if (b.texels.instance[t] == ceiling && std::abs(p.x - 0.5f) < 0.15f &&
          std::abs(p.z - 0.5f) < 0.15f)
        (b.texels.valid[t] ? above : dark).push_back(t);
    }
    if (singleSided) {
      // Nothing shines into the cavity but what slips through the gap: its texels are buried
      // as wedged in a gap (and any kept is dark).
      double most = 0.0;
      for (uint32_t t : above)
        most = std::max(most, double(b.texelDirect[t].x + b.texelIndirect[t].x));
      std::printf("front-only lamp: %zu of %zu ceiling texels above it buried, the rest at most "
                  "E/pi %.5f\n", dark.size(), dark.size() + above.size(), most);
      EXPECT_GT(dark.size() + above.size(), 50u);
      EXPECT_LT(most, 0.002 * double(kLe));
      continue;
    }
    // The lamp's back shines on the cavity: every texel there stays in the bake.
    EXPECT_TRUE(dark.empty()) << dark.size() << " ceiling texels above the lamp buried";
    ASSERT_GT(above.size(), 50u);
    double baked = 0.0;
    for (uint32_t t : above) baked += double(b.texelDirect[t].x + b.texelIndirect[t].x);
    baked /= double(above.size());
    Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(room.scene);
    ASSERT_TRUE(tracer) << tracer.message();
    ReferenceOptions high;
    high.samples = 2048;
    Result<ReferenceTexels> ref =
        referenceTexels(room.scene, *tracer.value(), b.texels, Environment(), high, above);
    ASSERT_TRUE(ref) << ref.message();
    double reference = 0.0;
    for (size_t k = 0; k < above.size(); ++k)
      reference += double(ref->direct[k].x + ref->indirect[k].x);
    reference /= double(above.size());
    std::printf("double-sided lamp: ceiling above it E/pi bake %.4f, reference %.4f\n", baked,
                reference);
    EXPECT_GT(reference, 0.99 * double(kLe));
    EXPECT_NEAR(baked / reference, 1.0, 0.02);
  }
}

}  // namespace
}  // namespace afterglow::baker
