// uv::unwrap end to end: per-instance meshes, packing across instances, lightmapScale, keep mode,
// determinism, and every shared reference scene.
#include <gtest/gtest.h>

#include <cstring>
#include <set>

#include <glm/gtc/matrix_transform.hpp>

#include "afterglow/core/parallel.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/uv/unwrap.h"
#include "test_util.h"

namespace afterglow::uv {
namespace {

using scenes::Instance;
using scenes::Mesh;
using scenes::Primitive;
using scenes::Scene;

// A square of side `size` metres in the XY plane, two triangles, facing +Z.
Mesh quadMesh(const char* name, float size) {
  Mesh mesh;
  mesh.name = name;
  Primitive p;
  p.positions = {{0, 0, 0}, {size, 0, 0}, {size, size, 0}, {0, size, 0}};
  p.normals.assign(4, {0, 0, 1});
  p.indices = {0, 1, 2, 0, 2, 3};
  mesh.primitives.push_back(p);
  return mesh;
}

// A unit cube with 24 vertices (flat faces), facing outwards.
Mesh cubeMesh() {
  Mesh mesh;
  mesh.name = "cube";
  Primitive p;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = -1; side <= 1; side += 2) {
      glm::vec3 n(0.0f), u(0.0f), v(0.0f);
      n[axis] = float(side);
      u[(axis + 1) % 3] = 1.0f;
      v[(axis + 2) % 3] = 1.0f;
      if (glm::dot(glm::cross(u, v), n) < 0.0f) std::swap(u, v);
      uint32_t base = uint32_t(p.positions.size());
      for (glm::vec2 c : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)}) {
        p.positions.push_back(0.5f * (n + u * c.x + v * c.y));
        p.normals.push_back(n);
      }
      for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) p.indices.push_back(base + k);
    }
  mesh.primitives.push_back(p);
  return mesh;
}

Instance instanceOf(const char* name, int mesh, glm::mat4 transform = glm::mat4(1.0f)) {
  Instance inst;
  inst.name = name;
  inst.mesh = mesh;
  inst.transform = transform;
  return inst;
}

// Area of an instance's lightmap UVs in texels.
double texelArea(const Scene& scene, const Instance& inst) {
  double area = 0.0;
  for (const Primitive& p : scene.meshes[inst.mesh].primitives)
    for (size_t t = 0; t < p.triangleCount(); ++t) {
      glm::dvec2 a(p.uv1[p.indices[3 * t]]), b(p.uv1[p.indices[3 * t + 1]]),
          c(p.uv1[p.indices[3 * t + 2]]);
      area += 0.5 * std::abs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
    }
  return area * inst.lightmap.width * inst.lightmap.height;
}

// Texel-space bounding box of an instance's uv1.
struct Rect {
  glm::vec2 min{1e30f}, max{-1e30f};
};
Rect texelRect(const Scene& scene, const Instance& inst) {
  Rect r;
  glm::vec2 size(inst.lightmap.width, inst.lightmap.height);
  for (const Primitive& p : scene.meshes[inst.mesh].primitives)
    for (glm::vec2 uv : p.uv1) {
      r.min = glm::min(r.min, uv * size);
      r.max = glm::max(r.max, uv * size);
    }
  return r;
}

// The invariants every generated unwrap must hold.
void expectValidUnwrap(const Scene& scene, const UnwrapResult& result, int padding) {
  std::set<int> meshes;
  for (const Instance& inst : scene.instances) {
    if (!inst.isStatic) continue;
    ASSERT_GE(inst.mesh, 0);
    EXPECT_TRUE(meshes.insert(inst.mesh).second) << inst.name << " shares its mesh";
    ASSERT_GE(inst.lightmap.atlas, 0) << inst.name;
    EXPECT_GE(inst.lightmap.width, 16);
    for (const Primitive& p : scene.meshes[inst.mesh].primitives) {
      ASSERT_EQ(p.uv1.size(), p.positions.size()) << inst.name;
      for (glm::vec2 uv : p.uv1) {
        EXPECT_GE(uv.x, 0.0f);
        EXPECT_LE(uv.x, 1.0f);
        EXPECT_GE(uv.y, 0.0f);
        EXPECT_LE(uv.y, 1.0f);
      }
    }
  }
  const Metrics& m = result.metrics;
  EXPECT_EQ(m.overlappingTexels, 0u);
  EXPECT_EQ(m.paddingViolations, 0u) << "padding " << padding;
  EXPECT_EQ(m.outOfRangeTriangles, 0u);
  EXPECT_EQ(m.flippedTriangles, 0u);
}

TEST(UvUnwrap, CornellBoxGivesOneChartPerWallAndFivePerBlock) {
  Scene scene = scenes::makeCornellBox();
  const size_t triangles = scene.instancedTriangleCount();
  Result<UnwrapResult> r = unwrap(scene);
  ASSERT_TRUE(r.isOk()) << r.message();
  expectValidUnwrap(scene, r.value(), 2);
  // 5 walls and the lamp are one quad each; each block is 5 quads meeting at right angles
  // (hard edges), its bottom left out.
  EXPECT_EQ(r->metrics.chartCount, 5u + 1u + 5u + 5u);
  EXPECT_EQ(r->metrics.triangleCount, triangles);
  EXPECT_EQ(scene.meshes.size(), scene.instances.size());
  EXPECT_LE(r->metrics.stretchL2, 1.01);
  EXPECT_EQ(r->metrics.atlases.size(), 1u);
}

TEST(UvUnwrap, FurnaceBoxGivesOneChartPerFace) {
  Scene scene = scenes::makeFurnaceBox();
  Result<UnwrapResult> r = unwrap(scene);
  ASSERT_TRUE(r.isOk()) << r.message();
  expectValidUnwrap(scene, r.value(), 2);
  EXPECT_EQ(r->metrics.chartCount, 6u);
  EXPECT_LE(r->metrics.stretchL2, 1.01);
}

TEST(UvUnwrap, CubeGivesSixCharts) {
  Scene scene;
  scene.meshes.push_back(cubeMesh());
  scene.instances.push_back(instanceOf("cube", 0));
  Result<UnwrapResult> r = unwrap(scene);
  ASSERT_TRUE(r.isOk()) << r.message();
  expectValidUnwrap(scene, r.value(), 2);
  EXPECT_EQ(r->metrics.chartCount, 6u);
}

TEST(UvUnwrap, InstancesOfOneMeshGetDisjointSpaceAndTheirOwnMeshes) {
  Scene scene;
  scene.meshes.push_back(cubeMesh());
  scene.instances.push_back(instanceOf("a", 0));
  scene.instances.push_back(
      instanceOf("b", 0, glm::translate(glm::mat4(1.0f), glm::vec3(3.0f, 0.0f, 0.0f))));
  UnwrapOptions options;
  options.pack.padding = 3;
  Result<UnwrapResult> r = unwrap(scene, options);
  ASSERT_TRUE(r.isOk()) << r.message();
  expectValidUnwrap(scene, r.value(), 3);
  ASSERT_EQ(scene.meshes.size(), 2u);  // the shared original is dropped
  EXPECT_NE(scene.instances[0].mesh, scene.instances[1].mesh);
  EXPECT_EQ(r->metrics.chartCount, 12u);
  // Both instances together cover twice the chart texels of one, with nothing overlapping.
  EXPECT_NEAR(texelArea(scene, scene.instances[0]), texelArea(scene, scene.instances[1]),
              0.01 * texelArea(scene, scene.instances[0]));
  // Object-space vertices are kept: the transform stays on the instance.
  EXPECT_EQ(scene.meshes[scene.instances[1].mesh].primitives[0].positions[0],
            cubeMesh().primitives[0].positions[0]);
}

TEST(UvUnwrap, LightmapScaleTwoGivesFourTimesTheTexels) {
  Scene scene;
  scene.meshes.push_back(quadMesh("quad", 1.0f));
  scene.instances.push_back(instanceOf("normal", 0));
  scene.instances.push_back(instanceOf("doubled", 0));
  scene.instances[1].lightmapScale = 2.0f;
  Result<UnwrapResult> r = unwrap(scene);
  ASSERT_TRUE(r.isOk()) << r.message();
  expectValidUnwrap(scene, r.value(), 2);
  const double normal = texelArea(scene, scene.instances[0]);
  const double doubled = texelArea(scene, scene.instances[1]);
  EXPECT_NEAR(normal, 16.0 * 16.0, 0.1 * 256.0);  // 1 m² at 16 texels per metre
  EXPECT_NEAR(doubled / normal, 4.0, 0.4);
  // Disjoint atlas space: the two squares' texel rectangles do not intersect.
  if (scene.instances[0].lightmap.atlas == scene.instances[1].lightmap.atlas) {
    Rect a = texelRect(scene, scene.instances[0]), b = texelRect(scene, scene.instances[1]);
    bool apart = a.max.x <= b.min.x || b.max.x <= a.min.x || a.max.y <= b.min.y ||
                 b.max.y <= a.min.y;
    EXPECT_TRUE(apart);
  }
}

TEST(UvUnwrap, UniformScaleScalesTexelsAndNonUniformScaleIsChartedInTheWorld) {
  Scene scene;
  scene.meshes.push_back(quadMesh("quad", 1.0f));
  scene.instances.push_back(
      instanceOf("uniform", 0, glm::scale(glm::mat4(1.0f), glm::vec3(2.0f))));
  scene.instances.push_back(
      instanceOf("stretched", 0, glm::scale(glm::mat4(1.0f), glm::vec3(4.0f, 1.0f, 1.0f))));
  Result<UnwrapResult> r = unwrap(scene);
  ASSERT_TRUE(r.isOk()) << r.message();
  expectValidUnwrap(scene, r.value(), 2);
  // Both are 4 m² in the world: 4 × 256 texels at 16 texels per metre.
  EXPECT_NEAR(texelArea(scene, scene.instances[0]), 1024.0, 0.1 * 1024.0);
  EXPECT_NEAR(texelArea(scene, scene.instances[1]), 1024.0, 0.1 * 1024.0);
  // The stretched instance's UVs follow the world shape: 4:1, not the mesh's 1:1.
  Rect s = texelRect(scene, scene.instances[1]);
  glm::vec2 extent = s.max - s.min;
  float aspect = std::max(extent.x, extent.y) / std::min(extent.x, extent.y);
  EXPECT_NEAR(aspect, 4.0f, 0.2f);
  EXPECT_LE(r->metrics.stretchL2, 1.02);
}

TEST(UvUnwrap, SpillingPastMaxAtlasSizeKeepsEachInstanceInOneAtlas) {
  // Each 1 m cube needs six 16-texel faces plus padding: about 2,400 texels, so at most one
  // cube fits a 64 x 64 atlas and the charts must spread over several atlases.
  Scene scene;
  scene.meshes.push_back(cubeMesh());
  for (int i = 0; i < 5; ++i)
    scene.instances.push_back(instanceOf(
        "cube", 0, glm::translate(glm::mat4(1.0f), glm::vec3(2.0f * float(i), 0.0f, 0.0f))));
  UnwrapOptions options;
  options.pack.maxAtlasSize = 64;
  Result<UnwrapResult> r = unwrap(scene, options);
  ASSERT_TRUE(r.isOk()) << r.message();
  expectValidUnwrap(scene, r.value(), 2);
  EXPECT_GE(r->metrics.atlases.size(), 3u);
  for (const AtlasMetrics& a : r->metrics.atlases) {
    EXPECT_LE(a.width, 64);
    EXPECT_LE(a.height, 64);
  }
  for (const Instance& inst : scene.instances)
    EXPECT_NEAR(texelArea(scene, inst), 6.0 * 256.0, 0.1 * 6.0 * 256.0);
}

TEST(UvUnwrap, AnInstanceLargerThanMaxAtlasSizeIsAnError) {
  Scene scene;
  scene.meshes.push_back(quadMesh("floor", 10.0f));  // 160 texels across at 16 per metre
  scene.instances.push_back(instanceOf("floor", 0));
  UnwrapOptions options;
  options.pack.maxAtlasSize = 64;
  Result<UnwrapResult> r = unwrap(scene, options);
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.message().find("instance 'floor'"), std::string::npos) << r.message();
  EXPECT_NE(r.message().find("--texels-per-unit"), std::string::npos) << r.message();
}

TEST(UvUnwrap, DynamicInstancesAreLeftAlone) {
  Scene scene;
  scene.meshes.push_back(cubeMesh());
  scene.meshes.push_back(quadMesh("unused", 1.0f));
  scene.instances.push_back(instanceOf("static", 0));
  scene.instances.push_back(instanceOf("dynamic", 0));
  scene.instances[1].isStatic = false;
  Result<UnwrapResult> r = unwrap(scene);
  ASSERT_TRUE(r.isOk()) << r.message();
  // The dynamic instance keeps the original cube; the unused quad is dropped.
  ASSERT_EQ(scene.meshes.size(), 2u);
  const Instance& dynamic = scene.instances[1];
  EXPECT_EQ(dynamic.lightmap.atlas, -1);
  EXPECT_TRUE(scene.meshes[dynamic.mesh].primitives[0].uv1.empty());
  EXPECT_EQ(scene.meshes[dynamic.mesh].primitives[0].positions.size(), 24u);
  EXPECT_FALSE(scene.meshes[scene.instances[0].mesh].primitives[0].uv1.empty());
  EXPECT_EQ(r->metrics.chartCount, 6u);
}

TEST(UvUnwrap, CancelledProgressStops) {
  Scene scene = scenes::makeCornellBox();
  Progress progress;
  progress.cancel();
  Result<UnwrapResult> r = unwrap(scene, {}, progress);
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.message(), "cancelled");
}

bool sameUv1(const Scene& a, const Scene& b) {
  if (a.meshes.size() != b.meshes.size()) return false;
  for (size_t i = 0; i < a.instances.size(); ++i)
    if (a.instances[i].lightmap.atlas != b.instances[i].lightmap.atlas ||
        a.instances[i].lightmap.width != b.instances[i].lightmap.width)
      return false;
  for (size_t m = 0; m < a.meshes.size(); ++m)
    for (size_t p = 0; p < a.meshes[m].primitives.size(); ++p) {
      const auto &x = a.meshes[m].primitives[p].uv1, &y = b.meshes[m].primitives[p].uv1;
      if (x.size() != y.size() || std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) != 0)
        return false;
    }
  return true;
}

TEST(UvUnwrap, OutputDoesNotDependOnThreadCount) {
  Scene one = scenes::makeCornellBox(), two = one;
  one.instances.push_back(instanceOf("extra", 5, glm::translate(glm::mat4(1.0f), glm::vec3(2, 0, 0))));
  two.instances.push_back(one.instances.back());
  setThreadCount(1);
  Result<UnwrapResult> a = unwrap(one);
  setThreadCount(2);
  Result<UnwrapResult> b = unwrap(two);
  setThreadCount(0);
  ASSERT_TRUE(a.isOk() && b.isOk());
  EXPECT_TRUE(sameUv1(one, two));
  EXPECT_EQ(a->metrics.chartCount, b->metrics.chartCount);
}

// --uv keep ------------------------------------------------------------------------------------

Scene keepScene() {
  Scene scene;
  scene.sourcePath = "level.gltf";
  scene.meshes.push_back(quadMesh("Chair", 4.0f));
  scene.meshes[0].primitives[0].uv1 = {{0.1f, 0.1f}, {0.9f, 0.1f}, {0.9f, 0.9f}, {0.1f, 0.9f}};
  scene.instances.push_back(instanceOf("Chair", 0));
  scene.instances.push_back(
      instanceOf("Chair2", 0, glm::translate(glm::mat4(1.0f), glm::vec3(5, 0, 0))));
  return scene;
}

TEST(UvUnwrapKeep, AcceptsValidUvsWithAnAtlasPerInstance) {
  Scene scene = keepScene();
  UnwrapOptions options;
  options.mode = UvMode::Keep;
  Result<UnwrapResult> r = unwrap(scene, options);
  ASSERT_TRUE(r.isOk()) << r.message();
  ASSERT_EQ(scene.meshes.size(), 2u);
  EXPECT_EQ(scene.instances[0].lightmap.atlas, 0);
  EXPECT_EQ(scene.instances[1].lightmap.atlas, 1);
  // 4 m × 16 texels per metre over the 0.8 of the square the UVs span: 80 texels.
  EXPECT_EQ(scene.instances[0].lightmap.width, 80);
  EXPECT_EQ(scene.instances[0].lightmap.height, 80);
  EXPECT_EQ(scene.meshes[scene.instances[1].mesh].primitives[0].uv1[2], glm::vec2(0.9f, 0.9f));
  EXPECT_EQ(r->metrics.overlappingTexels, 0u);
  EXPECT_EQ(r->metrics.atlases.size(), 2u);
}

TEST(UvUnwrapKeep, RejectsMissingUvs) {
  Scene scene = keepScene();
  scene.meshes[0].primitives[0].uv1.clear();
  UnwrapOptions options;
  options.mode = UvMode::Keep;
  Result<UnwrapResult> r = unwrap(scene, options);
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.message(),
            "level.gltf: instance 'Chair' mesh 'Chair' primitive 0 has no TEXCOORD_1; use --uv "
            "generate to make new lightmap UVs");
}

TEST(UvUnwrapKeep, RejectsUvsOutsideTheUnitSquare) {
  Scene scene = keepScene();
  scene.meshes[0].primitives[0].uv1[2] = {1.5f, 0.9f};  // in both triangles
  UnwrapOptions options;
  options.mode = UvMode::Keep;
  Result<UnwrapResult> r = unwrap(scene, options);
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.message().find("instance 'Chair' mesh 'Chair': 2 triangles of TEXCOORD_1 lie "
                             "outside [0,1]"),
            std::string::npos)
      << r.message();
  EXPECT_NE(r.message().find("--uv generate"), std::string::npos);
}

TEST(UvUnwrapKeep, RejectsOverlappingCharts) {
  Scene scene = keepScene();
  // Two separate quads (own vertices) mapped onto the same UV square: two charts, one place.
  Primitive& p = scene.meshes[0].primitives[0];
  Primitive copy = p;
  for (glm::vec3& v : copy.positions) v.z += 1.0f;
  uint32_t base = uint32_t(p.positions.size());
  p.positions.insert(p.positions.end(), copy.positions.begin(), copy.positions.end());
  p.normals.insert(p.normals.end(), copy.normals.begin(), copy.normals.end());
  p.uv1.insert(p.uv1.end(), copy.uv1.begin(), copy.uv1.end());
  for (uint32_t i : copy.indices) p.indices.push_back(base + i);
  UnwrapOptions options;
  options.mode = UvMode::Keep;
  options.pack.maxAtlasSize = 256;  // the atlas grows to here before giving up
  Result<UnwrapResult> r = unwrap(scene, options);
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.message().find("level.gltf: instance 'Chair' mesh 'Chair': TEXCOORD_1 charts "
                             "overlap on "),
            std::string::npos)
      << r.message();
}

TEST(UvUnwrapKeep, KeepsALayoutRecordedByAnEarlierRun) {
  Scene scene = scenes::makeCornellBox();
  ASSERT_TRUE(unwrap(scene).isOk());
  std::vector<scenes::LightmapLocation> before;
  for (const Instance& inst : scene.instances) before.push_back(inst.lightmap);
  Scene again = scene;
  UnwrapOptions options;
  options.mode = UvMode::Keep;
  Result<UnwrapResult> r = unwrap(again, options);
  ASSERT_TRUE(r.isOk()) << r.message();
  ASSERT_EQ(again.instances.size(), before.size());
  for (size_t i = 0; i < before.size(); ++i) {
    EXPECT_EQ(again.instances[i].lightmap.atlas, before[i].atlas);
    EXPECT_EQ(again.instances[i].lightmap.width, before[i].width);
  }
  EXPECT_EQ(r->metrics.atlases.size(), 1u);
  EXPECT_EQ(r->metrics.overlappingTexels, 0u);
  EXPECT_EQ(r->metrics.paddingViolations, 0u);
  EXPECT_TRUE(sameUv1(scene, again));
}

TEST(UvUnwrapKeep, ARecordedLayoutWithSharedTexelsFallsBackToAnAtlasPerInstance) {
  Scene scene = keepScene();  // two instances of one mesh: identical UVs
  for (Instance& inst : scene.instances) inst.lightmap = {0, 64, 64};
  UnwrapOptions options;
  options.mode = UvMode::Keep;
  Result<UnwrapResult> r = unwrap(scene, options);
  ASSERT_TRUE(r.isOk()) << r.message();
  EXPECT_EQ(scene.instances[0].lightmap.atlas, 0);
  EXPECT_EQ(scene.instances[1].lightmap.atlas, 1);
  EXPECT_EQ(r->metrics.overlappingTexels, 0u);
  ASSERT_FALSE(r->warnings.empty());
  EXPECT_NE(r->warnings[0].find("recorded extras.afterglow.lightmap layout"), std::string::npos);
}

// Shared reference scenes --------------------------------------------------------------------

void unwrapShared(const std::string& path, float texelsPerUnit, UvMode mode) {
  Result<Scene> loaded = scenes::loadGltf(path, scenes::LoadOptions{false});
  ASSERT_TRUE(loaded.isOk()) << loaded.message();
  Scene scene = std::move(loaded.value());
  UnwrapOptions options;
  options.mode = mode;
  options.pack.texelsPerUnit = texelsPerUnit;
  Result<UnwrapResult> r = unwrap(scene, options);
  ASSERT_TRUE(r.isOk()) << r.message();
  EXPECT_EQ(r->metrics.overlappingTexels, 0u) << path;
  EXPECT_EQ(r->metrics.outOfRangeTriangles, 0u) << path;
  if (mode == UvMode::Generate) {
    expectValidUnwrap(scene, r.value(), options.pack.padding);
    EXPECT_LE(r->metrics.stretchL2, 1.05) << path;
  }
  EXPECT_GT(r->metrics.chartCount, 0u);
}

TEST(UvUnwrapShared, CornellBox) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  unwrapShared(path, 16.0f, UvMode::Generate);
}

TEST(UvUnwrapShared, SponzaAtFourTexelsPerUnit) {
  AG_REQUIRE_SHARED_SCENE(path, "sponza/Sponza.gltf");
  unwrapShared(path, 4.0f, UvMode::Generate);
}

TEST(UvUnwrapShared, MixedLightingGenerate) {
  AG_REQUIRE_SHARED_SCENE(path, "mixed_lighting_bevy/MixedLightingExample.gltf");
  unwrapShared(path, 16.0f, UvMode::Generate);
}

TEST(UvUnwrapShared, MixedLightingKeep) {
  AG_REQUIRE_SHARED_SCENE(path, "mixed_lighting_bevy/MixedLightingExample.gltf");
  unwrapShared(path, 16.0f, UvMode::Keep);
}

TEST(UvUnwrapShared, MixedLightingIsBitIdenticalWithOneAndTwoThreads) {
  AG_REQUIRE_SHARED_SCENE(path, "mixed_lighting_bevy/MixedLightingExample.gltf");
  Result<Scene> loaded = scenes::loadGltf(path, scenes::LoadOptions{false});
  ASSERT_TRUE(loaded.isOk()) << loaded.message();
  Scene one = loaded.value(), two = loaded.value();
  setThreadCount(1);
  Result<UnwrapResult> a = unwrap(one);
  setThreadCount(2);
  Result<UnwrapResult> b = unwrap(two);
  setThreadCount(0);
  ASSERT_TRUE(a.isOk() && b.isOk());
  EXPECT_GT(a->metrics.chartCount, 10u);
  EXPECT_EQ(a->metrics.chartCount, b->metrics.chartCount);
  EXPECT_TRUE(sameUv1(one, two));
}

}  // namespace
}  // namespace afterglow::uv
