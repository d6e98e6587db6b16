// UV metrics on hand-made scenes with exact answers, and the atlas pictures.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "afterglow/uv/atlas_image.h"
#include "afterglow/uv/metrics.h"
#include "test_util.h"

namespace afterglow::uv {
namespace {

using scenes::Scene;

// A scene with one instance in one atlas of size x size texels; charts are added as quads.
struct Builder {
  Scene scene;
  int size;
  explicit Builder(int atlasSize = 16) : size(atlasSize) {
    scene.meshes.emplace_back();
    scene.meshes[0].primitives.emplace_back();
    scenes::Instance inst;
    inst.mesh = 0;
    inst.lightmap = {0, size, size};
    scene.instances.push_back(inst);
  }
  scenes::Primitive& prim() { return scene.meshes[0].primitives[0]; }
  uint32_t vertex(glm::vec3 pos, glm::vec2 texel) {
    prim().positions.push_back(pos);
    prim().normals.push_back(glm::vec3(0, 0, 1));
    prim().uv1.push_back(texel / float(size));
    return uint32_t(prim().positions.size() - 1);
  }
  void triangle(uint32_t a, uint32_t b, uint32_t c) { prim().indices.insert(prim().indices.end(), {a, b, c}); }
  // A quad whose world position is its texel position / 16 m (16 texels per metre), in z = 0.
  void quad(glm::vec2 lo, glm::vec2 hi) {
    auto v = [&](float x, float y) { return vertex(glm::vec3(x / 16, y / 16, 0), glm::vec2(x, y)); };
    const uint32_t a = v(lo.x, lo.y), b = v(hi.x, lo.y), c = v(hi.x, hi.y), d = v(lo.x, hi.y);
    triangle(a, b, c);
    triangle(a, c, d);
  }
};

TEST(UvMetrics, QuadCoverageIsExact) {
  Builder b;
  b.quad({1.5f, 1.5f}, {4.5f, 3.5f});  // columns 1..4, rows 1..3: 12 texels
  b.quad({6, 6}, {9, 8});              // texel-aligned: columns 6..8, rows 6..7: 6 texels
  const Metrics m = computeMetrics(b.scene, 2);
  EXPECT_EQ(m.chartCount, 2u);
  EXPECT_EQ(m.triangleCount, 4u);
  ASSERT_EQ(m.atlases.size(), 1u);
  EXPECT_EQ(m.atlases[0].coveredTexels, 18u);
  EXPECT_DOUBLE_EQ(m.atlases[0].utilization, 18.0 / 256.0);
  EXPECT_DOUBLE_EQ(m.utilization, 18.0 / 256.0);
  EXPECT_EQ(m.overlappingTexels, 0u);
  // Chebyshev gap between the footprints is 2 empty texels: fine for padding 2...
  EXPECT_EQ(m.paddingViolations, 0u);
  // ...but for padding 3, texels (3,3), (4,3) of one and (6,6), (7,6) of the other are too close.
  EXPECT_EQ(computeMetrics(b.scene, 3).paddingViolations, 4u);
  EXPECT_EQ(m.outOfRangeTriangles, 0u);
  EXPECT_EQ(m.flippedTriangles, 0u);
}

TEST(UvMetrics, OverlappingChartsCountSharedTexels) {
  Builder b;
  b.quad({1, 1}, {5, 5});
  b.quad({3, 3}, {7, 7});  // shares [3,5]^2: 4 texels
  const Metrics m = computeMetrics(b.scene, 0);
  EXPECT_EQ(m.chartCount, 2u);
  EXPECT_EQ(m.atlases[0].coveredTexels, 28u);
  EXPECT_EQ(m.overlappingTexels, 4u);
  EXPECT_GT(m.paddingViolations, 0u);
}

TEST(UvMetrics, ChartsOneTexelApartViolatePaddingTwo) {
  Builder b;
  b.quad({1, 1}, {4, 4});
  b.quad({5, 1}, {8, 4});  // column 4 is the only empty one between them
  // Column 3 of one and column 5 of the other, 3 rows each, are within 2 of the other chart.
  EXPECT_EQ(computeMetrics(b.scene, 2).paddingViolations, 6u);
  EXPECT_EQ(computeMetrics(b.scene, 1).paddingViolations, 0u);
  EXPECT_EQ(computeMetrics(b.scene, 2).overlappingTexels, 0u);
}

TEST(UvMetrics, SharedEdgesAndWeldedSeamsStayOneChart) {
  Builder b;
  // Two triangles of one quad with their own vertices (a normal seam): same uv1 and position.
  auto v = [&](float x, float y) { return b.vertex(glm::vec3(x, y, 0), glm::vec2(x, y)); };
  b.triangle(v(1, 1), v(5, 1), v(5, 5));
  b.triangle(v(1, 1), v(5, 5), v(1, 5));
  // Same uv1 but another position: a different (overlapping) chart.
  b.triangle(b.vertex(glm::vec3(9, 9, 1), glm::vec2(1, 1)), b.vertex(glm::vec3(9, 9, 2), glm::vec2(2, 1)),
             b.vertex(glm::vec3(9, 10, 2), glm::vec2(2, 2)));
  const Metrics m = computeMetrics(b.scene, 2);
  EXPECT_EQ(m.chartCount, 2u);
  EXPECT_EQ(m.overlappingTexels, 1u);  // texel (1,1)
}

TEST(UvMetrics, FlippedTriangleAgainstItsChartIsCounted) {
  Builder b;
  auto v = [&](float x, float y) { return b.vertex(glm::vec3(x, y, 0), glm::vec2(x, y)); };
  // Chart 1: area +8 and a folded triangle of area -4 sharing vertices a and c.
  const uint32_t a = v(0, 0), c = v(4, 4);
  b.triangle(a, v(4, 0), c);
  b.triangle(a, c, v(3, 1));
  // Chart 2: wound clockwise throughout, which is consistent, so not flipped.
  const uint32_t e = v(8, 8), g = v(12, 12);
  b.triangle(e, g, v(12, 8));
  b.triangle(e, v(8, 12), g);
  // Chart 3: a zero-area UV triangle is not flipped.
  b.triangle(v(14, 1), v(15, 2), v(15.5f, 2.5f));
  const Metrics m = computeMetrics(b.scene, 0);
  EXPECT_EQ(m.chartCount, 3u);
  EXPECT_EQ(m.flippedTriangles, 1u);
}

TEST(UvMetrics, IsometricMapHasUnitStretchAndExactDensity) {
  Builder b(64);
  // 2 m x 1 m wall in the xz plane at 16 texels per metre, and a second chart at 8 texels per
  // metre on an instance with lightmapScale 0.5: both have density 16 per unit scale.
  auto v = [&](glm::vec3 p, glm::vec2 t) { return b.vertex(p, t); };
  b.triangle(v({0, 0, 0}, {1, 1}), v({2, 0, 0}, {33, 1}), v({2, 0, 1}, {33, 17}));
  b.triangle(v({0, 0, 0}, {1, 1}), v({2, 0, 1}, {33, 17}), v({0, 0, 1}, {1, 17}));
  b.scene.meshes.push_back(b.scene.meshes[0]);
  scenes::Instance half = b.scene.instances[0];
  half.mesh = 1;
  half.lightmapScale = 0.5f;
  half.lightmap = {1, 64, 64};
  for (glm::vec2& uv : b.scene.meshes[1].primitives[0].uv1) uv = glm::vec2(1.0f / 64) + (uv - glm::vec2(1.0f / 64)) * 0.5f;
  b.scene.instances.push_back(half);
  const Metrics m = computeMetrics(b.scene, 2);
  EXPECT_EQ(m.chartCount, 2u);
  EXPECT_NEAR(m.stretchL2, 1.0, 1e-6);
  EXPECT_NEAR(m.stretchL2Max, 1.0, 1e-6);
  EXPECT_NEAR(m.densityMin, 16.0, 1e-4);
  EXPECT_NEAR(m.densityMax, 16.0, 1e-4);
  EXPECT_NEAR(m.densitySpread, 0.0, 1e-6);
  ASSERT_EQ(m.atlases.size(), 2u);
  EXPECT_EQ(m.atlases[0].coveredTexels, 32u * 16u);
  EXPECT_EQ(m.atlases[1].coveredTexels, 16u * 8u);
}

TEST(UvMetrics, AnisotropicMapHasAnalyticStretch) {
  // A 1 m square mapped to 2k x k texels. Scaled to equal area the map is (sqrt2 x, y / sqrt2);
  // world per texel is 1/sqrt2 along s and sqrt2 along t: L2 = sqrt((1/2 + 2) / 2) = sqrt(1.25).
  Builder b(64);
  auto v = [&](glm::vec3 p, glm::vec2 t) { return b.vertex(p, t); };
  const uint32_t a = v({0, 0, 0}, {2, 2}), c = v({1, 1, 0}, {42, 22});
  b.triangle(a, v({1, 0, 0}, {42, 2}), c);
  b.triangle(a, c, v({0, 1, 0}, {2, 22}));
  const Metrics m = computeMetrics(b.scene, 2);
  EXPECT_NEAR(m.stretchL2, std::sqrt(1.25), 1e-6);
  EXPECT_NEAR(m.stretchL2Max, std::sqrt(1.25), 1e-6);
  // Density: sqrt(800 texels² / 1 m²).
  EXPECT_NEAR(m.densityMin, std::sqrt(800.0), 1e-4);
}

TEST(UvMetrics, OutOfRangeAndMissingUvsAreCounted) {
  Builder b;
  auto v = [&](float x, float y) { return b.vertex(glm::vec3(x, y, 0), glm::vec2(x, y)); };
  b.triangle(v(1, 1), v(5, 1), v(5, 5));
  b.triangle(v(10, 10), v(17, 10), v(10, 12));  // x = 17 of 16 texels: out of range
  b.triangle(v(3, -0.5f), v(5, 0.5f), v(3, 0.5f));  // below 0
  // A second primitive without uv1 on the lightmapped instance.
  scenes::Primitive bare;
  bare.positions = {glm::vec3(0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0)};
  bare.normals.assign(3, glm::vec3(0, 0, 1));
  bare.indices = {0, 1, 2};
  b.scene.meshes[0].primitives.push_back(bare);
  // An instance without a lightmap is ignored.
  scenes::Instance dynamicInstance = b.scene.instances[0];
  dynamicInstance.lightmap = {};
  b.scene.instances.push_back(dynamicInstance);
  const Metrics m = computeMetrics(b.scene, 2);
  EXPECT_EQ(m.triangleCount, 4u);
  EXPECT_EQ(m.outOfRangeTriangles, 3u);
}

TEST(UvMetrics, JsonCarriesEveryField) {
  Builder b;
  b.quad({1, 1}, {5, 5});
  b.quad({3, 3}, {7, 7});
  const Metrics m = computeMetrics(b.scene, 2);
  const nlohmann::json j = nlohmann::json::parse(metricsToJson(m));
  EXPECT_EQ(j.at("chartCount").get<size_t>(), 2u);
  EXPECT_EQ(j.at("overlappingTexels").get<size_t>(), 4u);
  EXPECT_EQ(j.at("paddingViolations").get<size_t>(), m.paddingViolations);
  EXPECT_DOUBLE_EQ(j.at("utilization").get<double>(), m.utilization);
  EXPECT_DOUBLE_EQ(j.at("stretchL2").get<double>(), m.stretchL2);
  ASSERT_EQ(j.at("atlases").size(), 1u);
  EXPECT_EQ(j.at("atlases")[0].at("width").get<int>(), 16);
  EXPECT_EQ(j.at("atlases")[0].at("coveredTexels").get<size_t>(), 28u);
  for (const char* key : {"triangleCount", "outOfRangeTriangles", "flippedTriangles",
                          "stretchL2Max", "densityMinTexelsPerMetre", "densityMaxTexelsPerMetre",
                          "densitySpread"})
    EXPECT_TRUE(j.contains(key)) << key;
}

TEST(UvAtlasImage, PicturesShowChartsOutlinesAndOverlaps) {
  Builder b;
  b.quad({1, 1}, {6, 6});
  b.quad({5, 5}, {9, 9});  // overlaps the first at texel (5,5)
  const std::string dir = test::tempDir("uv_atlas_image");
  AtomicOutput output;
  const auto written = writeAtlasPictures(b.scene, dir + "/atlas", output);
  ASSERT_TRUE(written.isOk()) << written.message();
  ASSERT_TRUE(output.commit().isOk());
  ASSERT_EQ(written->size(), 1u);
  auto in = OIIO::ImageInput::open((*written)[0]);
  ASSERT_TRUE(in);
  const OIIO::ImageSpec spec = in->spec();
  EXPECT_EQ(spec.width, 256);  // 16 texels enlarged 16x
  EXPECT_EQ(spec.height, 256);
  ASSERT_EQ(spec.nchannels, 3);
  std::vector<uint8_t> px(size_t(spec.width) * spec.height * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()));
  auto at = [&](int tx, int ty) {  // centre pixel of a texel
    const size_t i = (size_t(ty * 16 + 8) * spec.width + size_t(tx * 16 + 8)) * 3;
    return glm::ivec3(px[i], px[i + 1], px[i + 2]);
  };
  EXPECT_EQ(at(12, 2), glm::ivec3(40));      // background
  EXPECT_EQ(at(5, 5), glm::ivec3(255));      // overlap
  const glm::ivec3 inner = at(3, 3), outline = at(1, 3);
  EXPECT_NE(inner, glm::ivec3(40));
  EXPECT_LT(outline.x + outline.y + outline.z, inner.x + inner.y + inner.z);  // darker edge
  EXPECT_NE(at(7, 7), inner);                // the other chart has another colour
}

}  // namespace
}  // namespace afterglow::uv
