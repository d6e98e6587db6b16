// The radiosity solver on synthetic transport with analytic answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>
#include <vector>

#include "afterglow/runtime/solver.h"
#include "test_rng.h"

namespace afterglow::runtime {
namespace {

// A closed "furnace": n clusters that see each other uniformly (rows sum to 1), all emitting Le
// with albedo rho, one gather point per cluster and four texels per gather point. Every texel
// must read Le / (1 - rho).
TransportData makeFurnace(uint32_t n, float rho, float le) {
  TransportData d;
  d.clusterCount = n;
  d.gatherPointCount = n;
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
  std::vector<uint32_t> targets(n);
  std::vector<float> weights(n, 1.0f / float(n));
  for (uint32_t c = 0; c < n; ++c) targets[c] = c;
  for (uint32_t r = 0; r < n; ++r) d.links.appendRow(targets.data(), weights.data(), n);
  const float one = 1.0f;
  for (uint32_t c = 0; c < n; ++c) d.clusterGather.appendRow(&c, &one, 1);
  for (uint32_t t = 0; t < d.texelCount; ++t) {
    const uint32_t p = t / 4;
    d.texelGather.appendRow(&p, &one, 1);
  }
  EXPECT_EQ(d.validate(), "");
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
  d.gatherPointCount = 1;
  d.links.appendRow(nullptr, nullptr, 0);  // one gather point that sees no cluster
  const uint32_t point = 0;
  const float one = 1.0f;
  d.texelGather.appendRow(&point, &one, 1);
  // Transfer of an unoccluded, upward-facing point: only the DC term matters for a constant sky.
  const float y00 = 1.0f / (2.0f * std::sqrt(3.14159265358979f));
  d.texelSky.assign(kShCount, floatToHalf(0.0f));
  d.texelSky[0] = floatToHalf(y00);
  ASSERT_EQ(d.validate(), "");
  constantSkySh(glm::vec3(0.3f, 0.6f, 1.2f), d.skySh);
  Solver solver(d);
  std::vector<glm::vec3> texels;
  solver.gatherTexels(texels);
  // The texels' sky transfer is kept in half floats: 2^-11 relative.
  EXPECT_NEAR(texels[0].x, 0.3f, 0.3f / 2048.0f);
  EXPECT_NEAR(texels[0].z, 1.2f, 1.2f / 2048.0f);
}

// Two clusters (materials as given, untextured) lit by one light with the given unit cluster
// transfer, `points` gather points and texels, no links or maps yet: the tests below add the
// few they check by hand.
TransportData twoClusters(uint32_t points, std::vector<MaterialParams> materials,
                          std::vector<uint32_t> clusterMaterial, std::vector<float> clusterLight) {
  TransportData d;
  d.clusterCount = 2;
  d.gatherPointCount = points;
  d.texelCount = points;
  d.materials = std::move(materials);
  d.clusterMaterial = std::move(clusterMaterial);
  d.clusterAlbedoTexture.assign(2, glm::vec3(1.0f));
  d.clusterEmissionTexture.assign(2, glm::vec3(1.0f));
  Source light;
  light.name = "sun";
  light.texelTransfer.assign(points, 0.0f);
  light.clusterTransfer = std::move(clusterLight);
  d.sources.push_back(light);
  return d;
}

// Bounced light reaches texels through the smoothing between gather points and the texels'
// interpolation of them, both linear maps applied as written.
TEST(RuntimeSolver, GatherPointFilterAndTexelGatherApplyTheirWeights) {
  // Only cluster 0 is lit: R = (0.5, 0).
  TransportData d = twoClusters(2,
                                {{"grey", glm::vec3(0.5f), glm::vec3(0.0f)},
                                 {"black", glm::vec3(0.0f), glm::vec3(0.0f)}},
                                {0, 1}, {1.0f, 0.0f});
  const uint32_t c0 = 0, c1 = 1, both[2] = {0, 1};
  const float one = 1.0f, halves[2] = {0.5f, 0.5f}, mix[2] = {0.75f, 0.25f};
  d.links.appendRow(&c0, &one, 1);  // point 0 sees cluster 0, point 1 the black cluster
  d.links.appendRow(&c1, &one, 1);
  d.clusterGather.appendRow(&c1, &one, 1);  // cluster 0 reads point 1: no feedback
  d.clusterGather.appendRow(&c0, &one, 1);
  d.pointFilter.appendRow(both, halves, 2);
  d.pointFilter.appendRow(both, halves, 2);
  d.texelGather.appendRow(&c0, &one, 1);
  d.texelGather.appendRow(both, mix, 2);
  ASSERT_EQ(d.validate(), "");
  for (int passes : {0, 1}) {
    d.filterPasses = passes;
    Solver solver(d);
    solver.solve();
    std::vector<glm::vec3> direct, indirect;
    solver.gatherTexels(direct, indirect);
    // Gathered: V = (0.5, 0); one pass of the filter makes it (0.25, 0.25).
    const float v0 = passes ? 0.25f : 0.5f, v1 = passes ? 0.25f : 0.0f;
    EXPECT_FLOAT_EQ(indirect[0].x, v0) << passes;
    EXPECT_FLOAT_EQ(indirect[1].x, 0.75f * v0 + 0.25f * v1) << passes;
    EXPECT_EQ(direct[0], glm::vec3(0.0f));
  }
}

// A far cluster's reflected light is the weighted mean of its clusters', and a row that links it
// gathers that mean: two lit clusters (R = 0.5 and 0.25) under one far cluster weighted 3:1.
TEST(RuntimeSolver, FarClustersGatherTheirClustersMean) {
  TransportData d =
      twoClusters(1, {{"grey", glm::vec3(0.5f), glm::vec3(0.0f)}}, {0, 0}, {1.0f, 0.5f});
  const uint32_t both[2] = {0, 1}, far = 2, none = 0;
  const float mean[2] = {0.75f, 0.25f}, half = 0.5f, zero = 0.0f, one = 1.0f;
  d.farClusters.appendRow(both, mean, 2);
  d.links.appendRow(&far, &half, 1);           // the point sees the far cluster with F = 0.5
  d.clusterGather.appendRow(&none, &zero, 1);  // the clusters gather nothing back
  d.clusterGather.appendRow(&none, &zero, 1);
  d.texelGather.appendRow(&none, &one, 1);      // the texel reads the point
  ASSERT_EQ(d.linkTargetCount(), 3u);
  ASSERT_EQ(d.validate(), "");
  Solver solver(d);
  solver.solve();
  const float farR = 0.75f * 0.5f + 0.25f * 0.25f;
  EXPECT_NEAR(solver.rowGathered()[0].x, 0.5f * farR, 1e-6f);
  std::vector<glm::vec3> direct, indirect;
  solver.gatherTexels(direct, indirect);
  EXPECT_NEAR(indirect[0].x, 0.5f * farR, 1e-6f);
}

// A shared far field gathers from the far clusters and the clusters, after both are up to
// date, and the rows that link it read its light like a cluster's.
TEST(RuntimeSolver, SharedFarFieldsGatherBeforeTheRowsThatLinkThem) {
  TransportData d =
      twoClusters(2, {{"grey", glm::vec3(0.5f), glm::vec3(0.0f)}}, {0, 0}, {1.0f, 0.5f});
  const uint32_t both[2] = {0, 1}, farAndOne[2] = {1, 2}, shared = 3, sharedAndZero[2] = {0, 3};
  const uint32_t none = 0, first = 0, second = 1;
  const float mean[2] = {0.75f, 0.25f}, split[2] = {0.4f, 0.6f}, half = 0.5f,
              pair[2] = {0.1f, 0.3f}, zero = 0.0f, one = 1.0f;
  d.farClusters.appendRow(both, mean, 2);            // target 2
  d.sharedFar.appendRow(farAndOne, split, 2);        // target 3: 0.4 R_1 + 0.6 R_far
  d.links.appendRow(&shared, &half, 1);              // point 0: half its rays go far
  d.links.appendRow(sharedAndZero, pair, 2);         // point 1: 0.1 R_0 + 0.3 shared
  d.clusterGather.appendRow(&none, &zero, 1);        // the clusters gather nothing back
  d.clusterGather.appendRow(&none, &zero, 1);
  d.texelGather.appendRow(&first, &one, 1);
  d.texelGather.appendRow(&second, &one, 1);
  ASSERT_EQ(d.sharedFarBase(), 3u);
  ASSERT_EQ(d.linkTargetCount(), 4u);
  ASSERT_EQ(d.validate(), "");
  Solver solver(d);
  solver.iterate();  // one pass: every phase reads what the one before it wrote
  const float r0 = 0.5f * 1.0f, r1 = 0.5f * 0.5f;  // albedo × direct
  const float farR = 0.75f * r0 + 0.25f * r1;
  const float sharedR = 0.4f * r1 + 0.6f * farR;
  EXPECT_NEAR(solver.rowGathered()[0].x, 0.5f * sharedR, 1e-6f);
  EXPECT_NEAR(solver.rowGathered()[1].x, 0.1f * r0 + 0.3f * sharedR, 1e-6f);

  // Its rows may not link shared fields: the solver fills them in one pass, in order.
  TransportData bad = d;
  bad.sharedFar = SparseLinks();
  bad.sharedFar.appendRow(&shared, &one, 1);
  EXPECT_NE(bad.validate().find("shared far fields: entry 0 refers to 3 of 3"), std::string::npos)
      << bad.validate();
}

// A row's quantised links keep its exact sum: rounding moves weight between the links, and
// weights too small for a code go to the others, instead of light being made or lost.
TEST(RuntimeSolver, QuantisedRowsKeepTheirSums) {
  test::Rng rng{7};
  for (uint32_t targets : {100u, 1u << 18, 1u << 22}) {
    SparseLinks m(targets);
    std::vector<uint32_t> columns;
    std::vector<float> weights;
    const uint32_t n = std::min(targets, 300u);
    for (uint32_t k = 0; k < n; ++k) {
      columns.push_back(uint32_t(uint64_t(k) * targets / n));  // ascending
      // Mostly tiny weights next to one large one: many round to a code of 0 or 1.
      weights.push_back(k == 0 ? 0.5f : 1e-6f + 1e-4f * rng.unit());
    }
    double sum = 0.0;
    for (float w : weights) sum += double(w);
    m.appendRow(columns.data(), weights.data(), columns.size());
    double kept = 0.0;
    for (size_t k = 0; k < m.size(); ++k) kept += double(m.weightAt(0, k));
    EXPECT_NEAR(kept, sum, 1e-6 * sum) << targets << " targets";
  }
}

// normalisedRows builds its blocks on whatever threads run them: run backwards one block at a
// time, it must give the matrix that appending the rows in order gives, each row summing to 1.
TEST(RuntimeSolver, NormalisedRowsDoNotDependOnHowTheBlocksRun) {
  const size_t rows = 10000;  // a few blocks
  auto fill = [](size_t r, std::vector<std::pair<uint32_t, float>>& entries) {
    test::Rng rng{r + 1};
    const uint32_t n = rng.below(12);  // some rows empty, some with repeated columns
    for (uint32_t k = 0; k < n; ++k) entries.emplace_back(rng.below(50), 0.1f + rng.unit());
  };
  SparseMatrix serial;
  std::vector<std::pair<uint32_t, float>> entries;
  for (size_t r = 0; r < rows; ++r) {
    entries.clear();
    fill(r, entries);
    serial.appendNormalisedRow(entries);
  }
  size_t blocksRun = 0;
  const ParallelFor backwards = [&](size_t count, const std::function<void(size_t, size_t)>& body) {
    for (size_t b = count; b-- > 0;) body(b, b + 1), ++blocksRun;
  };
  const SparseMatrix blocked = normalisedRows(rows, fill, backwards);
  EXPECT_GT(blocksRun, 1u);
  EXPECT_EQ(blocked.rowStart, serial.rowStart);
  EXPECT_EQ(blocked.column, serial.column);
  EXPECT_EQ(blocked.weight, serial.weight);
  for (size_t r = 0; r < blocked.rows(); ++r) {
    if (blocked.rowStart[r] == blocked.rowStart[r + 1]) continue;
    double sum = 0.0;
    for (uint32_t k = blocked.rowStart[r]; k < blocked.rowStart[r + 1]; ++k)
      sum += blocked.weight[k];
    EXPECT_NEAR(sum, 1.0, 1e-6) << "row " << r;
  }
}

TEST(RuntimeSolver, LinkRowsArePaddedToFoursWithWeightlessEntries) {
  // Rows of 0 to 9 links: each stored as a multiple of four entries, the padding weightless
  // and aimed at the row's last target, and the bounce gathers exactly the weighted sum.
  SparseLinks m(64);
  size_t links = 0;
  for (uint32_t n = 0; n < 10; ++n) {
    std::vector<uint32_t> targets;
    std::vector<float> weights;
    for (uint32_t k = 0; k < n; ++k) targets.push_back(3 * k + n), weights.push_back(0.01f * float(k + 1));
    m.appendRow(targets.data(), weights.data(), n);
    links += n;
    const uint32_t begin = m.rowStart[n], end = m.rowStart[n + 1];
    EXPECT_EQ(end - begin, (n + 3) / 4 * 4) << n << " links";
    for (uint32_t k = begin + n; k < end; ++k) {
      EXPECT_TRUE(SparseLinks::isPadding(m.link[k], m.targetBits));
      EXPECT_EQ(m.weightAt(n, k), 0.0f);
      EXPECT_EQ(m.targetAt(k), targets.back());
    }
  }
  EXPECT_EQ(m.linkCount(), links);

  // Through a bounce: row r of a 64-cluster transport whose clusters reflect 1 + c.
  const uint32_t clusters = 64;
  TransportData d;
  d.clusterCount = clusters;
  d.gatherPointCount = uint32_t(m.rows());
  d.texelCount = d.gatherPointCount;
  d.materials.push_back({"grey", glm::vec3(1.0f), glm::vec3(0.0f)});
  d.clusterMaterial.assign(clusters, 0);
  d.clusterAlbedoTexture.assign(clusters, glm::vec3(1.0f));
  d.clusterEmissionTexture.assign(clusters, glm::vec3(1.0f));
  Source light;
  light.name = "light";
  light.texelTransfer.assign(d.texelCount, 0.0f);
  for (uint32_t c = 0; c < clusters; ++c) light.clusterTransfer.push_back(1.0f + float(c));
  d.sources.push_back(light);
  d.links = m;
  const float one = 1.0f;
  for (uint32_t c = 0; c < clusters; ++c) d.clusterGather.appendRow(nullptr, nullptr, 0);
  for (uint32_t t = 0; t < d.texelCount; ++t) d.texelGather.appendRow(&t, &one, 1);
  ASSERT_EQ(d.validate(), "");
  Solver solver(d);
  solver.solve({1, 0.0f});  // one pass: R = direct, then every row gathers it
  std::vector<glm::vec3> direct, indirect;
  solver.gatherTexels(direct, indirect);
  for (uint32_t r = 0; r < m.rows(); ++r) {
    double want = 0.0;
    for (uint32_t k = m.rowStart[r]; k < m.rowStart[r + 1]; ++k)
      want += double(m.weightAt(r, k)) * (1.0 + double(m.targetAt(k)));
    EXPECT_NEAR(indirect[r].x, want, 1e-6 * want + 1e-12) << "row " << r;
  }
}

}  // namespace
}  // namespace afterglow::runtime
