// Sampling helpers shared by the precompute stages (links, direct light). Every random number is
// a pure function of (stream, item, sample), never of the thread, so bakes are bit-identical
// whatever the thread count.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "afterglow/runtime/transport.h"

namespace afterglow::baker::sampling {

constexpr float kPi = 3.14159265358979323846f;

// Streams keep the sequences of different stages independent for the same (item, sample).
enum class Stream : uint64_t {
  TexelLinks = 1,
  ClusterLinks = 2,
  LightVisibility = 3,
  Emissive = 4,
  Reference = 5,
  ReferenceView = 6,
  BackDistance = 7,
};

// SplitMix64's finaliser: a cheap, well-mixed 64-bit hash.
inline uint64_t mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Counter-based generator: seeded from (stream, item, sample), then a SplitMix64 sequence.
class Rng {
 public:
  Rng(Stream stream, uint64_t item, uint64_t sample)
      : state_(mix64(mix64(mix64(uint64_t(stream)) ^ item) ^ sample)) {}
  // Uniform in [0, 1).
  float next() {
    state_ += 0x9e3779b97f4a7c15ull;
    return float(mix64(state_) >> 40) * (1.0f / 16777216.0f);
  }
  glm::vec2 next2() {
    const float a = next();
    return {a, next()};
  }

 private:
  uint64_t state_;
};

// Jittered-stratified point in [0,1)² for sample `index` of `count`: the first g² samples
// (g = floor(sqrt(count))) fall one per cell of a g×g grid, the rest uniformly. Stratification
// cuts the variance of smooth integrands such as form factors by a large factor at no cost.
inline glm::vec2 stratified2(Rng& rng, uint32_t index, uint32_t count) {
  const glm::vec2 u = rng.next2();
  const uint32_t g = uint32_t(std::sqrt(double(count)));
  if (g <= 1 || index >= g * g) return u;
  const float inv = 1.0f / float(g);
  return {(float(index % g) + u.x) * inv, (float(index / g) + u.y) * inv};
}

// Cosine-weighted direction about +Z (pdf cosθ/π).
inline glm::vec3 cosineHemisphere(glm::vec2 u) {
  const float r = std::sqrt(u.x);
  const float phi = 2.0f * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u.x))};
}

// Uniform direction in the cone of half-angle acos(cosMax) about +Z.
inline glm::vec3 uniformCone(glm::vec2 u, float cosMax) {
  const float cosT = 1.0f - u.x * (1.0f - cosMax);
  const float sinT = std::sqrt(std::max(0.0f, 1.0f - cosT * cosT));
  const float phi = 2.0f * kPi * u.y;
  return {sinT * std::cos(phi), sinT * std::sin(phi), cosT};
}

// Uniform point in the unit disk (concentric-free polar form; uniform in area).
inline glm::vec2 uniformDisk(glm::vec2 u) {
  const float r = std::sqrt(u.x);
  const float phi = 2.0f * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi)};
}

// Orthonormal basis (t, b, n) around a unit n (Duff et al. 2017, branchless and continuous
// except at n.z = -1's sign flip).
struct Frame {
  glm::vec3 t, b, n;
  explicit Frame(glm::vec3 normal) : n(normal) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float c = n.x * n.y * a;
    t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = glm::vec3(c, sign + n.y * n.y * a, -n.y);
  }
  glm::vec3 toWorld(glm::vec3 v) const { return t * v.x + b * v.y + n * v.z; }
};

// Real SH basis, bands 0..2, in world axes (x, y, z) of a unit direction, in the usual order
// Y00, Y1-1 (y), Y10 (z), Y11 (x), Y2-2 (xy), Y2-1 (yz), Y20, Y21 (xz), Y22. With this basis a
// constant radiance L projects to L·2√π on Y00 (runtime::constantSkySh).
inline void shBasis(glm::vec3 d, float out[runtime::kShCount]) {
  out[0] = 0.282094791773878f;
  out[1] = 0.488602511902920f * d.y;
  out[2] = 0.488602511902920f * d.z;
  out[3] = 0.488602511902920f * d.x;
  out[4] = 1.092548430592079f * d.x * d.y;
  out[5] = 1.092548430592079f * d.y * d.z;
  out[6] = 0.315391565252520f * (3.0f * d.z * d.z - 1.0f);
  out[7] = 1.092548430592079f * d.x * d.z;
  out[8] = 0.546274215296040f * (d.x * d.x - d.y * d.y);
}

}  // namespace afterglow::baker::sampling
