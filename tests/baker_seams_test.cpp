// Seam stitching (baker/src/seams.cpp): a flat plane cut into two charts (built by hand) and a
// cylinder cut by the unwrapper are stitched so bilinear lookups on either side of the cut
// agree; a box's hard edge, the Cornell box and an edge between two objects are left alone;
// the stitched mixes stay linear and keep uniform light uniform.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/trace/raytracer.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/uv/unwrap.h"
#include "post/lightmap_post.h"
#include "post/seams.h"

namespace afterglow::baker {
namespace {

// One atlas holding axis-aligned rectangular charts of world quads, with a texel on every pixel
// whose centre a chart covers (what conservative rasterisation gives for pixel-aligned charts).
class ChartBuilder {
 public:
  ChartBuilder(int width, int height) {
    layout_.width = width;
    layout_.height = height;
    layout_.texelOfPixel.assign(size_t(width) * size_t(height), runtime::kNoTexel);
  }

  // Starts a new static instance (with a mesh of its own) in the atlas.
  void beginInstance() {
    scene_.meshes.emplace_back();
    scene_.meshes.back().primitives.emplace_back();
    scenes::Instance inst;
    inst.mesh = int(scene_.meshes.size()) - 1;
    inst.lightmap = {0, layout_.width, layout_.height};
    scene_.instances.push_back(inst);
  }

  // The world quad corner + s·e1 + t·e2 (s, t in [0, 1]) as the chart origin + s·a1 + t·a2 in
  // atlas pixels (a1, a2 along the atlas axes, any orientation), in the current instance.
  void addQuad(glm::vec3 corner, glm::vec3 e1, glm::vec3 e2, glm::vec2 origin, glm::vec2 a1,
               glm::vec2 a2) {
    scenes::Primitive& prim = scene_.meshes.back().primitives.back();
    const uint32_t base = uint32_t(prim.positions.size());
    const glm::vec3 normal = glm::normalize(glm::cross(e1, e2));
    const glm::vec2 size(layout_.width, layout_.height);
    const glm::vec2 st[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (const glm::vec2& c : st) {
      prim.positions.push_back(corner + c.x * e1 + c.y * e2);
      prim.normals.push_back(normal);
      prim.uv1.push_back((origin + c.x * a1 + c.y * a2) / size);
    }
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) prim.indices.push_back(base + i);

    const glm::mat2 toSt = glm::inverse(glm::mat2(a1, a2));
    for (int y = 0; y < layout_.height; ++y)
      for (int x = 0; x < layout_.width; ++x) {
        const glm::vec2 c = toSt * (glm::vec2(float(x) + 0.5f, float(y) + 0.5f) - origin);
        if (c.x <= 0.0f || c.y <= 0.0f || c.x >= 1.0f || c.y >= 1.0f) continue;
        layout_.texelOfPixel[size_t(y) * size_t(layout_.width) + size_t(x)] = texels_.size();
        texels_.position.push_back(corner + c.x * e1 + c.y * e2);
        texels_.instance.push_back(uint32_t(scene_.instances.size() - 1));
        texels_.valid.push_back(1);
      }
  }

  const scenes::Scene& scene() const { return scene_; }
  const std::vector<glm::vec3>& texelPositions() const { return texels_.position; }

  // The texels with their mixes computed (stitched or not).
  TexelSet post(bool stitch, PostStats* stats = nullptr) const {
    TexelSet texels = texels_;
    texels.atlases = {layout_};
    PostOptions options;
    options.stitchSeams = stitch;
    const PostStats s = computeAtlasMixes(texels, scene_, options);
    if (stats) *stats = s;
    return texels;
  }

 private:
  scenes::Scene scene_;
  TexelSet texels_;
  runtime::AtlasLayout layout_;
};

std::vector<glm::vec3> resolve(const TexelSet& texels, const std::vector<glm::vec3>& values) {
  std::vector<glm::vec3> image;
  runtime::resolveAtlas(texels.atlases[0], values, image);
  return image;
}

// Bilinear between pixel centres, clamped at the edges, as baker/src/render.cpp fetches.
glm::vec3 fetch(const std::vector<glm::vec3>& image, int width, int height, glm::vec2 pixel) {
  const float x = pixel.x - 0.5f, y = pixel.y - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  auto at = [&](int px, int py) {
    px = std::clamp(px, 0, width - 1);
    py = std::clamp(py, 0, height - 1);
    return image[size_t(py) * size_t(width) + size_t(px)];
  };
  const int x0 = int(fx), y0 = int(fy);
  return glm::mix(glm::mix(at(x0, y0), at(x0 + 1, y0), tx),
                  glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), tx), ty);
}

// Mean |difference| of the lookups on the two sides of a seam (atlas pixels), over 200 points.
float seamMismatch(const std::vector<glm::vec3>& image, int width, int height, glm::vec2 a0,
                   glm::vec2 a1, glm::vec2 b0, glm::vec2 b1) {
  constexpr int kPoints = 200;
  float sum = 0.0f;
  for (int i = 0; i < kPoints; ++i) {
    const float t = (float(i) + 0.5f) / float(kPoints);
    sum += std::abs(fetch(image, width, height, glm::mix(a0, a1, t)).x -
                    fetch(image, width, height, glm::mix(b0, b1, t)).x);
  }
  return sum / float(kPoints);
}

// Distance from point p to the segment a–b.
float distanceToSegment(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
  const float t = std::clamp(glm::dot(p - a, b - a) / glm::dot(b - a, b - a), 0.0f, 1.0f);
  return glm::distance(p, a + t * (b - a));
}

// The plane y = 0, x in [0, 2], z in [0, 1], as two quads cut at x = 1: the left one charted
// upright at 12 pixels a metre, the right one turned 90° at 10 pixels a metre (the packer
// rotates charts; LSCM charts differ in scale), so the seam runs down a column on one side and
// along a row on the other.
constexpr int kWidth = 40, kHeight = 20;
const glm::vec2 kLeftEdge0(14, 2), kLeftEdge1(14, 14);    // x = 1, z = 0 → 1 on the left chart
const glm::vec2 kRightEdge0(34, 2), kRightEdge1(24, 2);   // and on the right chart

ChartBuilder cutPlane() {
  ChartBuilder b(kWidth, kHeight);
  b.beginInstance();
  const glm::vec3 e1(1, 0, 0), e2(0, 0, 1);
  b.addQuad({0, 0, 0}, e1, e2, {2, 2}, {12, 0}, {0, 12});
  b.addQuad({1, 0, 0}, e1, e2, {34, 2}, {0, 10}, {-10, 0});
  return b;
}

// Light rising across x and along z, with a step of 0.5 injected across the cut (what two
// charts baked with independent noise or texel placement look like).
std::vector<glm::vec3> rampWithStep(const ChartBuilder& b) {
  std::vector<glm::vec3> values;
  for (const glm::vec3& p : b.texelPositions())
    values.push_back(glm::vec3(1.0f + p.x + 0.3f * p.z + (p.x > 1.0f ? 0.5f : 0.0f)));
  return values;
}

TEST(SeamStitch, CutPlaneAgreesAcrossTheSeam) {
  const ChartBuilder b = cutPlane();
  const std::vector<glm::vec3> values = rampWithStep(b);
  PostStats stats;
  const std::vector<glm::vec3> before = resolve(b.post(false), values);
  const TexelSet stitched = b.post(true, &stats);
  const std::vector<glm::vec3> after = resolve(stitched, values);
  EXPECT_EQ(stats.seamEdges, 1u);  // the cut; the quads' diagonals are not cut
  EXPECT_GT(stats.stitchedPixels, 0u);
  EXPECT_LE(stats.stitchedEntries, stats.stitchedPixels * PostOptions().stitchMaxMix);

  const float mismatchBefore =
      seamMismatch(before, kWidth, kHeight, kLeftEdge0, kLeftEdge1, kRightEdge0, kRightEdge1);
  const float mismatchAfter =
      seamMismatch(after, kWidth, kHeight, kLeftEdge0, kLeftEdge1, kRightEdge0, kRightEdge1);
  RecordProperty("mismatchBefore", std::to_string(mismatchBefore));
  RecordProperty("mismatchAfter", std::to_string(mismatchAfter));
  EXPECT_GT(mismatchBefore, 0.4f);
  EXPECT_LT(mismatchAfter * 5.0f, mismatchBefore)
      << "before " << mismatchBefore << ", after " << mismatchAfter;

  // Only pixels a seam lookup reads change; the rest stay bit-identical.
  size_t changed = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const size_t p = size_t(y) * size_t(kWidth) + size_t(x);
      const glm::vec2 centre(float(x) + 0.5f, float(y) + 0.5f);
      const float distance = std::min(distanceToSegment(centre, kLeftEdge0, kLeftEdge1),
                                      distanceToSegment(centre, kRightEdge0, kRightEdge1));
      if (before[p] == after[p]) continue;
      ++changed;
      EXPECT_LT(distance, 1.5f) << "pixel " << x << "," << y;
    }
  EXPECT_GT(changed, 0u);
}

TEST(SeamStitch, MixesStayLinearAndKeepConstantLight) {
  const ChartBuilder b = cutPlane();
  const TexelSet stitched = b.post(true);
  const std::vector<glm::vec3> values = rampWithStep(b);
  std::vector<glm::vec3> doubled = values;
  for (glm::vec3& v : doubled) v *= 2.0f;
  const std::vector<glm::vec3> image = resolve(stitched, values), twice = resolve(stitched, doubled);
  for (size_t p = 0; p < image.size(); ++p) EXPECT_FLOAT_EQ(twice[p].x, 2.0f * image[p].x);

  // Weights still sum to one: uniform light stays uniform wherever a pixel is baked or mixed.
  const std::vector<glm::vec3> ones(values.size(), glm::vec3(1.0f));
  const std::vector<glm::vec3> flat = resolve(stitched, ones);
  const std::vector<glm::vec3> reference = resolve(b.post(false), ones);
  for (size_t p = 0; p < flat.size(); ++p) EXPECT_NEAR(flat[p].x, reference[p].x, 1e-5f);
}

void expectSameMixes(const TexelSet& a, const TexelSet& b) {
  EXPECT_EQ(a.atlases[0].mixPixel, b.atlases[0].mixPixel);
  EXPECT_EQ(a.atlases[0].mixStart, b.atlases[0].mixStart);
  EXPECT_EQ(a.atlases[0].mixTexel, b.atlases[0].mixTexel);
  EXPECT_EQ(a.atlases[0].mixWeight, b.atlases[0].mixWeight);
}

// Seams are found in parallel over instances and solved in sorted order: the mixes are the
// same bits whatever the thread count.
TEST(SeamStitch, IsDeterministic) {
  ChartBuilder b = cutPlane();
  b.beginInstance();  // a second instance, so the search has more than one item to spread
  b.addQuad({0, 0, 2}, {1, 0, 0}, {0, 0, 1}, {36, 14}, {3, 0}, {0, 3});
  setThreadCount(1);
  const TexelSet one = b.post(true);
  setThreadCount(2);
  const TexelSet two = b.post(true);
  setThreadCount(0);
  expectSameMixes(one, two);
}

// A box's floor and wall meet at 90°: separate charts lit differently on purpose.
TEST(SeamStitch, HardEdgeIsLeftAlone) {
  ChartBuilder b(kWidth, kHeight);
  b.beginInstance();
  b.addQuad({0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {2, 2}, {12, 0}, {0, 12});  // floor, x in [0, 1]
  b.addQuad({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {22, 2}, {12, 0}, {0, 12});  // wall at x = 1
  PostStats stats;
  const TexelSet stitched = b.post(true, &stats);
  EXPECT_EQ(stats.seamEdges, 0u);
  EXPECT_EQ(stats.stitchedPixels, 0u);
  expectSameMixes(stitched, b.post(false));
}

// Two objects that happen to touch (a rug on a floor, tiles) are not one surface.
TEST(SeamStitch, EdgesBetweenInstancesAreLeftAlone) {
  ChartBuilder b(kWidth, kHeight);
  const glm::vec3 e1(1, 0, 0), e2(0, 0, 1);
  b.beginInstance();
  b.addQuad({0, 0, 0}, e1, e2, {2, 2}, {12, 0}, {0, 12});
  b.beginInstance();
  b.addQuad({1, 0, 0}, e1, e2, {22, 2}, {12, 0}, {0, 12});
  PostStats stats;
  const TexelSet stitched = b.post(true, &stats);
  EXPECT_EQ(stats.seamEdges, 0u);
  expectSameMixes(stitched, b.post(false));
}

// An open cylinder (radius 0.5 m, height 1 m) with smooth normals and shared vertices: the
// unwrapper has to cut it somewhere along its side.
scenes::Scene cylinderScene(int segments) {
  scenes::Primitive prim;
  for (int ring = 0; ring <= 1; ++ring)
    for (int i = 0; i < segments; ++i) {
      const float a = 2.0f * 3.14159265f * float(i) / float(segments);
      prim.positions.push_back({0.5f * std::cos(a), float(ring), 0.5f * std::sin(a)});
      prim.normals.push_back({std::cos(a), 0.0f, std::sin(a)});
    }
  for (uint32_t i = 0; i < uint32_t(segments); ++i) {
    const uint32_t j = (i + 1) % uint32_t(segments), n = uint32_t(segments);
    for (uint32_t v : {i, i + n, j, j, i + n, j + n}) prim.indices.push_back(v);
  }
  scenes::Scene scene;
  scene.meshes.push_back({"cylinder", {prim}});
  scenes::Instance inst;
  inst.name = "cylinder";
  inst.mesh = 0;
  scene.instances.push_back(inst);
  return scene;
}

// Lightmap UVs and texels the way a bake makes them.
TexelSet unwrappedTexels(scenes::Scene& scene, float texelsPerUnit) {
  uv::UnwrapOptions options;
  options.pack.texelsPerUnit = texelsPerUnit;
  const Result<uv::UnwrapResult> unwrapped = uv::unwrap(scene, options);
  EXPECT_TRUE(unwrapped) << unwrapped.message();
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  EXPECT_TRUE(tracer) << tracer.message();
  if (!unwrapped || !tracer) return {};
  Result<TexelSet> texels = computeTexels(scene, *tracer.value());
  EXPECT_TRUE(texels) << texels.message();
  return texels ? std::move(texels.value()) : TexelSet{};
}

// Through uv::unwrap and computeTexels: the cut the unwrapper makes down a smoothly shaded
// cylinder is found and stitched. Smooth light alone already steps across it (the two sides'
// texel grids do not line up); stitching shrinks the step severalfold.
TEST(SeamStitch, UnwrappedCylinderSeamsAgree) {
  scenes::Scene scene = cylinderScene(24);
  const TexelSet texels = unwrappedTexels(scene, 24.0f);
  ASSERT_EQ(texels.atlases.size(), 1u);
  std::vector<glm::vec3> values;
  for (const glm::vec3& p : texels.position)
    values.push_back(glm::vec3(1.0f + 0.5f * std::sin(3.0f * std::atan2(p.z, p.x)) + 0.3f * p.y));
  const std::vector<Seam> seams = findSeams(scene, texels.atlases, 30.0f)[0];
  ASSERT_FALSE(seams.empty());

  float mismatch[2] = {};
  for (bool stitch : {false, true}) {
    TexelSet t = texels;
    PostOptions options;
    options.stitchSeams = stitch;
    computeAtlasMixes(t, scene, options);
    const std::vector<glm::vec3> image = resolve(t, values);
    for (const Seam& seam : seams)
      mismatch[stitch] += seamMismatch(image, t.atlases[0].width, t.atlases[0].height, seam.a0,
                                       seam.a1, seam.b0, seam.b1) / float(seams.size());
  }
  RecordProperty("mismatchBefore", std::to_string(mismatch[0]));
  RecordProperty("mismatchAfter", std::to_string(mismatch[1]));
  EXPECT_LT(mismatch[1] * 3.0f, mismatch[0])
      << "before " << mismatch[0] << ", after " << mismatch[1];
}

// The Cornell box's walls are single charts and its blocks meet at 90°: nothing to stitch, and
// the mixes are exactly those of fill and dilation.
TEST(SeamStitch, CornellBoxHasNothingToStitch) {
  scenes::Scene scene = scenes::makeCornellBox();
  TexelSet texels = unwrappedTexels(scene, 48.0f);
  ASSERT_EQ(texels.atlases.size(), 1u);
  TexelSet unstitched = texels;
  PostOptions options;
  const PostStats stats = computeAtlasMixes(texels, scene, options);
  options.stitchSeams = false;
  computeAtlasMixes(unstitched, scene, options);
  EXPECT_EQ(stats.seamEdges, 0u);
  expectSameMixes(texels, unstitched);
}

}  // namespace
}  // namespace afterglow::baker
