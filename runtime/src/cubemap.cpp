#include "afterglow/runtime/cubemap.h"

#include <algorithm>
#include <cmath>

namespace afterglow::runtime {

namespace {

// The unnormalised direction of face coordinates a, b ∈ [−1, 1] (the header's table).
glm::vec3 facePlanePoint(int face, float a, float b) {
  switch (face) {
    case kCubeFacePosX: return {1.0f, -b, a};
    case kCubeFaceNegX: return {-1.0f, -b, -a};
    case kCubeFacePosY: return {a, 1.0f, -b};
    case kCubeFaceNegY: return {a, -1.0f, b};
    case kCubeFacePosZ: return {-a, -b, 1.0f};
    default: return {a, -b, -1.0f};
  }
}

// The antiderivative of the face plane's solid-angle element at (s, t).
double areaElement(double s, double t) { return std::atan2(s * t, std::sqrt(s * s + t * t + 1.0)); }

// Bilinear within one face at (u, v), the texels beyond its edges clamped to it.
glm::vec3 sampleFaceClamped(const Cubemap& cube, const CubeFaceUv& p) {
  const int n = cube.size;
  const float fx = std::clamp(p.u * float(n) - 0.5f, 0.0f, float(n - 1));
  const float fy = std::clamp(p.v * float(n) - 0.5f, 0.0f, float(n - 1));
  const int x0 = std::min(int(fx), n - 1);
  const int y0 = std::min(int(fy), n - 1);
  const int x1 = std::min(x0 + 1, n - 1);
  const int y1 = std::min(y0 + 1, n - 1);
  const float wx = fx - float(x0);
  const float wy = fy - float(y0);
  const glm::vec3 top = glm::mix(cube.at(p.face, x0, y0), cube.at(p.face, x1, y0), wx);
  const glm::vec3 bottom = glm::mix(cube.at(p.face, x0, y1), cube.at(p.face, x1, y1), wx);
  return glm::mix(top, bottom, wy);
}

// sampleFaceClamped's texels and weights, each scaled by `scale`, appended at taps[count].
int faceClampedTaps(int n, const CubeFaceUv& p, float scale, CubemapTap* taps, int count) {
  const float fx = std::clamp(p.u * float(n) - 0.5f, 0.0f, float(n - 1));
  const float fy = std::clamp(p.v * float(n) - 0.5f, 0.0f, float(n - 1));
  const int x0 = std::min(int(fx), n - 1);
  const int y0 = std::min(int(fy), n - 1);
  const int x1 = std::min(x0 + 1, n - 1);
  const int y1 = std::min(y0 + 1, n - 1);
  const float wx = fx - float(x0);
  const float wy = fy - float(y0);
  const uint32_t row0 = uint32_t((p.face * n + y0) * n);
  const uint32_t row1 = uint32_t((p.face * n + y1) * n);
  taps[count++] = {row0 + uint32_t(x0), scale * (1.0f - wx) * (1.0f - wy)};
  taps[count++] = {row0 + uint32_t(x1), scale * wx * (1.0f - wy)};
  taps[count++] = {row1 + uint32_t(x0), scale * (1.0f - wx) * wy};
  taps[count++] = {row1 + uint32_t(x1), scale * wx * wy};
  return count;
}

}  // namespace

Cubemap makeCubemap(int size, glm::vec3 value) {
  Cubemap cube;
  cube.size = std::max(size, 0);
  cube.texels.assign(size_t(kCubeFaceCount) * size_t(cube.size) * size_t(cube.size), value);
  return cube;
}

glm::vec3 cubemapDirection(int face, float u, float v) {
  return glm::normalize(facePlanePoint(face, 2.0f * u - 1.0f, 2.0f * v - 1.0f));
}

glm::vec3 cubemapTexelDirection(int face, int x, int y, int size) {
  const float inv = 1.0f / float(size);
  return cubemapDirection(face, (float(x) + 0.5f) * inv, (float(y) + 0.5f) * inv);
}

CubeFaceUv cubemapFaceUv(glm::vec3 dir) {
  const glm::vec3 m = glm::abs(dir);
  CubeFaceUv out;
  float a = 0.0f;
  float b = 0.0f;
  // The inverse of facePlanePoint: divide by the major component's magnitude.
  if (m.x >= m.y && m.x >= m.z) {
    if (m.x == 0.0f) return {kCubeFacePosX, 0.5f, 0.5f};  // the zero vector: anything valid
    const float inv = 1.0f / m.x;
    out.face = dir.x > 0.0f ? kCubeFacePosX : kCubeFaceNegX;
    a = (dir.x > 0.0f ? dir.z : -dir.z) * inv;
    b = -dir.y * inv;
  } else if (m.y >= m.z) {
    const float inv = 1.0f / m.y;
    out.face = dir.y > 0.0f ? kCubeFacePosY : kCubeFaceNegY;
    a = dir.x * inv;
    b = (dir.y > 0.0f ? -dir.z : dir.z) * inv;
  } else {
    const float inv = 1.0f / m.z;
    out.face = dir.z > 0.0f ? kCubeFacePosZ : kCubeFaceNegZ;
    a = (dir.z > 0.0f ? -dir.x : dir.x) * inv;
    b = -dir.y * inv;
  }
  out.u = 0.5f * (a + 1.0f);
  out.v = 0.5f * (b + 1.0f);
  return out;
}

CubeTexel cubemapTexel(glm::vec3 dir, int size) {
  const CubeFaceUv p = cubemapFaceUv(dir);
  CubeTexel t;
  t.face = p.face;
  t.x = std::clamp(int(std::floor(p.u * float(size))), 0, size - 1);
  t.y = std::clamp(int(std::floor(p.v * float(size))), 0, size - 1);
  return t;
}

float cubemapTexelSolidAngle(int x, int y, int size) {
  // In double: the four terms nearly cancel for small texels, and the sum over a large cube
  // must reach 4π to 1e-5.
  const double inv = 2.0 / double(size);
  const double s0 = double(x) * inv - 1.0;
  const double s1 = double(x + 1) * inv - 1.0;
  const double t0 = double(y) * inv - 1.0;
  const double t1 = double(y + 1) * inv - 1.0;
  return float(areaElement(s1, t1) - areaElement(s0, t1) - areaElement(s1, t0) +
               areaElement(s0, t0));
}

glm::vec3 sampleCubemap(const Cubemap& cube, glm::vec3 dir) {
  if (cube.size <= 0) return glm::vec3(0.0f);
  const int n = cube.size;
  const CubeFaceUv p = cubemapFaceUv(dir);
  // Continuous texel coordinates with texel centres at integers.
  const float fx = p.u * float(n) - 0.5f;
  const float fy = p.v * float(n) - 0.5f;
  const int x0 = int(std::floor(fx));
  const int y0 = int(std::floor(fy));
  const float wx = fx - float(x0);
  const float wy = fy - float(y0);
  const float inv = 1.0f / float(n);

  auto fetch = [&](int x, int y) -> glm::vec3 {
    if (x >= 0 && x < n && y >= 0 && y < n) return cube.at(p.face, x, y);
    // Beyond the face: the radiance at the centre of the virtual texel on the extended face
    // plane, half a texel past the edge. It projects onto the neighbouring face about half a
    // texel inside it, across the edge from a texel centre, but along the edge it is pulled
    // toward the face's centre by up to half a texel near a corner; so it is read bilinearly
    // there (clamped to that face), not from the texel it falls in.
    const glm::vec3 d = facePlanePoint(p.face, 2.0f * (float(x) + 0.5f) * inv - 1.0f,
                                       2.0f * (float(y) + 0.5f) * inv - 1.0f);
    return sampleFaceClamped(cube, cubemapFaceUv(d));
  };

  const glm::vec3 top = glm::mix(fetch(x0, y0), fetch(x0 + 1, y0), wx);
  const glm::vec3 bottom = glm::mix(fetch(x0, y0 + 1), fetch(x0 + 1, y0 + 1), wx);
  return glm::mix(top, bottom, wy);
}

BorderedCubemap withBorder(const Cubemap& cube) {
  BorderedCubemap out;
  out.size = cube.size;
  if (cube.size <= 0) return out;
  const int n = cube.size, m = n + 2;
  const float inv = 1.0f / float(n);
  out.texels.resize(size_t(kCubeFaceCount) * size_t(m) * size_t(m));
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = -1; y <= n; ++y)
      for (int x = -1; x <= n; ++x) {
        glm::vec3 v;
        if (x >= 0 && x < n && y >= 0 && y < n) {
          v = cube.at(face, x, y);
        } else {
          // sampleCubemap's fetch beyond the face, exactly.
          const glm::vec3 d = facePlanePoint(face, 2.0f * (float(x) + 0.5f) * inv - 1.0f,
                                             2.0f * (float(y) + 0.5f) * inv - 1.0f);
          v = sampleFaceClamped(cube, cubemapFaceUv(d));
        }
        out.texels[(size_t(face) * size_t(m) + size_t(y + 1)) * size_t(m) + size_t(x + 1)] = v;
      }
  return out;
}

glm::vec3 sampleBorderedCubemap(const BorderedCubemap& cube, glm::vec3 dir) {
  return sampleBorderedCubemap(cube, cubemapFaceUv(dir));
}

glm::vec3 sampleBorderedCubemap(const BorderedCubemap& cube, const CubeFaceUv& p) {
  if (cube.size <= 0) return glm::vec3(0.0f);
  return sampleBordered(cube, borderedBilinear(cube.size, p));
}

BorderedBilinear borderedBilinear(int size, const CubeFaceUv& p) {
  const int n = size, m = n + 2;
  const float fx = p.u * float(n) - 0.5f;
  const float fy = p.v * float(n) - 0.5f;
  // In [-1, n - 1] (u, v in [0, 1]); clamped against rounding at u = 1.
  const int x0 = std::clamp(int(std::floor(fx)), -1, n - 1);
  const int y0 = std::clamp(int(std::floor(fy)), -1, n - 1);
  BorderedBilinear b;
  b.wx = fx - float(x0);
  b.wy = fy - float(y0);
  b.index = uint32_t((size_t(p.face) * size_t(m) + size_t(y0 + 1)) * size_t(m) + size_t(x0 + 1));
  return b;
}

int cubemapBilinearTaps(int size, glm::vec3 dir, CubemapTap* taps) {
  if (size <= 0) return 0;
  // sampleCubemap step by step, recording texels instead of reading them.
  const int n = size;
  const CubeFaceUv p = cubemapFaceUv(dir);
  const float fx = p.u * float(n) - 0.5f;
  const float fy = p.v * float(n) - 0.5f;
  const int x0 = int(std::floor(fx));
  const int y0 = int(std::floor(fy));
  const float wx = fx - float(x0);
  const float wy = fy - float(y0);
  const float inv = 1.0f / float(n);
  int count = 0;
  auto corner = [&](int x, int y, float weight) {
    if (weight == 0.0f) return;
    if (x >= 0 && x < n && y >= 0 && y < n) {
      taps[count++] = {uint32_t((p.face * n + y) * n + x), weight};
      return;
    }
    const glm::vec3 d = facePlanePoint(p.face, 2.0f * (float(x) + 0.5f) * inv - 1.0f,
                                       2.0f * (float(y) + 0.5f) * inv - 1.0f);
    count = faceClampedTaps(n, cubemapFaceUv(d), weight, taps, count);
  };
  corner(x0, y0, (1.0f - wx) * (1.0f - wy));
  corner(x0 + 1, y0, wx * (1.0f - wy));
  corner(x0, y0 + 1, (1.0f - wx) * wy);
  corner(x0 + 1, y0 + 1, wx * wy);
  return count;
}

}  // namespace afterglow::runtime
