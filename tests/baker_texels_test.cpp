// Texels and clusters: conservative coverage and exact areas on a quad, no samples inside the
// Cornell box's blocks or outside its room, texelAt round trips, cluster invariants and counts,
// the meta-pass albedo, and determinism across thread counts.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/direct.h"
#include "afterglow/baker/gather.h"
#include "afterglow/baker/links.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/parallel.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/material_eval.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/uv/unwrap.h"
#include "afterglow/uv/texel_raster.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::baker {
namespace {

using runtime::kNoTexel;
using scenes::Scene;

Scene unwrapped(Scene scene, float texelsPerUnit) {
  uv::UnwrapOptions options;
  options.pack.texelsPerUnit = texelsPerUnit;
  Result<uv::UnwrapResult> r = uv::unwrap(scene, options);
  EXPECT_TRUE(r.isOk()) << r.message();
  return scene;
}

std::unique_ptr<trace::RayTracer> buildOrDie(const Scene& scene) {
  auto result = trace::RayTracer::build(scene);
  EXPECT_TRUE(result.isOk()) << result.message();
  return result.isOk() ? std::move(result.value()) : nullptr;
}

TexelSet texelsOrDie(const Scene& scene, const trace::RayTracer& tracer, const TexelOptions& options = {}) {
  Result<TexelSet> r = computeTexels(scene, tracer, options);
  EXPECT_TRUE(r.isOk()) << r.message();
  return r.isOk() ? std::move(r.value()) : TexelSet{};
}

int instanceNamed(const Scene& scene, const std::string& name) {
  for (size_t i = 0; i < scene.instances.size(); ++i)
    if (scene.instances[i].name == name) return int(i);
  return -1;
}

// World-space triangles of an instance.
std::vector<glm::vec3> worldTriangles(const Scene& scene, int instance) {
  std::vector<glm::vec3> out;
  scenes::forEachWorldTriangle(scene, scene.instances[size_t(instance)],
                               [&](size_t, size_t, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
                                 out.insert(out.end(), {a, b, c});
                               });
  return out;
}

// A 2 × 1 m quad in the y = 0 plane, front +Y.
Scene quadScene() {
  Scene scene;
  scenes::Material m;
  m.metallicFactor = 0.0f;
  scene.materials.push_back(m);
  scenes::Primitive p;
  p.material = 0;
  p.positions = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, {2.0f, 0.0f, 1.0f}, {2.0f, 0.0f, 0.0f}};
  p.normals.assign(4, glm::vec3(0.0f, 1.0f, 0.0f));
  p.uv0 = {{0.0f, 0.0f}, {0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}};
  p.indices = {0, 1, 2, 0, 2, 3};
  scenes::Mesh mesh;
  mesh.name = "quad";
  mesh.primitives.push_back(p);
  scene.meshes.push_back(mesh);
  scenes::Instance inst;
  inst.name = "quad";
  inst.mesh = 0;
  scene.instances.push_back(inst);
  return scene;
}

TEST(BakerTexels, QuadCoverageAreaAndPlacement) {
  const Scene scene = unwrapped(quadScene(), 8.0f);
  auto tracer = buildOrDie(scene);
  ASSERT_TRUE(tracer);
  const TexelSet texels = texelsOrDie(scene, *tracer);

  // The conservative footprint of the quad's UV triangles, counted independently.
  const scenes::Instance& inst = scene.instances[0];
  const scenes::Primitive& prim = scene.meshes[size_t(inst.mesh)].primitives[0];
  const glm::dvec2 size(inst.lightmap.width, inst.lightmap.height);
  std::set<std::pair<int, int>> covered;
  for (size_t t = 0; t < prim.triangleCount(); ++t)
    uv::rasterizeTriangle(glm::dvec2(prim.uv1[prim.indices[3 * t]]) * size,
                                  glm::dvec2(prim.uv1[prim.indices[3 * t + 1]]) * size,
                                  glm::dvec2(prim.uv1[prim.indices[3 * t + 2]]) * size, 0.0,
                                  inst.lightmap.width, inst.lightmap.height,
                                  [&](int x, int y) { covered.insert({x, y}); });
  ASSERT_EQ(texels.size(), covered.size());
  // 16 × 8 texels at 8 per metre, plus at most one partial row and column.
  EXPECT_GE(texels.size(), 128u);
  EXPECT_LE(texels.size(), 17u * 9u);
  ASSERT_EQ(texels.atlases.size(), 1u);

  double area = 0.0;
  size_t layoutTexels = 0;
  for (uint32_t v : texels.atlases[0].texelOfPixel) layoutTexels += v != kNoTexel;
  EXPECT_EQ(layoutTexels, texels.size());
  const float texelSize = 1.0f / 8.0f;
  const float offset = std::max(TexelOptions{}.offsetFraction * texelSize, TexelOptions{}.minOffset);
  for (uint32_t t = 0; t < texels.size(); ++t) {
    area += texels.area[t];
    EXPECT_EQ(texels.valid[t], 1) << t;  // nothing to hide in
    const glm::vec3 p = texels.position[t];
    EXPECT_NEAR(p.y, offset, 1e-5f) << t;
    EXPECT_GE(p.x, -1e-5f);
    EXPECT_LE(p.x, 2.0f + 1e-5f);
    EXPECT_GE(p.z, -1e-5f);
    EXPECT_LE(p.z, 1.0f + 1e-5f);
    EXPECT_NEAR(texels.normal[t].y, 1.0f, 1e-6f);
    EXPECT_NEAR(texels.geometricNormal[t].y, 1.0f, 1e-6f);
    EXPECT_TRUE(covered.count({texels.pixel[t].x, texels.pixel[t].y}));
    EXPECT_EQ(texels.atlases[0].texelOfPixel[size_t(texels.pixel[t].y) * size_t(inst.lightmap.width) +
                                             texels.pixel[t].x],
              t);
    // uv0 runs 0..1 across the quad, x = 2·u0.
    EXPECT_NEAR(texels.uv0[t].x * 2.0f, p.x, 1e-4f);
    if (t > 0) {  // atlas, row, column order
      const bool ordered = texels.pixel[t].y > texels.pixel[t - 1].y ||
                           (texels.pixel[t].y == texels.pixel[t - 1].y &&
                            texels.pixel[t].x > texels.pixel[t - 1].x);
      EXPECT_TRUE(ordered) << t;
    }
  }
  EXPECT_NEAR(area, 2.0, 0.02 * 2.0);
  std::printf("quad: %u texels, area %.6f m² (exact 2)\n", texels.size(), area);
}

// A triangle whose UVs sit at odd angles and fractions in a 16 × 16 atlas, so most texels are
// partly covered: areas still add up exactly and every sample stays on the triangle.
TEST(BakerTexels, PartialTexelsStayOnTheTriangle) {
  Scene scene = quadScene();
  scenes::Primitive& p = scene.meshes[0].primitives[0];
  // World triangle (0,0,0), (3,0,0.5), (1,0,2) in the y = 0 plane, counter-clockwise from +Y.
  p.positions = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 2.0f}, {3.0f, 0.0f, 0.5f}};
  p.normals.assign(3, glm::vec3(0.0f, 1.0f, 0.0f));
  p.uv0.clear();
  p.uv1 = {{0.113f, 0.071f}, {0.377f, 0.913f}, {0.921f, 0.259f}};
  p.indices = {0, 1, 2};
  scene.instances[0].lightmap = {0, 16, 16};
  auto tracer = buildOrDie(scene);
  ASSERT_TRUE(tracer);
  const TexelSet texels = texelsOrDie(scene, *tracer);
  std::set<std::pair<int, int>> covered;
  const glm::dvec2 size(16.0);
  uv::rasterizeTriangle(glm::dvec2(p.uv1[0]) * size, glm::dvec2(p.uv1[1]) * size,
                                glm::dvec2(p.uv1[2]) * size, 0.0, 16, 16,
                                [&](int x, int y) { covered.insert({x, y}); });
  EXPECT_EQ(texels.size(), covered.size());
  double area = 0.0;
  const glm::vec3 a = p.positions[0], b = p.positions[1], c = p.positions[2];
  for (uint32_t t = 0; t < texels.size(); ++t) {
    area += texels.area[t];
    EXPECT_GT(texels.area[t], 0.0f);
    const glm::vec3 q = texels.position[t];
    EXPECT_GT(q.y, 0.0f);
    EXPECT_LT(q.y, 0.01f);
    // Inside the triangle's footprint in the plane (edge functions, 1e-5 slack).
    const glm::vec2 q2(q.x, q.z), a2(a.x, a.z), b2(b.x, b.z), c2(c.x, c.z);
    auto edge = [](glm::vec2 o, glm::vec2 d, glm::vec2 r) {
      return (d.x - o.x) * (r.y - o.y) - (d.y - o.y) * (r.x - o.x);
    };
    const float s = edge(a2, b2, c2) > 0 ? 1.0f : -1.0f;
    EXPECT_GE(s * edge(a2, b2, q2), -1e-5f) << t;
    EXPECT_GE(s * edge(b2, c2, q2), -1e-5f) << t;
    EXPECT_GE(s * edge(c2, a2, q2), -1e-5f) << t;
  }
  const double exact = 0.5 * double(glm::length(glm::cross(b - a, c - a)));
  EXPECT_NEAR(area, exact, 1e-4 * exact);
  std::printf("triangle: %u texels, area %.6f m² (exact %.6f)\n", texels.size(), area, exact);
}

struct Cornell {
  Scene scene;
  std::unique_ptr<trace::RayTracer> tracer;
  TexelSet texels;
};

// Texels placed and then judged by their gather rays (which marks buried ones invalid).
Cornell cornell(float texelsPerUnit = 64.0f) {
  Cornell c;
  c.scene = unwrapped(scenes::makeCornellBox(), texelsPerUnit);
  c.tracer = buildOrDie(c.scene);
  if (!c.tracer) return c;
  c.texels = texelsOrDie(c.scene, *c.tracer);
  LinkOptions options;
  options.texelRays = 16;
  EXPECT_TRUE(gatherTexels(c.scene, *c.tracer, c.texels, options).isOk());
  return c;
}

// How far p lies inside the convex block (positive: inside), from its outward-facing triangles.
float depthInside(const std::vector<glm::vec3>& triangles, const glm::vec3& p) {
  float depth = std::numeric_limits<float>::infinity();
  for (size_t i = 0; i + 2 < triangles.size(); i += 3) {
    const glm::vec3 n = glm::normalize(
        glm::cross(triangles[i + 1] - triangles[i], triangles[i + 2] - triangles[i]));
    depth = std::min(depth, -glm::dot(n, p - triangles[i]));
  }
  return depth;
}

TEST(BakerTexels, CornellSamplesStayInTheRoomAndOutOfTheBlocks) {
  const Cornell c = cornell();
  ASSERT_TRUE(c.tracer);
  const Scene& scene = c.scene;
  const TexelSet& texels = c.texels;
  ASSERT_GT(texels.size(), 1000u);

  scenes::Bounds room;
  for (const char* wall : {"floor", "ceiling", "back_wall", "left_wall", "right_wall"}) {
    const int i = instanceNamed(scene, wall);
    ASSERT_GE(i, 0) << wall;
    for (const glm::vec3& p : worldTriangles(scene, i)) room.extend(p);
  }
  const glm::vec3 roomCentre = 0.5f * (room.min + room.max);
  const int shortBlock = instanceNamed(scene, "short_block");
  const int tallBlock = instanceNamed(scene, "tall_block");
  const int floor = instanceNamed(scene, "floor");
  ASSERT_GE(shortBlock, 0);
  ASSERT_GE(tallBlock, 0);
  const std::vector<glm::vec3> blocks[2] = {worldTriangles(scene, shortBlock),
                                            worldTriangles(scene, tallBlock)};
  glm::vec3 blockCentre[2];
  double footprint = 0.0;  // floor area under both blocks (their top faces)
  for (int b = 0; b < 2; ++b) {
    blockCentre[b] = glm::vec3(0.0f);
    for (const glm::vec3& p : blocks[b]) blockCentre[b] += p;
    blockCentre[b] /= float(blocks[b].size());
    for (size_t i = 0; i < blocks[b].size(); i += 3) {
      const glm::vec3 cr = glm::cross(blocks[b][i + 1] - blocks[b][i], blocks[b][i + 2] - blocks[b][i]);
      if (glm::normalize(cr).y > 0.9f) footprint += 0.5 * glm::length(cr);
    }
  }

  size_t invalid = 0, invalidFloor = 0, floorNearBlock = 0;
  double invalidFloorArea = 0.0;
  const float tol = 1e-4f;
  for (uint32_t t = 0; t < texels.size(); ++t) {
    const glm::vec3 p = texels.position[t];
    const glm::vec3 n = texels.normal[t];
    EXPECT_NEAR(glm::length(n), 1.0f, 1e-4f);
    if (!texels.valid[t]) {
      ++invalid;
      if (int(texels.instance[t]) == floor) {
        ++invalidFloor;
        invalidFloorArea += texels.area[t];
      }
      continue;
    }
    EXPECT_TRUE(p.x >= room.min.x - tol && p.x <= room.max.x + tol && p.y >= room.min.y - tol &&
                p.y <= room.max.y + tol && p.z >= room.min.z - tol && p.z <= room.max.z + tol)
        << "texel " << t << " of " << scene.instances[texels.instance[t]].name << " at " << p.x
        << ", " << p.y << ", " << p.z;
    for (int b = 0; b < 2; ++b) {
      const float depth = depthInside(blocks[b], p);
      EXPECT_LT(depth, 1e-5f) << "texel " << t << " of " << scene.instances[texels.instance[t]].name
                              << " inside block " << b;
      if (int(texels.instance[t]) == floor && depth > -1.0f / 64.0f) ++floorNearBlock;
    }
    // Normals face the air: into the room for walls, away from the block for blocks.
    const int inst = int(texels.instance[t]);
    if (inst == shortBlock || inst == tallBlock) {
      EXPECT_GT(glm::dot(n, p - blockCentre[inst == shortBlock ? 0 : 1]), 0.0f) << t;
    } else {
      EXPECT_GT(glm::dot(n, roomCentre - p), 0.0f) << t;
    }
  }
  // The floor under the blocks is buried; the strip along their sides was pushed out, not lost.
  EXPECT_GT(invalidFloor, 0u);
  EXPECT_GT(floorNearBlock, 0u);
  EXPECT_GT(invalidFloorArea, 0.3 * footprint);
  EXPECT_LT(invalidFloorArea, 1.05 * footprint);
  std::printf("cornell: %u texels, %zu invalid (%zu floor, %.4f m² of %.4f m² under blocks), "
              "%zu floor texels within a texel of a block\n",
              texels.size(), invalid, invalidFloor, invalidFloorArea, footprint, floorNearBlock);
}

TEST(BakerTexels, TexelAtRoundTrips) {
  const Cornell c = cornell();
  ASSERT_TRUE(c.tracer);
  const TexelSet& texels = c.texels;
  const std::vector<glm::vec3> blocks[2] = {
      worldTriangles(c.scene, instanceNamed(c.scene, "short_block")),
      worldTriangles(c.scene, instanceNamed(c.scene, "tall_block"))};
  const int floor = instanceNamed(c.scene, "floor");
  size_t tested = 0, exact = 0, valid = 0;
  for (uint32_t t = 0; t < texels.size(); ++t) {
    if (!texels.valid[t]) continue;
    ++valid;
    trace::Ray ray;
    ray.origin = texels.position[t] + 1e-3f * texels.geometricNormal[t];
    ray.direction = -texels.geometricNormal[t];
    ray.tfar = 2e-2f;
    const trace::Hit hit = c.tracer->intersect(ray);
    // Samples pushed out next to a block no longer sit above their own texel.
    if (!hit.valid() || hit.instance != texels.instance[t]) continue;
    if (int(texels.instance[t]) == floor && (depthInside(blocks[0], texels.position[t]) > -2.0f / 64.0f ||
                                             depthInside(blocks[1], texels.position[t]) > -2.0f / 64.0f))
      continue;
    ++tested;
    const uint32_t found =
        texelAt(c.scene, texels, hit.instance, hit.primitive, hit.triangle, hit.barycentric);
    ASSERT_NE(found, kNoTexel) << t;
    exact += found == t;
    EXPECT_EQ(texels.atlas[found], texels.atlas[t]);
    EXPECT_LE(std::abs(int(texels.pixel[found].x) - int(texels.pixel[t].x)), 1) << t;
    EXPECT_LE(std::abs(int(texels.pixel[found].y) - int(texels.pixel[t].y)), 1) << t;
  }
  EXPECT_GT(tested, valid * 95 / 100);
  EXPECT_GT(exact, tested * 95 / 100);
  std::printf("texelAt: %zu of %zu valid texels tested, %zu exact\n", tested, valid, exact);

  // Dynamic instances have no lightmap.
  Scene dynamicScene = c.scene;
  dynamicScene.instances[0].isStatic = false;
  EXPECT_EQ(texelAt(dynamicScene, texels, 0, 0, 0, glm::vec2(0.3f)), kNoTexel);
}

void expectClusterInvariants(const Scene& scene, const TexelSet& texels, const Clusters& clusters,
                             const ClusterOptions& options) {
  ASSERT_EQ(clusters.texelCluster.size(), texels.size());
  ASSERT_EQ(clusters.firstTexel.size(), clusters.size() + 1u);
  ASSERT_EQ(clusters.position.size(), clusters.size());
  ASSERT_EQ(clusters.normal.size(), clusters.size());
  ASSERT_EQ(clusters.material.size(), clusters.size());
  ASSERT_EQ(clusters.albedo.size(), clusters.size());
  ASSERT_EQ(clusters.emission.size(), clusters.size());
  std::vector<int> seen(texels.size(), 0);
  double validArea = 0.0, clusterArea = 0.0;
  const float cosLimit = std::cos((options.maxNormalAngleDeg + 0.5f) * 3.14159265f / 180.0f);
  for (uint32_t c = 0; c < clusters.size(); ++c) {
    ASSERT_LT(clusters.firstTexel[c], clusters.firstTexel[c + 1]) << "empty cluster " << c;
    clusterArea += clusters.area[c];
    EXPECT_NEAR(glm::length(clusters.normal[c]), 1.0f, 1e-4f);
    const uint32_t first = clusters.memberTexels[clusters.firstTexel[c]];
    double area = 0.0;
    for (uint32_t k = clusters.firstTexel[c]; k < clusters.firstTexel[c + 1]; ++k) {
      const uint32_t t = clusters.memberTexels[k];
      ++seen[t];
      area += texels.area[t];
      EXPECT_EQ(clusters.texelCluster[t], c);
      EXPECT_EQ(texels.instance[t], texels.instance[first]) << "cluster " << c << " mixes instances";
      const scenes::Instance& inst = scene.instances[texels.instance[t]];
      const int mat = scene.meshes[size_t(inst.mesh)].primitives[texels.primitive[t]].material;
      EXPECT_EQ(uint32_t(mat), clusters.material[c]) << "cluster " << c << " mixes materials";
      EXPECT_GE(glm::dot(texels.normal[t], clusters.normal[c]), cosLimit) << "texel " << t;
    }
    EXPECT_NEAR(area, clusters.area[c], 1e-5 * std::max(1.0, area));
  }
  for (uint32_t t = 0; t < texels.size(); ++t) {
    if (texels.valid[t]) {
      validArea += texels.area[t];
      EXPECT_EQ(seen[t], 1) << "texel " << t;
    } else {
      EXPECT_EQ(seen[t], 0) << "texel " << t;
      EXPECT_EQ(clusters.texelCluster[t], kNoTexel);
    }
  }
  EXPECT_NEAR(clusterArea, validArea, 1e-4 * validArea);
}

size_t tinyClusters(const Clusters& clusters) {
  size_t tiny = 0;
  for (uint32_t k = 0; k < clusters.size(); ++k)
    tiny += clusters.firstTexel[k + 1] - clusters.firstTexel[k] < 4;
  return tiny;
}

TEST(BakerClusters, FurnaceBoxHasFourClustersPerFace) {
  scenes::FurnaceOptions fo;
  fo.size = 1.0f;
  fo.albedo = glm::vec3(0.5f);
  fo.emission = glm::vec3(2.0f, 1.0f, 0.5f);
  const Scene scene = unwrapped(scenes::makeFurnaceBox(fo), 32.0f);
  auto tracer = buildOrDie(scene);
  ASSERT_TRUE(tracer);
  const TexelSet texels = texelsOrDie(scene, *tracer);
  double area = 0.0;
  size_t valid = 0;
  for (uint32_t t = 0; t < texels.size(); ++t) {
    area += texels.area[t];
    valid += texels.valid[t];
  }
  EXPECT_EQ(valid, texels.size());  // seen from inside a closed box nothing is buried
  EXPECT_NEAR(area, 6.0, 0.02 * 6.0);

  ClusterOptions options;
  options.clusterSize = 0.5f;
  options.clusterTexels = 0.0f;  // metres alone
  const Clusters clusters = computeClusters(scene, nullptr, texels, nullptr, options);
  expectClusterInvariants(scene, texels, clusters, options);
  EXPECT_EQ(clusters.size(), 24u);
  for (uint32_t c = 0; c < clusters.size(); ++c) {
    EXPECT_NEAR(clusters.area[c], 0.25f, 0.02f) << c;
    // Rough dielectric: 0.5 · (1 − 0.04) + 0.04 · 1² · 0.5 (the meta pass's specular share).
    EXPECT_NEAR(clusters.albedo[c].x, 0.5f * 0.96f + 0.02f, 1e-5f);
    EXPECT_NEAR(clusters.emission[c].x, 2.0f, 1e-5f);
    EXPECT_NEAR(clusters.emission[c].y, 1.0f, 1e-5f);
    EXPECT_NEAR(clusters.emission[c].z, 0.5f, 1e-5f);
    // Each quarter face's centre sits 0.25 m from the face's middle along both in-plane axes.
    const glm::vec3 p = glm::abs(clusters.position[c]);
    const float big = std::max({p.x, p.y, p.z});
    EXPECT_NEAR(big, 0.5f, 0.01f);
    EXPECT_NEAR(p.x + p.y + p.z - big, 0.5f, 0.02f);
  }
}

// Clusters shrink with the lightmap's texels: at 32 texels/m and 4 texels across, a 0.5 m cell
// splits into clusters of at most 4 texel edges (one more for the texels' own size).
TEST(BakerClusters, ClusterTexelsBoundsTheExtentInTexels) {
  scenes::FurnaceOptions fo;
  fo.size = 1.0f;
  const Scene scene = unwrapped(scenes::makeFurnaceBox(fo), 32.0f);
  auto tracer = buildOrDie(scene);
  ASSERT_TRUE(tracer);
  const TexelSet texels = texelsOrDie(scene, *tracer);
  ClusterOptions options;
  options.clusterSize = 0.5f;
  options.clusterTexels = 4.0f;
  const Clusters clusters = computeClusters(scene, nullptr, texels, nullptr, options);
  expectClusterInvariants(scene, texels, clusters, options);
  const float edge = 1.0f / 32.0f;
  for (uint32_t c = 0; c < clusters.size(); ++c) {
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (uint32_t k = clusters.firstTexel[c]; k < clusters.firstTexel[c + 1]; ++k) {
      lo = glm::min(lo, texels.position[clusters.memberTexels[k]]);
      hi = glm::max(hi, texels.position[clusters.memberTexels[k]]);
    }
    const glm::vec3 extent = hi - lo;
    EXPECT_LE(std::max({extent.x, extent.y, extent.z}), 5.0f * edge) << "cluster " << c;
  }
  // Six 1 m faces in cells of at most 4 × 4 texels: at least 6 × 8 × 8.
  EXPECT_GE(clusters.size(), 6u * 64u);
}

TEST(BakerClusters, CornellInvariants) {
  const Cornell c = cornell();
  ASSERT_TRUE(c.tracer);
  ClusterOptions options;
  options.clusterSize = 0.1f;
  options.clusterTexels = 0.0f;  // metres alone
  options.maxNormalAngleDeg = 20.0f;
  const Clusters clusters = computeClusters(c.scene, nullptr, c.texels, nullptr, options);
  expectClusterInvariants(c.scene, c.texels, clusters, options);
  // Five 0.55 m walls in 0.1 m cells, blocks and the light: well over 100 clusters.
  EXPECT_GT(clusters.size(), 100u);
  EXPECT_LT(clusters.size(), 400u);
  std::printf("cornell clusters at 0.1 m: %u (%zu with fewer than 4 texels)\n", clusters.size(),
              tinyClusters(clusters));

  // Clusters of two texels across: without a minimum the subdivision leaves many of one to
  // three texels; with minTexels = 4 a node is split only into halves of at least 4, and what
  // stays small comes from normal cones (a block's edge), so far fewer are tiny.
  options.clusterSize = 2.0f / 64.0f;
  options.minTexels = 1;
  const Clusters unmerged = computeClusters(c.scene, nullptr, c.texels, nullptr, options);
  expectClusterInvariants(c.scene, c.texels, unmerged, options);
  options.minTexels = 4;
  const Clusters merged = computeClusters(c.scene, nullptr, c.texels, nullptr, options);
  expectClusterInvariants(c.scene, c.texels, merged, options);
  EXPECT_GT(tinyClusters(unmerged), 0u);
  EXPECT_LT(tinyClusters(merged), tinyClusters(unmerged) / 3);
  EXPECT_LT(merged.size(), unmerged.size());
  std::printf("cornell clusters at 2 texels: %u (%zu tiny) unmerged, %u (%zu tiny) merged\n",
              unmerged.size(), tinyClusters(unmerged), merged.size(), tinyClusters(merged));
}

TEST(BakerClusters, DiffuseAlbedoAndEmission) {
  Scene scene;
  auto add = [&](float metallic, float roughness, glm::vec3 base) {
    scenes::Material m;
    m.baseColorFactor = glm::vec4(base, 1.0f);
    m.metallicFactor = metallic;
    m.roughnessFactor = roughness;
    scene.materials.push_back(m);
    return int(scene.materials.size()) - 1;
  };
  const glm::vec2 uv(0.3f, 0.7f);
  auto near = [](glm::vec3 a, glm::vec3 b) { return glm::length(a - b) < 1e-6f; };
  // Polished metal reflects nothing diffusely.
  EXPECT_TRUE(near(diffuseAlbedo(scene, add(1.0f, 0.0f, glm::vec3(1.0f)), uv), glm::vec3(0.0f)));
  // White dielectric: 1 − 0.04 (the dielectric reflectance) + 0.04 · roughness² · 0.5.
  EXPECT_TRUE(near(diffuseAlbedo(scene, add(0.0f, 1.0f, glm::vec3(1.0f)), uv), glm::vec3(0.98f)));
  EXPECT_TRUE(near(diffuseAlbedo(scene, add(0.0f, 0.5f, glm::vec3(1.0f)), uv), glm::vec3(0.965f)));
  EXPECT_TRUE(near(diffuseAlbedo(scene, add(0.0f, 0.0f, glm::vec3(0.3f)), uv), glm::vec3(0.288f)));
  // Rough metal: only the specular share, half its colour.
  EXPECT_TRUE(near(diffuseAlbedo(scene, add(1.0f, 1.0f, {0.8f, 0.4f, 0.2f}), uv),
                   glm::vec3(0.4f, 0.2f, 0.1f)));
  // glTF's default material is fully metallic and rough, white: 0.5.
  EXPECT_TRUE(near(diffuseAlbedo(scene, -1, uv), glm::vec3(0.5f)));

  // Textures multiply their factors; metallic-roughness reads B and G, the specular texture A,
  // the specular colour texture RGB.
  scenes::Texture tex;
  tex.width = tex.height = 1;
  tex.texels = {glm::vec4(0.5f, 0.25f, 1.0f, 0.5f)};
  scene.textures.push_back(tex);
  scenes::Material m;
  m.baseColorFactor = glm::vec4(0.8f, 0.8f, 0.4f, 1.0f);
  m.baseColorTexture.texture = 0;
  m.metallicFactor = 0.5f;
  m.roughnessFactor = 1.0f;
  m.metallicRoughnessTexture.texture = 0;  // metallic 0.5 · 1, roughness 1 · 0.25
  m.emissiveFactor = glm::vec3(1.0f, 0.5f, 0.0f);
  m.emissiveStrength = 3.0f;
  m.emissiveTexture.texture = 0;
  scene.materials.push_back(m);
  const int textured = int(scene.materials.size()) - 1;
  const glm::vec3 base(0.4f, 0.2f, 0.4f);
  const glm::vec3 spec = glm::mix(glm::vec3(0.04f), base, 0.5f);
  EXPECT_TRUE(near(diffuseAlbedo(scene, textured, uv),
                   base * 0.5f * 0.96f + spec * 0.0625f * 0.5f));
  EXPECT_TRUE(near(emittedRadiance(scene, textured, uv), glm::vec3(1.5f, 0.375f, 0.0f)));
  EXPECT_TRUE(near(emittedRadiance(scene, 0, uv), glm::vec3(0.0f)));
  // The factor alone (the transport's material albedo) reads every texture as 1.
  EXPECT_TRUE(near(diffuseAlbedoFactor(m), glm::vec3(0.8f, 0.8f, 0.4f) * 0.5f * 0.96f +
                                               glm::mix(glm::vec3(0.04f),
                                                        glm::vec3(0.8f, 0.8f, 0.4f), 0.5f) *
                                                   0.5f));

  // KHR_materials_specular textures: strength 0.8 × A 0.5, colour (2, 1, 1) × RGB (0.5, 0.25, 1).
  scenes::Material s;
  s.baseColorFactor = glm::vec4(0.6f, 0.6f, 0.6f, 1.0f);
  s.metallicFactor = 0.0f;
  s.roughnessFactor = 1.0f;
  s.specularFactor = 0.8f;
  s.specularTexture.texture = 0;
  s.specularColorFactor = glm::vec3(2.0f, 1.0f, 1.0f);
  s.specularColorTexture.texture = 0;
  scene.materials.push_back(s);
  const glm::vec3 f0 = glm::vec3(0.04f, 0.01f, 0.04f) * 0.4f;  // 0.04 × (1, 0.25, 1) × 0.4
  EXPECT_TRUE(near(diffuseAlbedo(scene, int(scene.materials.size()) - 1, uv),
                   glm::vec3(0.6f) * (1.0f - 0.016f) + f0 * 0.5f));
}

// The bounce albedo for a table of materials, each expected value worked out from the formula
// (README, "Materials"): dielectricF0 = min(F0(ior) × specularColor, 1) × specular,
// albedo = base (1 − metallic)(1 − max(dielectricF0)) + mix(dielectricF0, base, metallic) ×
// roughness² / 2.
TEST(BakerAlbedo, TableOfMaterials) {
  struct Row {
    const char* what;
    glm::vec3 base;
    float metallic, roughness, ior, specular;
    glm::vec3 specularColor;
    glm::vec3 expected;  // by hand
  };
  const glm::vec3 white(1.0f), grey(0.5f), red(0.9f, 0.2f, 0.1f);
  // F0 for ior 1.5 is 0.04, for ior 2 (1/3)² = 1/9, for ior 1 0, for ior 0 1.
  const double ninth = 1.0 / 9.0;
  const Row rows[] = {
      {"smooth dielectric", grey, 0, 0, 1.5f, 1, white, glm::vec3(0.5 * 0.96)},
      {"rough dielectric", grey, 0, 1, 1.5f, 1, white, glm::vec3(0.5 * 0.96 + 0.04 * 0.5)},
      {"half-rough white", white, 0, 0.5f, 1.5f, 1, white, glm::vec3(0.96 + 0.04 * 0.25 * 0.5)},
      {"rough red", red, 0, 1, 1.5f, 1, white,
       glm::vec3(0.9 * 0.96 + 0.02, 0.2 * 0.96 + 0.02, 0.1 * 0.96 + 0.02)},
      {"smooth metal", red, 1, 0, 1.5f, 1, white, glm::vec3(0.0f)},
      {"rough metal", red, 1, 1, 1.5f, 1, white, glm::vec3(0.45, 0.1, 0.05)},
      {"rough metal, specular 0", red, 1, 1, 1.5f, 0, white, glm::vec3(0.45, 0.1, 0.05)},
      {"specular 0", red, 0, 1, 1.5f, 0, white, red},
      {"specular 0.5", grey, 0, 1, 1.5f, 0.5f, white, glm::vec3(0.5 * 0.98 + 0.02 * 0.5)},
      {"ior 2", grey, 0, 1, 2.0f, 1, white, glm::vec3(0.5 * (1 - ninth) + ninth * 0.5)},
      {"ior 1", grey, 0, 1, 1.0f, 1, white, grey},
      {"ior 0 (F0 = 1)", grey, 0, 1, 0.0f, 1, white, glm::vec3(0.5)},
      {"ior 0, smooth", grey, 0, 0, 0.0f, 1, white, glm::vec3(0.0f)},
      {"ior 0, specular colour (0.5, 0.25, 0)", white, 0, 1, 0.0f, 1, {0.5f, 0.25f, 0.0f},
       glm::vec3(0.5 + 0.25, 0.5 + 0.125, 0.5)},
      {"specular colour 30 (F0 clamped to 1)", grey, 0, 1, 1.5f, 1, glm::vec3(30.0f),
       glm::vec3(0.5)},
      {"red specular colour", white, 0, 1, 1.5f, 1, {1, 0, 0},
       glm::vec3(0.96 + 0.02, 0.96, 0.96)},
      {"half metal, specular 0.5, ior 2", grey, 0.5f, 1, 2.0f, 0.5f, white,
       glm::vec3(0.5 * 0.5 * (1 - ninth / 2) + (ninth / 2 * 0.5 + 0.5 * 0.5) * 0.5)},
  };
  for (const Row& r : rows) {
    scenes::AlbedoInputs in;
    in.baseColor = r.base;
    in.metallic = r.metallic;
    in.roughness = r.roughness;
    in.ior = r.ior;
    in.specular = r.specular;
    in.specularColor = r.specularColor;
    const glm::vec3 a = bounceAlbedo(in);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(a[k], r.expected[k], 1e-6f) << r.what << " channel " << k;
      EXPECT_LE(a[k], 1.0f) << r.what;
    }
    // The same through a material and its factors.
    Scene scene;
    scenes::Material m;
    m.baseColorFactor = glm::vec4(r.base, 1.0f);
    m.metallicFactor = r.metallic;
    m.roughnessFactor = r.roughness;
    m.ior = r.ior;
    m.specularFactor = r.specular;
    m.specularColorFactor = r.specularColor;
    scene.materials.push_back(m);
    EXPECT_EQ(diffuseAlbedo(scene, 0, glm::vec2(0.5f)), a) << r.what;
    EXPECT_EQ(diffuseAlbedoFactor(m), a) << r.what;
  }
}

// specular 0 is a Lambertian surface: the base colour bit for bit (metallic 0), base ×
// (1 − metallic) plus the metal's own share otherwise.
TEST(BakerAlbedo, SpecularZeroIsLambertian) {
  uint32_t state = 12345u;
  auto unit = [&] {
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1u << 24);
  };
  for (int i = 0; i < 10000; ++i) {
    scenes::AlbedoInputs in;
    in.baseColor = glm::vec3(unit(), unit(), unit());
    in.metallic = 0.0f;
    in.roughness = unit();
    in.ior = i % 3 == 0 ? 0.0f : 1.0f + 3.0f * unit();
    in.specular = 0.0f;
    in.specularColor = glm::vec3(unit(), unit(), unit()) * 4.0f;
    ASSERT_EQ(bounceAlbedo(in), in.baseColor) << i;
    in.metallic = unit();
    const float r2 = in.roughness * in.roughness;
    const glm::vec3 a = bounceAlbedo(in);
    for (int k = 0; k < 3; ++k)
      ASSERT_NEAR(a[k], in.baseColor[k] * (1.0f - in.metallic) +
                            in.baseColor[k] * in.metallic * r2 * 0.5f, 1e-6f) << i;
  }
}

// The bounce albedo never exceeds 1 for a valid material: a grid over every input's range
// (with the corners, where the bound is tightest) and a random sample, every channel.
TEST(BakerAlbedo, NeverAboveOne) {
  const float unitGrid[] = {0.0f, 0.01f, 0.25f, 0.5f, 0.9f, 0.99f, 1.0f};
  const float iors[] = {0.0f, 1.0f, 1.001f, 1.33f, 1.5f, 2.4f, 10.0f, 1e6f};
  const float colourGrid[] = {0.0f, 0.5f, 1.0f, 4.0f, 25.0f, 1e6f};
  float worst = 0.0f;
  size_t checked = 0;
  auto check = [&](const scenes::AlbedoInputs& in) {
    const glm::vec3 a = bounceAlbedo(in);
    for (int k = 0; k < 3; ++k) {
      ASSERT_TRUE(std::isfinite(a[k]));
      ASSERT_GE(a[k], 0.0f);
      ASSERT_LE(a[k], 1.0f) << "base " << in.baseColor[k] << " metallic " << in.metallic
                            << " roughness " << in.roughness << " ior " << in.ior
                            << " specular " << in.specular << " colour " << in.specularColor[k];
      worst = std::max(worst, a[k]);
    }
    ++checked;
  };
  for (float b : unitGrid)
    for (float metallic : unitGrid)
      for (float roughness : unitGrid)
        for (float ior : iors)
          for (float specular : unitGrid)
            for (float c0 : colourGrid)
              for (float c1 : {0.0f, 1.0f, 25.0f}) {
                scenes::AlbedoInputs in;
                in.baseColor = glm::vec3(b, 1.0f, 0.0f);
                in.metallic = metallic;
                in.roughness = roughness;
                in.ior = ior;
                in.specular = specular;
                in.specularColor = glm::vec3(c0, c1, c0);
                check(in);
                if (::testing::Test::HasFatalFailure()) return;
              }
  uint32_t state = 777u;
  auto unit = [&] {
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float((1u << 24) - 1u);
  };
  for (int i = 0; i < 200000; ++i) {
    scenes::AlbedoInputs in;
    in.baseColor = glm::vec3(unit(), unit(), unit());
    in.metallic = unit();
    in.roughness = unit();
    in.ior = i % 10 == 0 ? 0.0f : 1.0f + 4.0f * unit() * unit();
    in.specular = unit();
    in.specularColor = glm::vec3(unit(), unit(), unit()) * (i % 2 ? 1.0f : 30.0f);
    check(in);
    if (::testing::Test::HasFatalFailure()) return;
  }
  // The bound is reached, never passed: white with specular 0 is exactly 1.
  EXPECT_EQ(worst, 1.0f);
  std::printf("bounce albedo <= 1 over %zu materials\n", checked);
}

TEST(BakerTexels, DeterministicAcrossThreadCounts) {
  const Scene scene = unwrapped(scenes::makeCornellBox(), 48.0f);
  auto tracer = buildOrDie(scene);
  ASSERT_TRUE(tracer);
  setThreadCount(1);
  const TexelSet a = texelsOrDie(scene, *tracer);
  const Clusters ca = computeClusters(scene, tracer.get(), a);
  setThreadCount(2);
  const TexelSet b = texelsOrDie(scene, *tracer);
  const Clusters cb = computeClusters(scene, tracer.get(), b);
  setThreadCount(0);
  ASSERT_EQ(a.size(), b.size());
  for (uint32_t t = 0; t < a.size(); ++t) {
    ASSERT_EQ(a.position[t], b.position[t]) << t;
    ASSERT_EQ(a.normal[t], b.normal[t]) << t;
    ASSERT_EQ(a.area[t], b.area[t]) << t;
    ASSERT_EQ(a.valid[t], b.valid[t]) << t;
    ASSERT_EQ(a.triangle[t], b.triangle[t]) << t;
  }
  EXPECT_EQ(a.atlases[0].texelOfPixel, b.atlases[0].texelOfPixel);
  EXPECT_EQ(ca.texelCluster, cb.texelCluster);
  EXPECT_EQ(ca.memberTexels, cb.memberTexels);
  ASSERT_EQ(ca.size(), cb.size());
  for (uint32_t c = 0; c < ca.size(); ++c) EXPECT_EQ(ca.position[c], cb.position[c]);
}

TEST(BakerTexels, SponzaAreasAndValidity) {
  AG_REQUIRE_SHARED_SCENE(path, "sponza/Sponza.gltf");
  Result<Scene> loaded = scenes::loadGltf(path);
  ASSERT_TRUE(loaded.isOk()) << loaded.message();
  const Scene scene = unwrapped(std::move(loaded.value()), 4.0f);
  auto tracer = buildOrDie(scene);
  ASSERT_TRUE(tracer);
  const auto start = std::chrono::steady_clock::now();
  const TexelSet texels = texelsOrDie(scene, *tracer);
  const double texelSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const Clusters clusters = computeClusters(scene, tracer.get(), texels);
  const double clusterSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() - texelSeconds;

  // World area of every lightmapped triangle with UV area: what the texels must add up to.
  double worldArea = 0.0, texelArea = 0.0;
  for (const scenes::Instance& inst : scene.instances) {
    if (!inst.isStatic || inst.lightmap.atlas < 0) continue;
    for (const scenes::Primitive& prim : scene.meshes[size_t(inst.mesh)].primitives) {
      if (prim.uv1.size() != prim.positions.size()) continue;
      for (size_t t = 0; t < prim.triangleCount(); ++t) {
        const uint32_t* i = &prim.indices[3 * t];
        const glm::vec2 e1 = prim.uv1[i[1]] - prim.uv1[i[0]], e2 = prim.uv1[i[2]] - prim.uv1[i[0]];
        if (std::abs(e1.x * e2.y - e1.y * e2.x) * float(inst.lightmap.width) *
                float(inst.lightmap.height) <= 2e-12f)
          continue;
        const glm::vec3 p0 = inst.toWorld(prim.positions[i[0]]);
        const glm::vec3 p1 = inst.toWorld(prim.positions[i[1]]);
        const glm::vec3 p2 = inst.toWorld(prim.positions[i[2]]);
        worldArea += 0.5 * double(glm::length(glm::cross(p1 - p0, p2 - p0)));
      }
    }
  }
  size_t valid = 0;
  const scenes::Bounds bounds = scene.bounds();
  for (uint32_t t = 0; t < texels.size(); ++t) {
    texelArea += texels.area[t];
    valid += texels.valid[t];
    const glm::vec3 p = texels.position[t];
    ASSERT_TRUE(glm::all(glm::greaterThanEqual(p, bounds.min - 0.05f)) &&
                glm::all(glm::lessThanEqual(p, bounds.max + 0.05f)))
        << t;
  }
  EXPECT_NEAR(texelArea, worldArea, 0.01 * worldArea);
  EXPECT_GT(valid, texels.size() * 7 / 10);
  // Every valid texel sits in exactly one front-side cluster (the back sides of Sponza's
  // double-sided plants and chains have clusters of their own on top).
  size_t members = 0;
  for (uint32_t c = 0; c < clusters.size(); ++c)
    if (!clusters.back[c]) members += clusters.firstTexel[c + 1] - clusters.firstTexel[c];
  EXPECT_EQ(members, valid);
  std::printf("sponza at 4 texels/m: %u texels (%zu valid), area %.1f of %.1f m², texels %.2f s, "
              "%u clusters (%zu under 4 texels) %.2f s\n",
              texels.size(), valid, texelArea, worldArea, texelSeconds, clusters.size(),
              tinyClusters(clusters), clusterSeconds);
}

}  // namespace
}  // namespace afterglow::baker

namespace afterglow::baker {
namespace {

// Texture detail finer than a texel reaches the bounces as its mean over the texel (an
// engine's meta pass renders albedo at lightmap resolution), not as whatever texture point
// the texel's sample lands on: a 2 m floor at 4 texels/m whose base colour is a black and
// white checker of 4-pixel cells on a 64² texture spanning the floor, 8 texture pixels a
// texel, shifted by a pixel so that no texel's sample sits on a cell's edge. Every cluster of
// one texel has the checker's mean, 0.5, as its albedo (specularFactor 0: albedo is the base
// colour); the texel's sample alone reads black or white.
TEST(BakerClusters, AlbedoIsTheTexturesMeanOverTheTexel) {
  scenes::Scene scene = groundQuad("checker", 1.0f, 1.0f, 0.0f);
  scenes::Texture checker;
  checker.name = "checker";
  checker.width = checker.height = 64;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      checker.texels.push_back(glm::vec4(glm::vec3(float(((x / 4) + (y / 4)) % 2)), 1.0f));
  scene.textures.push_back(checker);
  scene.materials[0].baseColorTexture.texture = 0;
  scenes::Primitive& floor = scene.meshes[0].primitives[0];
  for (const glm::vec3& p : floor.positions)
    floor.uv0.push_back(glm::vec2(p.x, p.z) * 0.5f + 0.5f + 1.0f / 64.0f);
  const Scene lit = unwrapped(std::move(scene), 4.0f);
  auto tracer = buildOrDie(lit);
  ASSERT_TRUE(tracer);
  const TexelSet texels = texelsOrDie(lit, *tracer);
  ClusterOptions options;
  options.clusterSize = 0.1f;  // a texel a cluster: no averaging over neighbours
  options.clusterTexels = 1.0f;
  options.minTexels = 1;
  const Clusters clusters = computeClusters(lit, nullptr, texels, nullptr, options);
  ASSERT_EQ(clusters.size(), texels.size());
  float lo = 1.0f, hi = 0.0f;
  for (uint32_t c = 0; c < clusters.size(); ++c) {
    lo = std::min(lo, clusters.albedo[c].x);
    hi = std::max(hi, clusters.albedo[c].x);
  }
  std::printf("%u texels, %u clusters, albedo %.3f to %.3f (the checker's mean 0.5)\n", texels.size(), clusters.size(),
              double(lo), double(hi));
  EXPECT_GE(lo, 0.45f);
  EXPECT_LE(hi, 0.55f);
}

}  // namespace
}  // namespace afterglow::baker
