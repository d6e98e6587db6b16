// The radiosity solver on synthetic transport with analytic answers.
#include <gtest/gtest.h>

#include <cmath>

#include "afterglow/runtime/solver.h"

namespace afterglow::runtime {
namespace {

// A closed "furnace": n clusters that see each other uniformly (rows sum to 1), all emitting Le
// with albedo rho, and texels that see the same. Every texel must read Le / (1 - rho).
TransportData makeFurnace(uint32_t n, float rho, float le) {
  TransportData d;
  d.clusterCount = n;
  d.texelCount = n * 4;
  d.materials.push_back({"wall", glm::vec3(rho), glm::vec3(le)});
  d.clusterMaterial.assign(n, 0);
  d.clusterAlbedoTexture.assign(n, glm::vec3(1.0f));
  d.clusterEmissionTexture.assign(n, glm::vec3(1.0f));
  Source emit;
  emit.name = "wall";
  emit.kind = SourceKind::Emissive;
  emit.material = 0;
  emit.texelTransfer.assign(d.texelCount, 1.0f);   // every texel sees only emitters
  emit.clusterTransfer.assign(n, 1.0f);
  d.sources.push_back(emit);
  auto fill = [n](SparseLinks& links, uint32_t rows) {
    links = SparseLinks();
    std::vector<uint32_t> targets(n);
    std::vector<float> weights(n, 1.0f / float(n));
    for (uint32_t c = 0; c < n; ++c) targets[c] = c;
    for (uint32_t r = 0; r < rows; ++r) links.appendRow(targets.data(), weights.data(), n);
  };
  fill(d.clusterLinks, n);
  fill(d.texelLinks, d.texelCount);
  return d;
}

TEST(RuntimeSolver, WhiteFurnaceConvergesToAnalyticRadiance) {
  for (float rho : {0.5f, 0.9f}) {
    TransportData d = makeFurnace(8, rho, 1.0f);
    Solver solver(d);
    solver.solve({0, 1e-6f});
    std::vector<glm::vec3> texels;
    solver.gatherTexels(texels);
    const float expected = 1.0f / (1.0f - rho);
    for (const glm::vec3& t : texels) EXPECT_NEAR(t.y, expected, expected * 1e-4f) << "rho " << rho;
  }
}

TEST(RuntimeSolver, FixedBounceCountGivesPartialGeometricSeries) {
  const float rho = 0.5f;
  TransportData d = makeFurnace(4, rho, 1.0f);
  Solver solver(d);
  std::vector<glm::vec3> texels;
  solver.gatherTexels(texels);
  EXPECT_NEAR(texels[0].x, 1.0f, 1e-6f);  // no pass yet: emission only
  for (int bounces = 1; bounces <= 4; ++bounces) {
    solver.iterate();
    solver.gatherTexels(texels);
    // After k passes: Le * (1 + rho + ... + rho^k).
    float expected = (1.0f - std::pow(rho, float(bounces + 1))) / (1.0f - rho);
    EXPECT_NEAR(texels[0].x, expected, 1e-5f) << bounces << " bounces";
  }
}

TEST(RuntimeSolver, ConstantSkyOnUnoccludedTexelEqualsSkyRadiance) {
  TransportData d;
  d.texelCount = 1;
  d.texelLinks.appendRow(nullptr, nullptr, 0);  // one texel that sees no cluster
  // Transfer of an unoccluded, upward-facing point: only the DC term matters for a constant sky.
  d.texelSky.assign(kShCount, 0.0f);
  d.texelSky[0] = 1.0f / (2.0f * std::sqrt(3.14159265358979f));
  constantSkySh(glm::vec3(0.3f, 0.6f, 1.2f), d.skySh);
  Solver solver(d);
  std::vector<glm::vec3> texels;
  solver.gatherTexels(texels);
  EXPECT_NEAR(texels[0].x, 0.3f, 1e-6f);
  EXPECT_NEAR(texels[0].z, 1.2f, 1e-6f);
}

}  // namespace
}  // namespace afterglow::runtime
