// The reflection probes' cubemap geometry: texel solid angles, direction ↔ texel, OpenEXR's face
// order and orientation, and bilinear filtering across face edges.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "afterglow/runtime/cubemap.h"
#include "test_rng.h"

namespace afterglow::runtime {
namespace {

constexpr double kPiD = 3.14159265358979323846;

float angleBetween(glm::vec3 a, glm::vec3 b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

TEST(Cubemap, TexelSolidAnglesSumToFourPi) {
  for (int size : {1, 2, 5, 16, 128}) {
    double sum = 0.0;
    for (int face = 0; face < kCubeFaceCount; ++face)
      for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) sum += double(cubemapTexelSolidAngle(x, y, size));
    EXPECT_NEAR(sum, 4.0 * kPiD, 1e-5) << "size " << size;
  }
}

// The sum above would also hold for a wrong split of a face among its texels, so each texel is
// checked against a midpoint-rule integral of dA / (1 + s² + t²)^{3/2} over its square.
TEST(Cubemap, TexelSolidAngleMatchesQuadrature) {
  const int size = 8;
  const int steps = 200;
  double worst = 0.0;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double h = 2.0 / size / steps;
      double integral = 0.0;
      for (int j = 0; j < steps; ++j) {
        for (int i = 0; i < steps; ++i) {
          const double s = -1.0 + 2.0 * x / size + (i + 0.5) * h;
          const double t = -1.0 + 2.0 * y / size + (j + 0.5) * h;
          integral += h * h / std::pow(1.0 + s * s + t * t, 1.5);
        }
      }
      worst = std::max(worst, std::abs(double(cubemapTexelSolidAngle(x, y, size)) - integral) /
                                  integral);
    }
  }
  EXPECT_LT(worst, 1e-5);
  // A corner texel subtends less than a centre one: about 3^{-3/2} of it for small texels.
  EXPECT_LT(cubemapTexelSolidAngle(0, 0, size), 0.5f * cubemapTexelSolidAngle(3, 3, size));
}

TEST(Cubemap, DirectionToTexelRoundTripsAtTexelCentres) {
  for (int size : {1, 3, 8, 32}) {
    int mismatches = 0;
    float worstUv = 0.0f;
    for (int face = 0; face < kCubeFaceCount; ++face) {
      for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
          const glm::vec3 d = cubemapTexelDirection(face, x, y, size);
          EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
          const CubeTexel t = cubemapTexel(d, size);
          if (t.face != face || t.x != x || t.y != y) ++mismatches;
          const CubeFaceUv p = cubemapFaceUv(d);
          worstUv = std::max({worstUv, std::abs(p.u - (x + 0.5f) / size),
                              std::abs(p.v - (y + 0.5f) / size)});
          // And back: the direction of the found (u, v) is the texel's.
          EXPECT_LT(angleBetween(cubemapDirection(p.face, p.u, p.v), d), 1e-5f);
        }
      }
    }
    EXPECT_EQ(mismatches, 0) << "size " << size;
    EXPECT_LT(worstUv, 1e-6f) << "size " << size;
  }
}

TEST(Cubemap, FaceCentresAreTheirAxes) {
  const glm::vec3 axes[kCubeFaceCount] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                          {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  for (int face = 0; face < kCubeFaceCount; ++face) {
    EXPECT_EQ(cubemapDirection(face, 0.5f, 0.5f), axes[face]) << "face " << face;
    // The middle texel of an odd size is centred on the axis too, and the axis falls in it.
    EXPECT_EQ(cubemapTexelDirection(face, 2, 2, 5), axes[face]) << "face " << face;
    const CubeTexel t = cubemapTexel(axes[face], 5);
    EXPECT_EQ(t.face, face);
    EXPECT_EQ(t.x, 2);
    EXPECT_EQ(t.y, 2);
  }
}

// OpenEXR's ImfEnvmap.h, written out independently of cubemap.cpp: CubeMap::pixelPosition maps
// a face's position-in-face (px, py) to a pixel of the face's block, y down the image;
// CubeMap::direction maps it to a direction with pos = the position scaled to [−1, 1].
struct ExrPixel {
  int column, row;
};
ExrPixel exrPixelOfPositionInFace(int face, int px, int py, int size) {
  const int last = size - 1;
  switch (face) {
    case kCubeFacePosX: return {py, last - px};
    case kCubeFaceNegX: return {last - py, last - px};
    case kCubeFacePosY: return {px, last - py};
    case kCubeFaceNegY: return {px, py};
    case kCubeFacePosZ: return {last - px, last - py};
    default: return {px, last - py};
  }
}
glm::vec3 exrDirection(int face, float posX, float posY) {
  switch (face) {
    case kCubeFacePosX: return {1, posX, posY};
    case kCubeFaceNegX: return {-1, posX, posY};
    case kCubeFacePosY: return {posX, 1, posY};
    case kCubeFaceNegY: return {posX, -1, posY};
    case kCubeFacePosZ: return {posX, posY, 1};
    default: return {posX, posY, -1};
  }
}

TEST(Cubemap, OrientationIsOpenExrs) {
  for (int size : {2, 7, 64}) {
    float worstExact = 0.0f;
    float worstCentreToCentre = 0.0f;
    for (int face = 0; face < kCubeFaceCount; ++face) {
      for (int py = 0; py < size; ++py) {
        for (int px = 0; px < size; ++px) {
          const ExrPixel p = exrPixelOfPositionInFace(face, px, py, size);
          const glm::vec3 ours = cubemapTexelDirection(face, p.column, p.row, size);
          // OpenEXR's mapping with the texel centres at (i + 0.5)/size (ours) is the same
          // direction to float precision ...
          const glm::vec3 edgeToEdge =
              glm::normalize(exrDirection(face, (px + 0.5f) / size * 2.0f - 1.0f,
                                          (py + 0.5f) / size * 2.0f - 1.0f));
          worstExact = std::max(worstExact, angleBetween(ours, edgeToEdge));
          // ... and OpenEXR's own, centres of the edge pixels on the cube's edges, is within
          // about half a texel of it.
          const glm::vec3 centreToCentre =
              glm::normalize(exrDirection(face, float(px) / (size - 1) * 2.0f - 1.0f,
                                          float(py) / (size - 1) * 2.0f - 1.0f));
          worstCentreToCentre = std::max(worstCentreToCentre, angleBetween(ours, centreToCentre));
        }
      }
    }
    EXPECT_LT(worstExact, 1e-6f) << "size " << size;
    // Half a texel at a face centre is 1/size radians.
    EXPECT_LT(worstCentreToCentre, 1.0f / size) << "size " << size;
  }

  // The corners ImfEnvmap.h's diagram labels on each face (top-left, top-right, bottom-left,
  // bottom-right of the face's block), as the signs of the cube corner they touch.
  const glm::vec3 corners[kCubeFaceCount][4] = {
      {{1, 1, -1}, {1, 1, 1}, {1, -1, -1}, {1, -1, 1}},          // +X: 3 7 / 1 5
      {{-1, 1, 1}, {-1, 1, -1}, {-1, -1, 1}, {-1, -1, -1}},      // −X: 6 2 / 4 0
      {{-1, 1, 1}, {1, 1, 1}, {-1, 1, -1}, {1, 1, -1}},          // +Y: 6 7 / 2 3
      {{-1, -1, -1}, {1, -1, -1}, {-1, -1, 1}, {1, -1, 1}},      // −Y: 0 1 / 4 5
      {{1, 1, 1}, {-1, 1, 1}, {1, -1, 1}, {-1, -1, 1}},          // +Z: 7 6 / 5 4
      {{-1, 1, -1}, {1, 1, -1}, {-1, -1, -1}, {1, -1, -1}}};     // −Z: 2 3 / 0 1
  const float uv[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int c = 0; c < 4; ++c)
      EXPECT_LT(angleBetween(cubemapDirection(face, uv[c][0], uv[c][1]),
                             glm::normalize(corners[face][c])),
                1e-6f)
          << "face " << face << " corner " << c;
}

// The header's claim for GPU upload: OpenGL's cube-texture face selection and (s, t) table,
// applied to (x, y, −z), lands on our face (with +Z and −Z swapped) at our (u, v).
TEST(Cubemap, GpuTableWithZNegatedIsOurs) {
  test::Rng rng{11};
  for (int i = 0; i < 2000; ++i) {
    const glm::vec3 d = randomDirection(rng);
    const glm::vec3 g(d.x, d.y, -d.z);
    const glm::vec3 m = glm::abs(g);
    int glFace;
    float sc, tc, ma;
    if (m.x >= m.y && m.x >= m.z) {
      glFace = g.x > 0 ? 0 : 1;
      sc = g.x > 0 ? -g.z : g.z;
      tc = -g.y;
      ma = m.x;
    } else if (m.y >= m.z) {
      glFace = g.y > 0 ? 2 : 3;
      sc = g.x;
      tc = g.y > 0 ? g.z : -g.z;
      ma = m.y;
    } else {
      glFace = g.z > 0 ? 4 : 5;
      sc = g.z > 0 ? g.x : -g.x;
      tc = -g.y;
      ma = m.z;
    }
    const int expectedFace = glFace == 4 ? 5 : glFace == 5 ? 4 : glFace;
    const CubeFaceUv p = cubemapFaceUv(d);
    ASSERT_EQ(p.face, expectedFace);
    EXPECT_NEAR(p.u, 0.5f * (sc / ma + 1.0f), 1e-6f);
    EXPECT_NEAR(p.v, 0.5f * (tc / ma + 1.0f), 1e-6f);
  }
}

// Bilinear filtering of a smooth environment is second-order accurate everywhere, across face
// edges too, and nearly so at the corners where three faces meet. (Clamping each lookup to its
// face instead leaves first-order errors within half a texel of every edge: 0.012 at edges and
// 0.010 at corners for this field.)
TEST(Cubemap, BilinearIsSeamlessAcrossFaceEdges) {
  auto field = [](glm::vec3 d) {
    return glm::vec3(1.0f + 0.5f * d.x, 1.0f + 0.7f * d.y - 0.2f * d.z, 2.0f + d.x * d.z);
  };
  const int size = 32;
  Cubemap cube = makeCubemap(size);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x)
        cube.at(face, x, y) = field(cubemapTexelDirection(face, x, y, size));

  // At texel centres bilinear returns the texel.
  for (int face = 0; face < kCubeFaceCount; ++face)
    EXPECT_LT(glm::length(sampleCubemap(cube, cubemapTexelDirection(face, 5, 9, size)) -
                          cube.at(face, 5, 9)),
              1e-5f);

  test::Rng rng{5};
  float worstInterior = 0.0f;
  float worstEdge = 0.0f;
  float worstCorner = 0.0f;
  for (int i = 0; i < 200000; ++i) {
    const glm::vec3 d = randomDirection(rng);
    const CubeFaceUv p = cubemapFaceUv(d);
    const float borderU = std::min(p.u, 1.0f - p.u) * size;
    const float borderV = std::min(p.v, 1.0f - p.v) * size;
    const float err = glm::length(sampleCubemap(cube, d) - field(d));
    float& worst = borderU < 0.5f && borderV < 0.5f ? worstCorner
                   : borderU < 0.5f || borderV < 0.5f ? worstEdge
                                                      : worstInterior;
    worst = std::max(worst, err);
  }
  std::printf("bilinear, 32² faces: worst error %.5f inside, %.5f at edges, %.5f at corners\n",
              worstInterior, worstEdge, worstCorner);
  // The field changes by up to ~0.05 per texel (1.7 rad⁻¹ · 2/32 rad); second-order errors are
  // a small fraction of that.
  EXPECT_LT(worstInterior, 2e-3f);
  EXPECT_LT(worstEdge, 2e-3f);
  EXPECT_LT(worstCorner, 4e-3f);
}

// The taps are sampleCubemap's arithmetic: a random cube read through them matches the lookup,
// everywhere including the face edges and corners, whose corners read a neighbouring face.
TEST(Cubemap, BilinearTapsAreTheLookup) {
  test::Rng rng{11};
  for (int size : {1, 2, 7, 16}) {
    Cubemap cube = makeCubemap(size);
    for (glm::vec3& t : cube.texels) t = glm::vec3(rng.unit(), rng.unit(), 10.0f * rng.unit());
    float worst = 0.0f;
    int most = 0;
    for (int i = 0; i < 20000; ++i) {
      // Half the directions on face edges and corners, where the taps leave the face.
      glm::vec3 d = randomDirection(rng);
      const glm::vec3 m = glm::abs(d);
      const int major = m.x >= m.y && m.x >= m.z ? 0 : m.y >= m.z ? 1 : 2;
      const int other = (major + 1 + int(rng.below(2))) % 3;
      if (i % 2) d[other] = std::copysign(m[major], d[other]);  // on an edge
      if (i % 4 == 1) d = glm::vec3(std::copysign(1.0f, d.x), std::copysign(1.0f, d.y),
                                    std::copysign(1.0f, d.z));  // a corner
      CubemapTap taps[kMaxCubemapTaps];
      const int count = cubemapBilinearTaps(size, d, taps);
      ASSERT_GT(count, 0);
      ASSERT_LE(count, kMaxCubemapTaps);
      most = std::max(most, count);
      glm::vec3 sum(0.0f);
      float weight = 0.0f;
      for (int k = 0; k < count; ++k) {
        ASSERT_LT(taps[k].index, cube.texels.size());
        EXPECT_GE(taps[k].weight, 0.0f);
        sum += taps[k].weight * cube.texels[taps[k].index];
        weight += taps[k].weight;
      }
      EXPECT_NEAR(weight, 1.0f, 1e-5f);
      worst = std::max(worst, glm::length(sum - sampleCubemap(cube, d)));
    }
    EXPECT_LT(worst, 1e-5f) << "size " << size;
    EXPECT_GT(most, 4) << "size " << size;  // some lookups did read across an edge
  }
  EXPECT_EQ(cubemapBilinearTaps(0, glm::vec3(1.0f, 0.0f, 0.0f), nullptr), 0);
}

// A bordered cubemap reads what sampleCubemap reads, bit for bit, everywhere (edges and corners
// of small faces most of all).
TEST(Cubemap, BorderedLookupEqualsSampleCubemap) {
  for (int size : {1, 2, 4, 16}) {
    Cubemap cube = makeCubemap(size);
    for (size_t k = 0; k < cube.texels.size(); ++k)
      cube.texels[k] = glm::vec3(float(k % 7), float(k % 11) * 0.5f, float(k) * 0.01f);
    const BorderedCubemap bordered = withBorder(cube);
    int differ = 0;
    for (int i = 0; i < 20000; ++i) {
      // A deterministic spread of directions (golden-angle spiral), edges and corners included.
      const float z = 1.0f - 2.0f * (float(i) + 0.5f) / 20000.0f;
      const float r = std::sqrt(std::max(0.0f, 1.0f - z * z)), phi = 2.39996323f * float(i);
      const glm::vec3 d(r * std::cos(phi), r * std::sin(phi), z);
      differ += sampleBorderedCubemap(bordered, d) != sampleCubemap(cube, d);
    }
    for (const glm::vec3 d : {glm::vec3(1, 1, 1), glm::vec3(-1, 1, 0), glm::vec3(0, 0, -1)})
      differ += sampleBorderedCubemap(bordered, d) != sampleCubemap(cube, d);
    EXPECT_EQ(differ, 0) << "size " << size;
  }
}

}  // namespace
}  // namespace afterglow::runtime
