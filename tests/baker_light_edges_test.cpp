// Far clusters across a change in what light reaches (issue 16): a gather ray's hit links a far
// cluster only when the far cluster's clusters receive each light alike (far_targets.h,
// ClusterLight). On Sponza-sun a wall texel 8 cm behind a drape, whose view of the floor is the
// drape's shadow, read a far cluster half in the sun: its bounced light came out 5x the
// reference's. The scene here is that wall made small, its floor lit and shaded in turn.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "afterglow/baker/bake.h"
#include "bake_fixtures.h"

namespace afterglow::baker {
namespace {

scenes::Scene drapeInTheSun() {
  scenes::Scene scene = groundQuad("floor", 2.0f, 0.8f, 0.0f);
  scenes::Material wall = scene.materials[0];
  wall.name = "wall";
  scene.materials.push_back(wall);
  addBox(scene, "wall", {-0.2f, 0.0f, -2.0f}, {0.0f, 2.5f, 2.0f}, 1);
  addBox(scene, "drape", {0.08f, 0.0f, -2.0f}, {0.09f, 2.3f, 0.0f}, 1);
  // From high up over +x: the floor in front of the wall is in the sun but for the drape's
  // shadow, the floor behind the wall in the wall's for 1.25 m, and in the sun beyond.
  scenes::Light sun;
  sun.name = "sun";
  sun.type = scenes::LightType::Directional;
  sun.direction = glm::normalize(glm::vec3(-0.5f, -1.0f, 0.2f));
  sun.intensity = 3.0f;
  scene.lights.push_back(sun);
  return scene;
}

// Per link target (clusters, then far clusters), whether it is a far cluster whose clusters
// receive the sun's direct light unevenly: the largest more than 1.5× the smallest plus a
// twentieth of the mean over clusters (far_targets.h, ClusterLight, at LinkOptions'
// farLightRatio).
std::vector<uint8_t> unevenFarClusters(const runtime::TransportData& d) {
  const std::vector<float>& sun = d.sources.at(0).clusterTransfer;
  double mean = 0.0;
  for (float v : sun) mean += double(v);
  mean /= double(sun.size());
  std::vector<uint8_t> uneven(d.sharedFarBase(), 0);
  for (size_t f = 0; f < d.farClusters.rows(); ++f) {
    float lo = 1e30f, hi = 0.0f;
    for (uint32_t k = d.farClusters.rowStart[f]; k < d.farClusters.rowStart[f + 1]; ++k) {
      lo = std::min(lo, sun[d.farClusters.column[k]]);
      hi = std::max(hi, sun[d.farClusters.column[k]]);
    }
    uneven[d.clusterCount + f] = hi > 1.5f * lo + float(0.05 * mean) ? 1 : 0;
  }
  return uneven;
}

// Links (of the gather points and back clusters, and of the shared far fields) to such far
// clusters.
size_t linksToUnevenFarClusters(const runtime::TransportData& d) {
  const std::vector<uint8_t> uneven = unevenFarClusters(d);
  size_t count = 0;
  for (const runtime::SparseLinks* links : {&d.links, &d.sharedFar})
    for (size_t k = 0; k < links->size(); ++k) {
      if (runtime::SparseLinks::isPadding(links->link[k], links->targetBits)) continue;
      const uint32_t target = links->targetAt(k);
      count += target < uneven.size() && uneven[target] ? 1 : 0;
    }
  return count;
}

// A far cluster stands in for its clusters' mean light, right for a point that sees all of it
// from afar, wrong for one that sees only its shaded part (a wall texel behind the drape, whose
// view of the floor is the drape's shadow). With the check no link reads a far cluster whose
// clusters the sun lights unevenly; without it, many do (so the scene does test the check).
TEST(BakeLightEdges, NoLinkReadsAFarClusterTheSunLightsUnevenly) {
  scenes::Scene scene = drapeInTheSun();
  unwrapAt(scene, 8.0f);
  BakeOptions options = draftOptions();
  const BakeResult with = bakeOrDie(scene, options);
  options.links.farLightRatio = 0.0f;
  const BakeResult without = bakeOrDie(scene, options);
  ASSERT_FALSE(with.transport.sources.empty());
  ASSERT_GT(with.transport.farClusters.rows(), 0u);
  const size_t withCount = linksToUnevenFarClusters(with.transport);
  const size_t withoutCount = linksToUnevenFarClusters(without.transport);
  std::printf("links to far clusters the sun lights unevenly: %zu with the check, %zu without "
              "(of %zu and %zu links)\n", withCount, withoutCount, with.transport.linkCount(),
              without.transport.linkCount());
  EXPECT_EQ(withCount, 0u);
  EXPECT_GT(withoutCount, 50u);
}

}  // namespace
}  // namespace afterglow::baker
