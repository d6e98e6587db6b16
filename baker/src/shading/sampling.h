// Sampling helpers shared by the precompute stages (links, direct light). Every random number is
// a pure function of (stream, item, sample), never of the thread, so bakes are bit-identical
// whatever the thread count.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/math.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::baker::sampling {

// Streams keep the sequences of different stages independent for the same (item, sample).
enum class Stream : uint64_t {
  TexelLinks = 1,
  ClusterLinks = 2,
  LightVisibility = 3,
  Emissive = 4,
  Reference = 5,
  ReferenceView = 6,
  BackDistance = 7,
  Probes = 8,
  GlassSky = 9,
  Burial = 10,
  ProbeOcclusion = 11,
};

using afterglow::mix64;  // core/math.h

// Counter-based generator: seeded from (stream, item, sample), then a SplitMix64 sequence.
class Rng {
 public:
  Rng(Stream stream, uint64_t item, uint64_t sample)
      : state_(mix64(itemSeed(stream, item) ^ sample)) {}

  // The part of the seed shared by every sample of one item: loops that seed a generator per
  // sample (shadow rays) work it out once and call Rng(seed, sample), the same generator as
  // Rng(stream, item, sample) for a third of the hashing.
  static uint64_t itemSeed(Stream stream, uint64_t item) {
    return mix64(mix64(uint64_t(stream)) ^ item);
  }
  struct ItemSeed {
    uint64_t value;
  };
  Rng(ItemSeed seed, uint64_t sample) : state_(mix64(seed.value ^ sample)) {}

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

// stratified2 for one count, its grid worked out once: point(rng, i) == stratified2(rng, i,
// count), without a double-precision square root per sample (shadow rays take one each).
class Stratified {
 public:
  explicit Stratified(uint32_t count)
      : g_(uint32_t(std::sqrt(double(count)))), inv_(1.0f / float(g_)) {}
  glm::vec2 point(Rng& rng, uint32_t index) const {
    const glm::vec2 u = rng.next2();
    if (g_ <= 1 || index >= g_ * g_) return u;
    return {(float(index % g_) + u.x) * inv_, (float(index / g_) + u.y) * inv_};
  }

 private:
  uint32_t g_;
  float inv_;
};

// 16 multi-jittered points in [0,1)² (Chiu, Shirley and Wang 1994), row by row: one in each
// cell of a 4 × 4 grid and, the rows' and columns' sub-cells shuffled, one in each of 16
// strata along either axis, so an edge along either axis is placed to a sixteenth.
inline void multiJittered16(Rng& rng, glm::vec2 out[16]) {
  int across[4] = {0, 1, 2, 3}, down[4] = {0, 1, 2, 3};
  for (int i = 3; i > 0; --i) {
    std::swap(across[i], across[std::min(i, int(rng.next() * float(i + 1)))]);
    std::swap(down[i], down[std::min(i, int(rng.next() * float(i + 1)))]);
  }
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      const glm::vec2 u = rng.next2();
      out[y * 4 + x] = glm::vec2((float(x) + (float(across[y]) + u.x) * 0.25f) * 0.25f,
                                 (float(y) + (float(down[x]) + u.y) * 0.25f) * 0.25f);
    }
}

// Owen-scrambled Sobol' points spread over the texels of a 16 × 16 atlas tile in Morton order
// (Ahmed and Wonka 2020's hierarchical ordering of pixels), for the texels' gather rays: the
// texel at tile position m takes points m·n .. m·n + n − 1 of the tile's sequence. Any 2^k
// consecutive points of the first two Sobol' dimensions starting at a multiple of 2^k are a
// (0, k, 2)-net, stratified in every elementary interval, and Owen scrambling keeps that: for
// n a power of two each texel's n points, each aligned 2×2 block's 4n, each 4×4 square's 16n
// are such a net. Neighbouring texels' errors then cancel rather than add up: the noise left
// sits at the scale of a texel, where the smoothing and the eye average it away, not in
// blotches a few texels across (on the Cornell box's walls the blotches fell by about a
// third against independently jittered texels). The scramble (Burley 2020's hash form of
// Laine and Karras's) is seeded per tile and leaves every point uniformly distributed, so any
// texel's estimate, and any subset of its rays chosen by index, stays unbiased.
class TiledSobol {
 public:
  TiledSobol(uint64_t seed, uint32_t px, uint32_t py, uint32_t n)
      : base_(mortonInTile(px & 15u, py & 15u) * n) {
    const uint64_t h = mix64(seed ^ mix64((uint64_t(px >> 4) << 32) | uint64_t(py >> 4)));
    seedX_ = uint32_t(h), seedY_ = uint32_t(h >> 32);
  }
  // Owen scrambling of a 0.32 fraction v is reverseBits(scramble(reverseBits(v))): each binary
  // digit flipped by a hash of the digits above it, the hash working on the reversed bits,
  // where a multiply carries low into high. Both dimensions are generated reversed already
  // (the first is reverseBits(i), so reversed it is i itself), which saves two reversals.
  glm::vec2 point(uint32_t s) const {
    const uint32_t i = base_ + s;
    return {toUnit(reverseBits(scramble(i, seedX_))),
            toUnit(reverseBits(scramble(sobolSecondReversed(i), seedY_)))};
  }

 private:
  static uint32_t mortonInTile(uint32_t x, uint32_t y) {
    uint32_t m = 0;
    for (uint32_t b = 0; b < 4; ++b)
      m |= ((x >> b) & 1u) << (2 * b) | ((y >> b) & 1u) << (2 * b + 1);
    return m;
  }
  static uint32_t reverseBits(uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
  }
  // The second Sobol' dimension (primitive polynomial x + 1) as a 0.32 fixed-point fraction,
  // bit-reversed: its direction numbers 1 << 31, v ^ (v >> 1), ... reversed.
  static uint32_t sobolSecondReversed(uint32_t i) {
    uint32_t r = 0;
    for (uint32_t v = 1u; i != 0; i >>= 1, v ^= v << 1)
      if (i & 1u) r ^= v;
    return r;
  }
  // Burley 2020's hash form of Laine and Karras's nested uniform scramble, on reversed bits.
  static uint32_t scramble(uint32_t x, uint32_t seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
  }
  static float toUnit(uint32_t v) { return float(v >> 8) * (1.0f / 16777216.0f); }

  uint32_t base_;
  uint32_t seedX_, seedY_;
};

// A jittered grid for the refined gather's extra rays: `count` points on a gx × gy grid (gx·gy
// = count, gx ≥ gy, as square as count allows), one jittered point per cell.
struct JitteredGrid {
  uint32_t gx = 1, gy = 1;
  explicit JitteredGrid(uint32_t count) {
    gy = uint32_t(std::sqrt(double(count)));
    while (gy > 1 && count % gy != 0) --gy;
    gx = std::max(1u, count / gy);
  }
  glm::vec2 point(Rng& rng, uint32_t index) const {
    const glm::vec2 u = rng.next2();
    return {(float(index % gx) + u.x) / float(gx), (float((index / gx) % gy) + u.y) / float(gy)};
  }

  // The same points for index 0, 1, 2, ... in turn, without point()'s integer divisions (two
  // per ray, a measurable share of generating a gather ray): next() is point(rng, i) for the
  // i-th call.
  class Walk {
   public:
    explicit Walk(const JitteredGrid& grid) : grid_(grid) {}
    glm::vec2 next(Rng& rng) {
      const glm::vec2 u = rng.next2();
      const glm::vec2 p{(float(x_) + u.x) / float(grid_.gx), (float(y_) + u.y) / float(grid_.gy)};
      step();
      return p;
    }

   private:
    void step() {
      if (++x_ < grid_.gx) return;
      x_ = 0;
      if (++y_ == grid_.gy) y_ = 0;
    }
    const JitteredGrid& grid_;
    uint32_t x_ = 0, y_ = 0;  // index % gx, (index / gx) % gy
  };
};

// Points in [0,1)² reordered for tracing: row by row over JitteredGrid's cells for their count,
// so consecutive rays leave in neighbouring directions. Embree traces a stream of coherent rays
// markedly faster; in the Sobol' order each point lands far from the last, which cost the
// gather a third of its ray rate on Sponza.
inline void coherentOrder(std::vector<glm::vec2>& points) {
  const uint32_t n = uint32_t(points.size());
  if (n == 0) return;
  const JitteredGrid grid(n);  // its cells
  const uint32_t gx = grid.gx, gy = grid.gy;
  auto key = [&](glm::vec2 p) {
    const uint32_t x = std::min(gx - 1, uint32_t(p.x * float(gx)));
    const uint32_t y = std::min(gy - 1, uint32_t(p.y * float(gy)));
    return uint64_t(y) * gx + x;
  };
  // A net of n points holds one in each cell: placed straight into its slot. Otherwise sorted.
  thread_local std::vector<glm::vec2> placed;
  thread_local std::vector<uint8_t> taken;
  placed.resize(n);
  taken.assign(n, 0);
  bool net = true;
  for (uint32_t i = 0; i < n && net; ++i) {
    const uint64_t k = key(points[i]);
    net = k < n && !taken[k];
    if (net) placed[k] = points[i], taken[k] = 1;
  }
  if (net) {
    points.swap(placed);
    return;
  }
  std::stable_sort(points.begin(), points.end(), [&](glm::vec2 a, glm::vec2 b) {
    const uint64_t ka = key(a), kb = key(b);
    return ka != kb ? ka < kb : a.x < b.x;
  });
}

// cos and sin of 2π·t for t in [0, 1): a minimax polynomial on an octant (|error| < 4e-7, as
// good as float sinf), five times cheaper than sincosf; sampling calls it for every ray.
inline void sinCosTurns(float t, float* s, float* c) {
  // Reduce to x in [-1/8, 1/8] turns around the nearest quarter turn q.
  const float q = std::floor(t * 4.0f + 0.5f);
  const float x = (t - q * 0.25f) * (2.0f * kPi);
  const float x2 = x * x;
  const float sx = x * (1.0f + x2 * (-1.6666667e-1f + x2 * (8.3333310e-3f + x2 * -1.9840874e-4f)));
  const float cx = 1.0f + x2 * (-0.5f + x2 * (4.1666638e-2f + x2 * (-1.3888378e-3f + x2 * 2.4760495e-5f)));
  switch (int(q) & 3) {
    case 0: *s = sx; *c = cx; break;
    case 1: *s = cx; *c = -sx; break;
    case 2: *s = -sx; *c = -cx; break;
    default: *s = -cx; *c = sx; break;
  }
}

// Cosine-weighted direction about +Z (pdf cosθ/π).
inline glm::vec3 cosineHemisphere(glm::vec2 u) {
  const float r = std::sqrt(u.x);
  float s, c;
  sinCosTurns(u.y, &s, &c);
  return {r * c, r * s, std::sqrt(std::max(0.0f, 1.0f - u.x))};
}

// Uniform direction in the cone of half-angle acos(cosMax) about +Z.
inline glm::vec3 uniformCone(glm::vec2 u, float cosMax) {
  const float cosT = 1.0f - u.x * (1.0f - cosMax);
  const float sinT = std::sqrt(std::max(0.0f, 1.0f - cosT * cosT));
  float s, c;
  sinCosTurns(u.y, &s, &c);
  return {sinT * c, sinT * s, cosT};
}

// Uniform point in the unit disk (concentric-free polar form; uniform in area).
inline glm::vec2 uniformDisk(glm::vec2 u) {
  const float r = std::sqrt(u.x);
  float s, c;
  sinCosTurns(u.y, &s, &c);
  return {r * c, r * s};
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

// Real SH basis, bands 0..2, in world axes: the runtime's one definition (runtime::shBasis,
// afterglow/runtime/probe_sh.h), shared with the light probes.
using runtime::shBasis;

}  // namespace afterglow::baker::sampling
