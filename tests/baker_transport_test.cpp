// Form factors, sky transfer, validity and unit direct light (baker/src/links.cpp, direct.cpp)
// on hand-built scenes with analytic answers, checked also through the runtime Solver.
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/baker/direct.h"
#include "afterglow/baker/gather.h"
#include "afterglow/baker/links.h"
#include "afterglow/baker/probe_transfer.h"
#include "afterglow/core/math.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/uv/unwrap.h"

namespace afterglow::baker {
namespace {

using scenes::Scene;
constexpr float kY00 = 0.282094791773878f;  // 1 / (2√π)

scenes::Material material(const std::string& name, glm::vec3 albedo, glm::vec3 emission = {}) {
  scenes::Material m;
  m.name = name;
  m.baseColorFactor = glm::vec4(albedo, 1.0f);
  m.metallicFactor = 0.0f;
  m.specularFactor = 0.0f;  // KHR_materials_specular 0: Lambertian, the albedo is exactly albedo
  m.emissiveFactor = emission;
  return m;
}

// Hand-built scenes with texels on a regular grid per quad and square blocks of texels as
// clusters, so the tests do not depend on the rasteriser or the clusterer.
struct Builder {
  Scene scene;
  TexelSet texels;
  Clusters clusters;
  std::vector<std::vector<uint32_t>> groups;

  // The parallelogram corner + [0,1]·e1 + [0,1]·e2, front normal e1 × e2, uv1 = (s, t) over
  // an n×n atlas of its own. block = texels per cluster edge; n = 0 gives no lightmap.
  int addQuad(glm::vec3 corner, glm::vec3 e1, glm::vec3 e2, int n, int block, int mat,
              bool isStatic = true) {
    const glm::vec3 normal = glm::normalize(glm::cross(e1, e2));
    scenes::Primitive p;
    p.material = mat;
    p.positions = {corner, corner + e1, corner + e1 + e2, corner + e2};
    p.normals.assign(4, normal);
    p.uv0 = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    p.uv1 = p.uv0;
    p.indices = {0, 1, 2, 0, 2, 3};
    scenes::Mesh mesh;
    mesh.name = "quad" + std::to_string(scene.meshes.size());
    mesh.primitives.push_back(p);
    scene.meshes.push_back(mesh);
    scenes::Instance inst;
    inst.name = mesh.name;
    inst.mesh = int(scene.meshes.size()) - 1;
    inst.isStatic = isStatic;
    const uint32_t instance = uint32_t(scene.instances.size());
    if (n > 0 && isStatic) {
      inst.lightmap = {int(texels.atlases.size()), n, n};
      runtime::AtlasLayout layout;
      layout.width = layout.height = n;
      layout.texelOfPixel.assign(size_t(n) * size_t(n), runtime::kNoTexel);
      std::map<std::pair<int, int>, size_t> groupOfBlock;
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          const uint32_t t = texels.size();
          const float s = (float(i) + 0.5f) / float(n), u = (float(j) + 0.5f) / float(n);
          layout.texelOfPixel[size_t(j) * size_t(n) + size_t(i)] = t;
          texels.position.push_back(corner + s * e1 + u * e2 + 1e-4f * normal);
          texels.normal.push_back(normal);
          texels.geometricNormal.push_back(normal);
          texels.area.push_back(glm::length(glm::cross(e1, e2)) / float(n * n));
          texels.instance.push_back(instance);
          texels.primitive.push_back(0);
          texels.triangle.push_back(s >= u ? 0 : 1);
          texels.uv0.push_back({s, u});
          texels.atlas.push_back(uint16_t(inst.lightmap.atlas));
          texels.pixel.push_back({uint16_t(i), uint16_t(j)});
          texels.offset.push_back(1e-4f);
          texels.edge.push_back(glm::length(e1) / float(n));
          texels.nearGeometry.push_back(0);
          texels.valid.push_back(1);
          auto key = std::make_pair(i / block, j / block);
          auto it = groupOfBlock.find(key);
          if (it == groupOfBlock.end()) {
            it = groupOfBlock.emplace(key, groups.size()).first;
            groups.emplace_back();
          }
          groups[it->second].push_back(t);
        }
      }
      texels.atlases.push_back(std::move(layout));
    }
    scene.instances.push_back(inst);
    return int(instance);
  }

  void finish() {
    clusters = Clusters();
    clusters.texelCluster.assign(texels.size(), runtime::kNoTexel);
    clusters.texelBackCluster.assign(texels.size(), runtime::kNoTexel);
    clusters.firstTexel.push_back(0);
    for (uint32_t c = 0; c < groups.size(); ++c) {
      float area = 0.0f;
      glm::vec3 pos(0.0f), nrm(0.0f);
      for (uint32_t t : groups[c]) {
        clusters.texelCluster[t] = c;
        clusters.memberTexels.push_back(t);
        area += texels.area[t];
        pos += texels.area[t] * texels.position[t];
        nrm += texels.area[t] * texels.normal[t];
      }
      clusters.firstTexel.push_back(uint32_t(clusters.memberTexels.size()));
      clusters.position.push_back(pos / area);
      clusters.normal.push_back(glm::normalize(nrm));
      clusters.area.push_back(area);
      const int mat = scene.meshes[size_t(scene.instances[texels.instance[groups[c][0]]].mesh)]
                          .primitives[0]
                          .material;
      clusters.material.push_back(uint32_t(mat));
      const scenes::Material& m = scene.material(mat);
      clusters.albedo.push_back(glm::vec3(m.baseColorFactor));
      clusters.emission.push_back(m.emission());
      clusters.back.push_back(0);
    }
  }

  std::unique_ptr<trace::RayTracer> tracer() const {
    auto result = trace::RayTracer::build(scene);
    EXPECT_TRUE(result.isOk()) << result.message();
    return result.isOk() ? std::move(result.value()) : nullptr;
  }
};

// The texels' gather, then the links from it (what bake() does between them, clustering, is
// done by hand in these tests).
// The gather's point of each texel comes back through `pointOfTexel` when asked for.
Status gatherAndLink(const Scene& scene, const trace::RayTracer& tracer, TexelSet& texels,
                     const Clusters& clusters, const LinkOptions& options,
                     runtime::TransportData& data, std::vector<uint32_t>* pointOfTexel = nullptr,
                     const std::vector<Clusters>& farLevels = {}) {
  Result<TexelGather> gather = gatherTexels(scene, tracer, texels, options);
  if (!gather) return gather.status();
  if (pointOfTexel) *pointOfTexel = gather->pointOfTexel;
  return computeLinks(scene, tracer, texels, gather.value(), clusters, options, data,
                      nullProgress(), farLevels);
}

// Two sets of links alike bit for bit: rows, links (targets and codes) and row scales.
void expectSameLinks(const runtime::SparseLinks& a, const runtime::SparseLinks& b) {
  EXPECT_EQ(a.rowStart, b.rowStart);
  EXPECT_EQ(a.link, b.link);
  EXPECT_EQ(a.rowScale, b.rowScale);
}

float rowSum(const runtime::SparseLinks& links, size_t row) {
  float sum = 0.0f;
  for (uint32_t k = links.rowStart[row]; k < links.rowStart[row + 1]; ++k)
    sum += links.weightAt(row, k);
  return sum;
}

float texelSky(const runtime::TransportData& data, uint32_t t, int i = 0) {
  return runtime::halfToFloat(data.texelSky[size_t(t) * runtime::kShCount + size_t(i)]);
}

// What a cluster gathers, as one dense row over the clusters: its gather rows (its texels'
// gather points, or its own back-side row) composed with their links.
std::vector<double> clusterRow(const runtime::TransportData& data, uint32_t c) {
  std::vector<double> row(data.clusterCount, 0.0);
  const runtime::SparseMatrix& a = data.clusterGather;
  for (uint32_t i = a.rowStart[c]; i < a.rowStart[c + 1]; ++i) {
    const uint32_t r = a.column[i];
    for (uint32_t k = data.links.rowStart[r]; k < data.links.rowStart[r + 1]; ++k)
      row[data.links.targetAt(k)] += double(a.weight[i]) * double(data.links.weightAt(r, k));
  }
  return row;
}

double sum(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s;
}

// Two coaxial parallel squares of side a at distance c (X = a / c), the standard closed form.
double parallelSquaresFormFactor(double x) {
  const double x2 = x * x;
  return 2.0 / (kPi * x2) *
         (std::log(std::sqrt((1 + x2) * (1 + x2) / (1 + 2 * x2))) +
          2.0 * x * std::sqrt(1 + x2) * std::atan(x / std::sqrt(1 + x2)) - 2.0 * x * std::atan(x));
}

TEST(BakerTransport, ParallelSquaresFormFactorsRowsAndReciprocity) {
  EXPECT_NEAR(parallelSquaresFormFactor(1.0), 0.1998, 1e-4);
  Builder b;
  b.scene.materials.push_back(material("grey", glm::vec3(0.5f)));
  const int n = 16, block = 8;
  b.addQuad({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, n, block, 0);  // A, facing +Y
  b.addQuad({0, 1, 0}, {1, 0, 0}, {0, 0, 1}, n, block, 0);  // B, facing -Y, 1 m above
  b.finish();
  auto tracer = b.tracer();
  ASSERT_TRUE(tracer);
  LinkOptions opt;
  opt.texelRays = 1024;
  opt.clusterRays = 16384;
  runtime::TransportData data;
  std::vector<uint32_t> pointOf;
  ASSERT_TRUE(gatherAndLink(b.scene, *tracer, b.texels, b.clusters, opt, data, &pointOf).isOk());
  ASSERT_EQ(data.texelCount, b.texels.size());
  ASSERT_EQ(data.clusterCount, 8u);
  // Open flat squares: every texel shares a 2×2 block's gather point; no back-side rows.
  ASSERT_EQ(data.gatherPointCount, uint32_t(2 * n * n / 4));
  ASSERT_EQ(data.links.rows(), size_t(data.gatherPointCount));

  // Area-weighted mean over A of each texel's gather-point links to B's clusters (4..7).
  const uint32_t texelsA = uint32_t(n * n);
  double fab = 0.0, areaA = 0.0;
  for (uint32_t t = 0; t < 2 * texelsA; ++t) {
    ASSERT_TRUE(b.texels.valid[t]) << t;
    const uint32_t p = pointOf[t];
    ASSERT_LT(p, data.gatherPointCount) << t;
    // Every ray either reaches a cluster or leaves to the sky: row + miss fraction = 1 (the
    // sky transfer is stored as half floats).
    const float missFraction = texelSky(data, t) / kY00;
    EXPECT_NEAR(rowSum(data.links, p) + missFraction, 1.0f, 1e-3f) << t;
    for (uint32_t k = data.links.rowStart[p]; k < data.links.rowStart[p + 1]; ++k) {
      const uint32_t c = data.links.targetAt(k);
      // Flat squares never see themselves.
      EXPECT_EQ(c >= 4, t < texelsA) << "texel " << t << " links cluster " << c;
      if (t < texelsA) fab += double(b.texels.area[t]) * data.links.weightAt(p, k);
    }
    if (t < texelsA) areaA += b.texels.area[t];
  }
  fab /= areaA;
  // 128 × 1024 stratified rays: sampling error well below 0.002.
  EXPECT_NEAR(fab, parallelSquaresFormFactor(1.0), 0.003);

  // Cluster -> cluster (through the gather points of the cluster's texels): reciprocity
  // A_i F_ij = A_j F_ji, and the cluster rows against A's.
  std::vector<std::vector<double>> f(8);
  for (uint32_t c = 0; c < 8; ++c) {
    f[c] = clusterRow(data, c);
    const float miss = runtime::halfToFloat(data.clusterSky[size_t(c) * runtime::kShCount]) / kY00;
    EXPECT_NEAR(sum(f[c]) + miss, 1.0, 2e-3);
  }
  // A cluster of 8×8 texels pools 16 gather points of 1024 rays.
  const double clusterRays = 16.0 * opt.texelRays;
  double clusterFab = 0.0;
  for (uint32_t i = 0; i < 4; ++i) {
    for (uint32_t j = 4; j < 8; ++j) {
      const double ai = b.clusters.area[i], aj = b.clusters.area[j];
      const double sigma = std::sqrt(std::max(f[i][j], 0.01) / clusterRays);
      EXPECT_NEAR(ai * f[i][j], aj * f[j][i], 4.0 * ai * sigma) << i << "->" << j;
      EXPECT_GT(f[i][j], 0.01);
      clusterFab += 0.25 * f[i][j];
    }
  }
  EXPECT_NEAR(clusterFab, parallelSquaresFormFactor(1.0), 0.003);
}

TEST(BakerTransport, LinksAndDirectAreIndependentOfThreadCount) {
  Builder b;
  b.scene.materials.push_back(material("grey", glm::vec3(0.5f)));
  b.scene.materials.push_back(material("lamp", glm::vec3(0.5f), glm::vec3(3.0f)));
  b.addQuad({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, 8, 4, 0);
  b.addQuad({0, 0, 0}, {0, 1, 0}, {0, 0, 1}, 8, 4, 0);  // wall at x = 0 facing +X
  b.addQuad({0.4f, 0.8f, 0.4f}, {0.2f, 0, 0}, {0, 0, 0.2f}, 2, 2, 1);  // lamp facing down
  scenes::Light l;
  l.type = scenes::LightType::Point;
  l.position = {0.7f, 0.5f, 0.5f};
  l.radius = 0.05f;
  b.scene.lights.push_back(l);
  b.finish();
  auto tracer = b.tracer();
  ASSERT_TRUE(tracer);
  LinkOptions opt;
  opt.texelRays = 32;
  opt.clusterRays = 64;
  runtime::TransportData one, two;
  const int saved = threadCount();
  setThreadCount(1);
  TexelSet texels1 = b.texels;
  ASSERT_TRUE(gatherAndLink(b.scene, *tracer, texels1, b.clusters, opt, one).isOk());
  ASSERT_TRUE(computeDirect(b.scene, *tracer, texels1, b.clusters, {}, one).isOk());
  setThreadCount(2);
  TexelSet texels2 = b.texels;
  ASSERT_TRUE(gatherAndLink(b.scene, *tracer, texels2, b.clusters, opt, two).isOk());
  ASSERT_TRUE(computeDirect(b.scene, *tracer, texels2, b.clusters, {}, two).isOk());
  setThreadCount(saved);
  ASSERT_EQ(one.sources.size(), 2u);  // the point light, then the lamp material
  EXPECT_EQ(one.sources[1].kind, runtime::SourceKind::Emissive);
  EXPECT_EQ(one.sources[1].material, 1u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(one.sources[i].texelTransfer, two.sources[i].texelTransfer);
    EXPECT_EQ(one.sources[i].clusterTransfer, two.sources[i].clusterTransfer);
  }
  EXPECT_GT(one.sources[1].texelTransfer[0], 0.0f);
  EXPECT_EQ(one.gatherPointCount, two.gatherPointCount);
  expectSameLinks(one.links, two.links);
  for (auto m : {&runtime::TransportData::clusterGather, &runtime::TransportData::pointFilter,
                 &runtime::TransportData::texelGather}) {
    EXPECT_EQ((one.*m).rowStart, (two.*m).rowStart);
    EXPECT_EQ((one.*m).column, (two.*m).column);
    EXPECT_EQ((one.*m).weight, (two.*m).weight);
  }
  EXPECT_EQ(one.texelSky, two.texelSky);
  EXPECT_EQ(one.clusterSky, two.clusterSky);
  EXPECT_GT(one.links.size(), 0u);
}

TEST(BakerTransport, OpenFloorSeesTheSkyAsSh) {
  Builder b;
  b.scene.materials.push_back(material("grey", glm::vec3(0.5f)));
  b.addQuad({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, 2, 2, 0);
  b.finish();
  auto tracer = b.tracer();
  ASSERT_TRUE(tracer);
  LinkOptions opt;
  opt.texelRays = 4096;
  runtime::TransportData data;
  ASSERT_TRUE(gatherAndLink(b.scene, *tracer, b.texels, b.clusters, opt, data).isOk());
  EXPECT_EQ(data.links.size(), 0u);
  for (uint32_t t = 0; t < 4; ++t) {
    // Half floats: within 2^-11 relative.
    EXPECT_NEAR(texelSky(data, t, 0), kY00, kY00 / 2048.0f);
    // Cosine-weighted mean of the up axis is 2/3; the horizontal ones vanish.
    EXPECT_NEAR(texelSky(data, t, 1), 0.488603f * 2.0f / 3.0f, 0.003f);
    EXPECT_NEAR(texelSky(data, t, 3), 0.0f, 0.01f);
    EXPECT_NEAR(texelSky(data, t, 2), 0.0f, 0.01f);
  }
  // A constant sky of radiance L gives E/π = L through the runtime (to half precision).
  runtime::constantSkySh(glm::vec3(2.0f, 1.0f, 0.5f), data.skySh);
  runtime::Solver solver(data);
  solver.solve();
  std::vector<glm::vec3> out;
  solver.gatherTexels(out);
  for (const glm::vec3& v : out) {
    EXPECT_NEAR(v.x, 2.0f, 2.0f / 1024.0f);
    EXPECT_NEAR(v.z, 0.5f, 0.5f / 1024.0f);
  }
}

TEST(BakerTransport, BackFacesOfSingleSidedGeometryInvalidateTexels) {
  Builder b;
  b.scene.materials.push_back(material("grey", glm::vec3(0.5f)));
  b.addQuad({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, 4, 2, 0);
  // A lid just above the left half of the floor, facing up: the texels below see its back.
  b.addQuad({-1, 0.01f, -1}, {0, 0, 3}, {1.5f, 0, 0}, 0, 1, 0);
  b.finish();
  auto tracer = b.tracer();
  ASSERT_TRUE(tracer);
  LinkOptions opt;
  opt.texelRays = 256;
  runtime::TransportData data;
  ASSERT_TRUE(gatherAndLink(b.scene, *tracer, b.texels, b.clusters, opt, data).isOk());
  int invalid = 0;
  for (uint32_t t = 0; t < b.texels.size(); ++t) {
    const bool covered = b.texels.position[t].x < 0.5f;
    EXPECT_EQ(b.texels.valid[t] == 0, covered) << t;
    if (!b.texels.valid[t]) {
      ++invalid;
      // Invalid texels read no gather point and no sky.
      EXPECT_EQ(data.texelGather.rowStart[t], data.texelGather.rowStart[t + 1]);
      EXPECT_EQ(texelSky(data, t), 0.0f);
    }
  }
  EXPECT_EQ(invalid, 8);
}

// A slab cuts through a wall, as Sponza's roof cuts through its cornices: the wall's texel row
// across the slab is buried, and the rays from a closed room under the slab that land on that
// row's lower part must take the light of a wall texel under the slab, never of the one above
// it (in the sun). The wall's rows run downwards, so the nearest texel in scan order is the one
// above.
TEST(BakerTransport, HitsOnABuriedTexelTakeANeighbourTheHitSees) {
  Builder b;
  b.scene.materials.push_back(material("grey", glm::vec3(0.5f)));
  const float slab = 1.125f;  // the wall's row 3 has its samples in the slab
  b.addQuad({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, 4, 1, 0);    // floor, facing up
  b.addQuad({0, 2, 0}, {0, 0, 1}, {0, -2, 0}, 8, 1, 0);   // wall at x = 0 facing +X, rows down
  b.addQuad({0, slab - 0.005f, 0}, {1, 0, 0}, {0, 0, 1}, 4, 1, 0);  // slab underside, facing -Y
  b.addQuad({0, slab + 0.005f, 0}, {0, 0, 1}, {1, 0, 0}, 4, 1, 0);  // slab top, facing +Y
  // The room's other walls, up to the slab.
  b.addQuad({1, 0, 0}, {0, 0, 1}, {0, slab, 0}, 4, 1, 0);  // x = 1, facing -X
  b.addQuad({0, 0, 0}, {1, 0, 0}, {0, slab, 0}, 4, 1, 0);  // z = 0, facing +Z
  b.addQuad({0, 0, 1}, {0, slab, 0}, {1, 0, 0}, 4, 1, 0);  // z = 1, facing -Z
  b.finish();
  auto tracer = b.tracer();
  ASSERT_TRUE(tracer);
  LinkOptions opt;
  opt.texelRays = 1024;
  runtime::TransportData data;
  std::vector<uint32_t> pointOf;
  ASSERT_TRUE(gatherAndLink(b.scene, *tracer, b.texels, b.clusters, opt, data, &pointOf).isOk());
  const uint32_t floorTexels = 16, wallTexels = 64;
  int buried = 0;
  for (uint32_t t = floorTexels; t < floorTexels + wallTexels; ++t)
    if (!b.texels.valid[t]) {
      ++buried;
      EXPECT_NEAR(b.texels.position[t].y, slab, 0.01f) << "wall texel " << t;
    }
  ASSERT_GT(buried, 0) << "the slab buries no wall texel: the test lost its point";
  for (uint32_t t = 0; t < floorTexels; ++t) {
    ASSERT_TRUE(b.texels.valid[t]);
    const uint32_t p = pointOf[t];
    double below = 0.0;
    for (uint32_t k = data.links.rowStart[p]; k < data.links.rowStart[p + 1]; ++k) {
      if (runtime::SparseLinks::isPadding(data.links.link[k], data.links.targetBits)) continue;
      const uint32_t c = data.links.targetAt(k);
      EXPECT_LT(b.clusters.position[c].y, slab) << "floor texel " << t << " links cluster " << c
                                                 << " above the slab";
      below += data.links.weightAt(p, k);
    }
    // A closed room: every ray lands on a texel, and what lands on the buried row is not lost.
    EXPECT_NEAR(below, 1.0, 0.01) << "floor texel " << t;
  }
}

// Solves a furnace's transport to convergence for albedos 0.5 and 0.9 and expects every texel
// (every valid one, given `valid`) at the analytic E/π = Le / (1 − ρ) within 1%.
void expectFurnaceRadiance(runtime::TransportData& data, const std::vector<uint8_t>* valid,
                           float le = 1.0f) {
  for (float rho : {0.5f, 0.9f}) {
    data.materials[0].albedo = glm::vec3(rho);
    runtime::Solver solver(data);
    runtime::SolveOptions sopt;
    sopt.tolerance = 1e-6f;
    solver.solve(sopt);
    std::vector<glm::vec3> out;
    solver.gatherTexels(out);
    const float expected = le / (1.0f - rho);
    float worst = 0.0f;
    for (uint32_t t = 0; t < data.texelCount; ++t)
      if (!valid || (*valid)[t]) worst = std::max(worst, std::abs(out[t].x - expected) / expected);
    EXPECT_LT(worst, 0.01f) << "rho " << rho;
  }
}

// The procedural furnace box (ρ exactly 0.5, Le 1) unwrapped at 16 texels/m, with its tracer
// and texels. (The tracer refers to the scene, so the box stays where it was built.)
struct FurnaceBox {
  Scene scene;
  std::unique_ptr<trace::RayTracer> tracer;
  TexelSet texels;
};

void buildFurnaceBox(FurnaceBox& box) {
  scenes::FurnaceOptions fo;
  fo.albedo = glm::vec3(0.5f);
  fo.emission = glm::vec3(1.0f);
  box.scene = scenes::makeFurnaceBox(fo);
  box.scene.materials[0].specularFactor = 0.0f;  // Lambertian: ρ is exactly 0.5
  uv::UnwrapOptions uopt;
  uopt.pack.texelsPerUnit = 16.0f;
  ASSERT_TRUE(uv::unwrap(box.scene, uopt).isOk());
  auto built = trace::RayTracer::build(box.scene);
  ASSERT_TRUE(built.isOk()) << built.message();
  box.tracer = std::move(built.value());
  Result<TexelSet> texels = computeTexels(box.scene, *box.tracer);
  ASSERT_TRUE(texels.isOk()) << texels.message();
  box.texels = std::move(texels.value());
}

// The furnace box's clusters and one level of far clusters (default options).
struct FurnaceClusters {
  Clusters clusters;
  std::vector<Clusters> far;
};

FurnaceClusters clusterFurnaceBox(const FurnaceBox& box) {
  ClusterOptions copt;
  FurnaceClusters out;
  out.clusters = computeClusters(box.scene, box.tracer.get(), box.texels, nullptr, copt);
  out.far = {computeClusters(box.scene, box.tracer.get(), box.texels, nullptr,
                             farClusterOptions(copt, 1))};
  return out;
}

Status gatherAndLink(FurnaceBox& box, const Clusters& clusters, const LinkOptions& options,
                     runtime::TransportData& data, std::vector<uint32_t>* pointOfTexel = nullptr,
                     const std::vector<Clusters>& farLevels = {}) {
  return gatherAndLink(box.scene, *box.tracer, box.texels, clusters, options, data, pointOfTexel,
                       farLevels);
}

// Direct light from the box's emissive walls, then the solve against Le / (1 − ρ).
void expectLinkedFurnace(const FurnaceBox& box, const Clusters& clusters,
                         runtime::TransportData& data) {
  DirectOptions dopt;
  dopt.emissiveSamples = 2048;
  ASSERT_TRUE(computeDirect(box.scene, *box.tracer, box.texels, clusters, dopt, data).isOk());
  expectFurnaceRadiance(data, &box.texels.valid);
}

// A closed cube of six quads, every surface with albedo ρ and radiance Le: every texel's row
// sums to 1, no sky, and the solved E/π is Le / (1 − ρ).
TEST(BakerTransport, WhiteFurnaceConvergesToAnalyticRadiance) {
  const float le = 1.0f;
  Builder b;
  b.scene.materials.push_back(material("furnace", glm::vec3(0.5f), glm::vec3(le)));
  const int n = 8, block = 4;
  b.addQuad({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, n, block, 0);  // floor, +Y
  b.addQuad({0, 1, 0}, {1, 0, 0}, {0, 0, 1}, n, block, 0);  // ceiling, -Y
  b.addQuad({0, 0, 0}, {0, 1, 0}, {0, 0, 1}, n, block, 0);  // x = 0, +X
  b.addQuad({1, 0, 0}, {0, 0, 1}, {0, 1, 0}, n, block, 0);  // x = 1, -X
  b.addQuad({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, n, block, 0);  // z = 0, +Z
  b.addQuad({0, 0, 1}, {0, 1, 0}, {1, 0, 0}, n, block, 0);  // z = 1, -Z
  b.finish();
  auto tracer = b.tracer();
  ASSERT_TRUE(tracer);
  LinkOptions lopt;
  lopt.texelRays = 256;
  lopt.clusterRays = 1024;
  DirectOptions dopt;
  dopt.emissiveSamples = 4096;
  runtime::TransportData data;
  std::vector<uint32_t> pointOf;
  ASSERT_TRUE(gatherAndLink(b.scene, *tracer, b.texels, b.clusters, lopt, data, &pointOf).isOk());
  ASSERT_TRUE(computeDirect(b.scene, *tracer, b.texels, b.clusters, dopt, data).isOk());
  ASSERT_EQ(data.sources.size(), 1u);
  EXPECT_EQ(data.sources[0].kind, runtime::SourceKind::Emissive);
  ASSERT_EQ(data.materials.size(), 1u);
  EXPECT_EQ(data.materials[0].albedo, glm::vec3(0.5f));
  EXPECT_EQ(data.materials[0].emission, glm::vec3(le));
  for (uint32_t t = 0; t < data.texelCount; ++t) {
    ASSERT_TRUE(b.texels.valid[t]);
    EXPECT_NEAR(rowSum(data.links, pointOf[t]), 1.0f, 1e-3f) << t;
    EXPECT_NEAR(texelSky(data, t), 0.0f, 1e-3f * kY00) << t;
  }
  for (uint32_t c = 0; c < data.clusterCount; ++c)
    EXPECT_NEAR(sum(clusterRow(data, c)), 1.0, 1e-3) << c;

  expectFurnaceRadiance(data, nullptr, le);
}

// The same furnace through the whole precompute: procedural box, generated UVs, rasterised
// texels and computed clusters.
TEST(BakerTransport, WhiteFurnaceThroughTexelsAndClusters) {
  FurnaceBox box;
  ASSERT_NO_FATAL_FAILURE(buildFurnaceBox(box));
  const Scene& scene = box.scene;
  const trace::RayTracer& tracer = *box.tracer;
  TexelSet& texels = box.texels;
  const Clusters clusters = computeClusters(scene, &tracer, texels);
  ASSERT_GT(texels.size(), 1000u);
  LinkOptions lopt;
  lopt.texelRays = 256;
  lopt.clusterRays = 512;
  DirectOptions dopt;
  dopt.emissiveSamples = 2048;
  runtime::TransportData data;
  std::vector<uint32_t> pointOf;
  ASSERT_TRUE(gatherAndLink(scene, tracer, texels, clusters, lopt, data, &pointOf).isOk());
  ASSERT_TRUE(computeDirect(scene, tracer, texels, clusters, dopt, data).isOk());
  ASSERT_EQ(data.materials.size(), 1u);
  EXPECT_NEAR(data.materials[0].albedo.x, 0.5f, 1e-6f);
  size_t valid = 0;
  for (uint32_t t = 0; t < data.texelCount; ++t) {
    if (!texels.valid[t]) continue;
    ++valid;
    EXPECT_NEAR(rowSum(data.links, pointOf[t]), 1.0f, 2e-3f) << t;
  }
  EXPECT_GT(valid, 0.95 * data.texelCount);
  expectFurnaceRadiance(data, &box.texels.valid);
}

// Far clusters keep the furnace exact: a far hit's weight moves whole to the far cluster, whose
// light is its clusters' area-weighted mean, so rows keep their sums and the furnace its
// analytic radiance; and they make fewer links than the same gather without them.
TEST(BakerTransport, WhiteFurnaceThroughFarClusters) {
  FurnaceBox box;
  ASSERT_NO_FATAL_FAILURE(buildFurnaceBox(box));
  const FurnaceClusters clustered = clusterFurnaceBox(box);
  const Clusters& clusters = clustered.clusters;
  const std::vector<Clusters>& far = clustered.far;
  ASSERT_LT(far[0].size(), clusters.size());
  LinkOptions lopt;
  lopt.texelRays = 256;
  lopt.farDistance = 1.0f;  // far targets for most hits across the box
  lopt.sharedFarSpan = 0;   // (shared far fields: the next test)
  runtime::TransportData plain, data;
  std::vector<uint32_t> pointOf;
  ASSERT_TRUE(gatherAndLink(box, clusters, lopt, plain).isOk());
  ASSERT_TRUE(gatherAndLink(box, clusters, lopt, data, &pointOf, far).isOk());
  ASSERT_GT(data.farClusters.rows(), 0u);
  size_t farLinks = 0;
  for (size_t k = 0; k < data.links.size(); ++k)
    if (!runtime::SparseLinks::isPadding(data.links.link[k], data.links.targetBits))
      farLinks += data.links.targetAt(k) >= data.clusterCount;
  ASSERT_GT(farLinks, data.links.linkCount() / 8);
  EXPECT_LT(double(data.links.linkCount()), 0.8 * double(plain.links.linkCount()));
  for (uint32_t f = 0; f < data.farClusters.rows(); ++f) {
    double sum = 0.0;
    for (uint32_t k = data.farClusters.rowStart[f]; k < data.farClusters.rowStart[f + 1]; ++k)
      sum += data.farClusters.weight[k];
    EXPECT_NEAR(sum, 1.0, 1e-5) << "far cluster " << f;
  }
  for (uint32_t t = 0; t < data.texelCount; ++t) {
    if (!box.texels.valid[t]) continue;
    EXPECT_NEAR(rowSum(data.links, pointOf[t]), 1.0f, 2e-3f) << t;
  }

  expectLinkedFurnace(box, clusters, data);
}

// A far cluster of a single cluster reflects that cluster's light: its hits link the cluster
// itself, with no far row. Far clusters that are the clusters themselves then change nothing:
// the same links, bit for bit, as without far clusters.
TEST(BakerTransport, FarClustersOfOneClusterLinkThatCluster) {
  FurnaceBox box;
  ASSERT_NO_FATAL_FAILURE(buildFurnaceBox(box));
  const FurnaceClusters clustered = clusterFurnaceBox(box);
  const Clusters& clusters = clustered.clusters;
  LinkOptions lopt;
  lopt.texelRays = 64;
  lopt.farDistance = 1.0f;
  lopt.sharedFarSpan = 0;  // (sharing would pool the far hits)
  runtime::TransportData plain, data;
  ASSERT_TRUE(gatherAndLink(box, clusters, lopt, plain).isOk());
  ASSERT_TRUE(gatherAndLink(box, clusters, lopt, data, nullptr, {clusters}).isOk());
  EXPECT_EQ(data.farClusters.rows(), 0u);
  EXPECT_EQ(data.sharedFarBase(), data.clusterCount);
  expectSameLinks(data.links, plain.links);
  expectLinkedFurnace(box, clusters, data);
}

// Shared far fields move light, never make or lose it: a point that shares one links it with
// exactly the weight its own far-cluster links had (so its row sum, its visibility, stays its
// own), a shared row sums to 1, and the furnace stays exact; with fewer links than without.
TEST(BakerTransport, SharedFarFieldsKeepEachPointsFarShareAndTheFurnace) {
  FurnaceBox box;
  ASSERT_NO_FATAL_FAILURE(buildFurnaceBox(box));
  const FurnaceClusters clustered = clusterFurnaceBox(box);
  const Clusters& clusters = clustered.clusters;
  const std::vector<Clusters>& far = clustered.far;
  LinkOptions lopt;
  lopt.texelRays = 256;
  lopt.farDistance = 1.0f;
  lopt.blockDistance = 1e6f;  // every texel gathers alone, as near other geometry
  lopt.sharedFarSpan = 0;
  runtime::TransportData own, data;
  std::vector<uint32_t> pointOf;
  ASSERT_TRUE(gatherAndLink(box, clusters, lopt, own, &pointOf, far).isOk());
  lopt.sharedFarSpan = 4;
  ASSERT_TRUE(gatherAndLink(box, clusters, lopt, data, nullptr, far).isOk());
  ASSERT_EQ(own.sharedFar.rows(), 0u);
  ASSERT_GT(data.sharedFar.rows(), 0u);
  EXPECT_LT(double(data.linkCount()), 0.9 * double(own.linkCount()));
  const uint32_t base = data.sharedFarBase();
  ASSERT_EQ(data.linkTargetCount(), base + data.sharedFar.rows());
  for (uint32_t s = 0; s < data.sharedFar.rows(); ++s) {
    if (data.sharedFar.rowStart[s] == data.sharedFar.rowStart[s + 1]) continue;
    EXPECT_NEAR(rowSum(data.sharedFar, s), 1.0f, 1e-5f) << "shared far field " << s;
    for (uint32_t k = data.sharedFar.rowStart[s]; k < data.sharedFar.rowStart[s + 1]; ++k)
      EXPECT_LT(data.sharedFar.targetAt(k), base);  // no shared field of shared fields
  }
  // Every far cluster of this box holds several clusters (none stands in for a single one,
  // whose hits would merge with the near ones), so the own rows' far links are exactly their
  // links to far clusters.
  size_t frontFar = 0;
  for (uint32_t f = 0; f < far[0].size(); ++f)
    frontFar += !far[0].back[f] && far[0].firstTexel[f] < far[0].firstTexel[f + 1];
  ASSERT_EQ(own.farClusters.rows(), frontFar);
  for (uint32_t s = 0; s < data.sharedFar.rows(); ++s) {
    for (uint32_t k = data.sharedFar.rowStart[s]; k < data.sharedFar.rowStart[s + 1]; ++k)
      EXPECT_GE(data.sharedFar.targetAt(k), data.clusterCount);  // far clusters only
  }
  size_t sharing = 0;
  for (uint32_t p = 0; p < data.gatherPointCount; ++p) {
    double ownFar = 0.0, linked = 0.0;
    for (uint32_t k = own.links.rowStart[p]; k < own.links.rowStart[p + 1]; ++k)
      if (own.links.targetAt(k) >= own.clusterCount) ownFar += own.links.weightAt(p, k);
    for (uint32_t k = data.links.rowStart[p]; k < data.links.rowStart[p + 1]; ++k)
      if (data.links.targetAt(k) >= base) linked += data.links.weightAt(p, k), ++sharing;
    if (linked == 0.0) continue;
    EXPECT_NEAR(linked, ownFar, 2e-3 * ownFar + 1e-6) << "point " << p;
    EXPECT_NEAR(rowSum(data.links, p), rowSum(own.links, p), 1e-4f) << "point " << p;
  }
  EXPECT_GT(sharing, size_t(data.gatherPointCount) / 2);

  expectLinkedFurnace(box, clusters, data);
}

// The Cornell box's ceiling light seen from a floor point: the explicit area-light
// sampling against a brute-force quadrature of (1/π) ∫ cosθ cosθ' V / r² dA over the lamp.
TEST(BakerTransport, CornellLampOnTheFloorMatchesQuadrature) {
  Scene scene = scenes::makeCornellBox();
  uv::UnwrapOptions uopt;
  uopt.pack.texelsPerUnit = 48.0f;
  ASSERT_TRUE(uv::unwrap(scene, uopt).isOk());
  auto built = trace::RayTracer::build(scene);
  ASSERT_TRUE(built.isOk()) << built.message();
  const trace::RayTracer& tracer = *built.value();
  Result<TexelSet> texelResult = computeTexels(scene, tracer);
  ASSERT_TRUE(texelResult.isOk()) << texelResult.message();
  TexelSet texels = std::move(texelResult.value());
  const Clusters clusters = computeClusters(scene, &tracer, texels);
  runtime::TransportData data;
  ASSERT_TRUE(gatherAndLink(scene, tracer, texels, clusters, {}, data).isOk());
  DirectOptions dopt;
  dopt.emissiveSamples = 256;
  ASSERT_TRUE(computeDirect(scene, tracer, texels, clusters, dopt, data).isOk());
  ASSERT_EQ(data.sources.size(), 1u);
  const runtime::Source& lamp = data.sources[0];
  ASSERT_EQ(lamp.kind, runtime::SourceKind::Emissive);

  // The lamp's world triangles and a floor texel.
  std::vector<glm::vec3> tri;
  uint32_t floorInstance = ~0u;
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    const scenes::Instance& inst = scene.instances[i];
    if (inst.name == "floor") floorInstance = i;
    if (inst.name != "light") continue;
    scenes::forEachWorldTriangle(scene, inst, [&](size_t, size_t, glm::vec3 a, glm::vec3 b,
                                                  glm::vec3 c) { tri.insert(tri.end(), {a, b, c}); });
  }
  ASSERT_FALSE(tri.empty());
  ASSERT_NE(floorInstance, ~0u);
  uint32_t best = runtime::kNoTexel;
  float bestDist = 1e30f;
  for (uint32_t t = 0; t < texels.size(); ++t) {
    if (texels.instance[t] != floorInstance || !texels.valid[t]) continue;
    // Towards the back left corner the blocks hide none of the lamp (no penumbra noise).
    const glm::vec2 d(texels.position[t].x - 0.15f, texels.position[t].z - 0.45f);
    if (glm::dot(d, d) < bestDist) bestDist = glm::dot(d, d), best = t;
  }
  ASSERT_NE(best, runtime::kNoTexel);
  const glm::vec3 p = texels.position[best], n = texels.normal[best];
  double expected = 0.0;
  const int grid = 64;
  for (size_t k = 0; k + 2 < tri.size(); k += 3) {
    const glm::vec3 e1 = tri[k + 1] - tri[k], e2 = tri[k + 2] - tri[k];
    const glm::vec3 nl = glm::normalize(glm::cross(e1, e2));
    const float area = 0.5f * glm::length(glm::cross(e1, e2));
    double sum = 0.0;
    int count = 0;
    for (int i = 0; i < grid; ++i)
      for (int j = 0; j < grid; ++j) {
        const float u = (i + 0.5f) / grid, v = (j + 0.5f) / grid;
        if (u + v > 1.0f) continue;
        ++count;
        const glm::vec3 w = tri[k] + u * e1 + v * e2 - p;
        const float r2 = glm::dot(w, w);
        const glm::vec3 d = w / std::sqrt(r2);
        // Visibility too, so the check does not hinge on where exactly the blocks stand.
        trace::Ray ray;
        ray.origin = p;
        ray.direction = d;
        ray.tfar = 0.999f * std::sqrt(r2);
        if (tracer.occluded(ray)) continue;
        sum += std::max(0.0f, glm::dot(n, d)) * std::max(0.0f, -glm::dot(nl, d)) / r2;
      }
    expected += sum / count * area / kPi;
  }
  EXPECT_GT(expected, 0.01);
  EXPECT_NEAR(lamp.texelTransfer[best], expected, 0.03 * expected);
  // Through the solver: E/π = Le × transfer for direct light, plus bounced light on top.
  runtime::Solver solver(data);
  solver.solve();
  std::vector<glm::vec3> out;
  solver.gatherTexels(out);
  const glm::vec3 le = data.materials[lamp.material].emission;
  EXPECT_NEAR(le.x, 17.0f, 1e-4f);
  EXPECT_GT(out[best].x, le.x * lamp.texelTransfer[best]);
  EXPECT_LT(out[best].x, 2.0f * le.x * lamp.texelTransfer[best]);  // near the walls: ~50% bounce
}

TEST(BakerTransport, DirectionalLightStraightDownGivesIntensityOverPi) {
  Builder b;
  b.scene.materials.push_back(material("grey", glm::vec3(0.5f)));
  b.addQuad({-1, 0, -1}, {0, 0, 2}, {2, 0, 0}, 4, 2, 0);
  b.finish();
  scenes::Light sun;
  sun.name = "sun";
  sun.type = scenes::LightType::Directional;
  sun.direction = {0, -1, 0};
  sun.intensity = 5.0f;
  b.scene.lights.push_back(sun);
  auto tracer = b.tracer();
  ASSERT_TRUE(tracer);
  runtime::TransportData data;
  ASSERT_TRUE(gatherAndLink(b.scene, *tracer, b.texels, b.clusters, {}, data).isOk());
  ASSERT_TRUE(computeDirect(b.scene, *tracer, b.texels, b.clusters, {}, data).isOk());
  ASSERT_EQ(data.sources.size(), 1u);
  for (float v : data.sources[0].texelTransfer) EXPECT_NEAR(v, 1.0f / kPi, 1e-6f);
  for (float v : data.sources[0].clusterTransfer) EXPECT_NEAR(v, 1.0f / kPi, 1e-6f);
  runtime::Solver solver(data);
  solver.solve();
  std::vector<glm::vec3> out;
  solver.gatherTexels(out);
  for (const glm::vec3& v : out) EXPECT_NEAR(v.y, 5.0f / kPi, 1e-5f);
}

// A point light 1 m above a 4 m floor of 0.1 m texels, with an optional 0.4 m blocker halfway.
struct PointLightScene {
  Builder b;
  std::unique_ptr<trace::RayTracer> tracer;
  uint32_t below = 0, edge = 0;  // the texel under the light and one on the shadow's edge
  glm::vec3 light{2.05f, 1.0f, 2.05f};

  PointLightScene(bool blocker, float radius) {
    b.scene.materials.push_back(material("grey", glm::vec3(0.5f)));
    b.addQuad({0, 0, 0}, {0, 0, 4}, {4, 0, 0}, 40, 10, 0);
    if (blocker) b.addQuad({1.85f, 0.5f, 1.85f}, {0.4f, 0, 0}, {0, 0, 0.4f}, 0, 1, 0);
    b.finish();
    scenes::Light l;
    l.name = "bulb";
    l.type = scenes::LightType::Point;
    l.position = light;
    l.radius = radius;
    b.scene.lights.push_back(l);
    tracer = b.tracer();
    // Texel (i, j) sits at z = 0.05 + 0.1 i, x = 0.05 + 0.1 j (e1 = +Z, e2 = +X).
    below = 20 * 40 + 20;
    edge = 24 * 40 + 20;  // x = 2.45: the blocker's shadow edge (2.05 + 2 × 0.2)
  }
  float unshadowed(uint32_t t) const {
    const glm::vec3 d = light - b.texels.position[t];
    const float dist = glm::length(d);
    return glm::dot(glm::normalize(d), glm::vec3(0, 1, 0)) / (dist * dist) / kPi;
  }
};

TEST(BakerTransport, PointLightInverseSquareHardShadowAndPenumbra) {
  {
    PointLightScene s(false, 0.0f);
    ASSERT_TRUE(s.tracer);
    runtime::TransportData data;
    ASSERT_TRUE(computeDirect(s.b.scene, *s.tracer, s.b.texels, s.b.clusters, {}, data).isOk());
    const std::vector<float>& tr = data.sources[0].texelTransfer;
    EXPECT_NEAR(s.b.texels.position[s.below].x, 2.05f, 1e-5f);
    EXPECT_NEAR(s.b.texels.position[s.edge].x, 2.45f, 1e-5f);
    // I / h² / π directly below (h measured from the offset sample point).
    const float h = 1.0f - s.b.texels.position[s.below].y;
    EXPECT_NEAR(tr[s.below], 1.0f / (h * h) / kPi, 1e-6f);
    for (uint32_t t = 0; t < s.b.texels.size(); t += 37)
      EXPECT_NEAR(tr[t], s.unshadowed(t), 1e-6f) << t;
  }
  {
    PointLightScene s(true, 0.0f);
    ASSERT_TRUE(s.tracer);
    runtime::TransportData data;
    ASSERT_TRUE(computeDirect(s.b.scene, *s.tracer, s.b.texels, s.b.clusters, {}, data).isOk());
    EXPECT_EQ(data.sources[0].texelTransfer[s.below], 0.0f);
    EXPECT_NEAR(data.sources[0].texelTransfer[s.edge + 40], s.unshadowed(s.edge + 40), 1e-6f);
  }
  {
    PointLightScene s(true, 0.1f);
    ASSERT_TRUE(s.tracer);
    DirectOptions opt;
    opt.lightSamples = 64;
    runtime::TransportData data;
    ASSERT_TRUE(computeDirect(s.b.scene, *s.tracer, s.b.texels, s.b.clusters, opt, data).isOk());
    const std::vector<float>& tr = data.sources[0].texelTransfer;
    EXPECT_EQ(tr[s.below], 0.0f);  // umbra: the blocker hides the whole bulb
    const float full = s.unshadowed(s.edge);
    EXPECT_GT(tr[s.edge], 0.2f * full);
    EXPECT_LT(tr[s.edge], 0.8f * full);
    EXPECT_NEAR(tr[s.edge + 3 * 40], s.unshadowed(s.edge + 3 * 40), 1e-6f);  // fully lit
  }
}

TEST(BakerTransport, SpotConeAndRangeFollowGltf) {
  Builder b;
  b.scene.materials.push_back(material("grey", glm::vec3(0.5f)));
  b.addQuad({0, 0, 0}, {0, 0, 4}, {4, 0, 0}, 40, 10, 0);
  b.finish();
  scenes::Light spot;
  spot.type = scenes::LightType::Spot;
  spot.position = {2.05f, 1.0f, 2.05f};
  spot.direction = {0, -1, 0};
  spot.innerConeAngle = 0.2f;
  spot.outerConeAngle = 0.6f;
  spot.range = 3.0f;
  b.scene.lights.push_back(spot);
  auto tracer = b.tracer();
  ASSERT_TRUE(tracer);
  runtime::TransportData data;
  ASSERT_TRUE(computeDirect(b.scene, *tracer, b.texels, b.clusters, {}, data).isOk());
  const std::vector<float>& tr = data.sources[0].texelTransfer;
  for (uint32_t t = 0; t < b.texels.size(); ++t) {
    const glm::vec3 d = spot.position - b.texels.position[t];
    const float dist = glm::length(d);
    const float angle = std::acos(std::min(1.0f, d.y / dist));
    const float x = dist / spot.range;
    const float window = std::pow(std::max(0.0f, 1.0f - x * x * x * x), 2.0f);
    const float a = std::clamp((std::cos(angle) - std::cos(0.6f)) /
                                   (std::cos(0.2f) - std::cos(0.6f)), 0.0f, 1.0f);
    const float expected = (d.y / dist) * window * a * a / (dist * dist) / kPi;
    ASSERT_NEAR(tr[t], expected, 1e-5f) << t;
    if (angle > 0.61f) {
      ASSERT_EQ(tr[t], 0.0f);
    }
  }
}

// Floor and wall lit by one point light: doubling the intensity doubles every solved texel,
// bounced light included.
TEST(BakerTransport, SolvedTexelsAreLinearInLightIntensity) {
  Builder b;
  b.scene.materials.push_back(material("grey", glm::vec3(0.7f)));
  b.addQuad({0, 0, 0}, {0, 0, 2}, {2, 0, 0}, 8, 4, 0);  // floor, +Y
  b.addQuad({0, 0, 0}, {0, 2, 0}, {0, 0, 2}, 8, 4, 0);  // wall at x = 0, +X
  b.finish();
  scenes::Light l;
  l.type = scenes::LightType::Point;
  l.position = {1.0f, 0.2f, 1.0f};
  l.intensity = 3.0f;
  b.scene.lights.push_back(l);
  auto tracer = b.tracer();
  ASSERT_TRUE(tracer);
  LinkOptions lopt;
  lopt.texelRays = 64;
  runtime::TransportData data;
  ASSERT_TRUE(gatherAndLink(b.scene, *tracer, b.texels, b.clusters, lopt, data).isOk());
  ASSERT_TRUE(computeDirect(b.scene, *tracer, b.texels, b.clusters, {}, data).isOk());
  auto solve = [&]() {
    runtime::Solver solver(data);
    runtime::SolveOptions sopt;
    sopt.tolerance = 1e-7f;
    solver.solve(sopt);
    std::vector<glm::vec3> out;
    solver.gatherTexels(out);
    return out;
  };
  const std::vector<glm::vec3> once = solve();
  data.sources[0].intensity *= 2.0f;
  const std::vector<glm::vec3> twice = solve();
  float indirect = 0.0f;
  for (uint32_t t = 0; t < data.texelCount; ++t) {
    EXPECT_NEAR(twice[t].x, 2.0f * once[t].x, 1e-5f * std::max(1.0f, once[t].x)) << t;
    indirect += once[t].x - 3.0f * data.sources[0].texelTransfer[t];
  }
  EXPECT_GT(indirect, 0.0f);  // the wall and floor light each other
}

}  // namespace
}  // namespace afterglow::baker
