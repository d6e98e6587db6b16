#include "afterglow/runtime/reflection_prefilter.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>

#include "afterglow/core/math.h"
#include "afterglow/runtime/prefilter_plan.h"

namespace afterglow::runtime {

namespace {

// Křivánek & Colbert's bias: read one level blurrier than the sample's footprint, which hides
// the footprint's mismatch with the box filter of the mip chain (their "+1").
constexpr float kLodBias = 1.0f;

// Van der Corput radical inverse in base 2: the second Hammersley coordinate.
float radicalInverse(uint32_t bits) {
  bits = (bits << 16u) | (bits >> 16u);
  bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
  bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
  bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
  bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
  return float(bits) * 2.3283064365386963e-10f;  // / 2^32
}

// Point i of an n-point Hammersley set in [0, 1)²; the first coordinate at the midpoints
// (i + 0.5)/n so no sample sits exactly on the lobe's axis or rim.
glm::vec2 hammersley(int i, int n) {
  return {(float(i) + 0.5f) / float(n), radicalInverse(uint32_t(i))};
}

// GGX's D at cos θ_h for α (not perceptual roughness).
float ggxD(float nDotH, float alpha) {
  const float a2 = alpha * alpha;
  const float d = nDotH * nDotH * (a2 - 1.0f) + 1.0f;
  return a2 / (kPi * d * d);
}

// cos θ_h of GGX half-vector sample ξ (the inverse of D's cosine-weighted CDF).
float ggxCosTheta(float xi, float alpha) {
  const float a2 = alpha * alpha;
  return std::sqrt((1.0f - xi) / (1.0f + (a2 - 1.0f) * xi));
}

// Smith's height-correlated G2 / (4 (n·l)(n·v)).
float visibilitySmithGgxCorrelated(float nDotV, float nDotL, float alpha) {
  const float a2 = alpha * alpha;
  const float lambdaV = nDotL * std::sqrt(nDotV * nDotV * (1.0f - a2) + a2);
  const float lambdaL = nDotV * std::sqrt(nDotL * nDotL * (1.0f - a2) + a2);
  return 0.5f / (lambdaV + lambdaL);
}

// A GGX half vector (in the frame of n = +z) drawn from the distribution of normals visible
// from v, with density G1(v) D(h) (v·h)⁺ / (n·v) (Heitz 2018, "Sampling the GGX Distribution of
// Visible Normals"): stretch v to the α = 1 configuration, sample the projected hemisphere
// there (a disk, its far half squeezed by how much of it v sees), and unstretch.
glm::vec3 sampleVisibleNormal(glm::vec3 v, float alpha, glm::vec2 xi) {
  const glm::vec3 vs = glm::normalize(glm::vec3(alpha * v.x, alpha * v.y, v.z));
  const float lengthSq = vs.x * vs.x + vs.y * vs.y;
  const glm::vec3 t1 = lengthSq > 0.0f ? glm::vec3(-vs.y, vs.x, 0.0f) / std::sqrt(lengthSq)
                                       : glm::vec3(1.0f, 0.0f, 0.0f);
  const glm::vec3 t2 = glm::cross(vs, t1);
  const float radius = std::sqrt(xi.x);
  const float phi = 2.0f * kPi * xi.y;
  const float p1 = radius * std::cos(phi);
  const float squeeze = 0.5f * (1.0f + vs.z);
  const float p2 =
      (1.0f - squeeze) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + squeeze * radius * std::sin(phi);
  const glm::vec3 ns = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vs;
  const glm::vec3 h(alpha * ns.x, alpha * ns.y, std::max(ns.z, 0.0f));
  const float length = glm::length(h);
  return length > 0.0f ? h / length : glm::vec3(0.0f, 0.0f, 1.0f);
}

// An orthonormal frame (t, b, n) around unit n, continuous except across n.z = 0's sign
// (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
void frameAround(glm::vec3 n, glm::vec3& t, glm::vec3& b) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float c = n.x * n.y * a;
  t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  b = glm::vec3(c, sign + n.y * n.y * a, -n.y);
}

// The next level of a mip chain: each texel of the finer level goes, with its solid angle as
// weight, to the coarser texel holding its centre (2×2 texels for even sizes).
Cubemap downsample(const Cubemap& fine) {
  const int n = fine.size;
  const int m = std::max(1, n / 2);
  Cubemap coarse = makeCubemap(m);
  std::vector<float> omega(size_t(n) * size_t(n));
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) omega[size_t(y * n + x)] = cubemapTexelSolidAngle(x, y, n);
  std::vector<float> weight(size_t(m) * size_t(m), 0.0f);
  for (int y = 0; y < n; ++y) {
    const int cy = std::min(m - 1, (2 * y + 1) * m / (2 * n));
    for (int x = 0; x < n; ++x) {
      const int cx = std::min(m - 1, (2 * x + 1) * m / (2 * n));
      weight[size_t(cy * m + cx)] += omega[size_t(y * n + x)];
    }
  }
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      const int cy = std::min(m - 1, (2 * y + 1) * m / (2 * n));
      for (int x = 0; x < n; ++x) {
        const int cx = std::min(m - 1, (2 * x + 1) * m / (2 * n));
        coarse.at(face, cx, cy) += fine.at(face, x, y) * omega[size_t(y * n + x)];
      }
    }
    for (int y = 0; y < m; ++y)
      for (int x = 0; x < m; ++x) coarse.at(face, x, y) /= weight[size_t(y * m + x)];
  }
  return coarse;
}

// The source and its coarser levels down to 1 × 1.
std::vector<Cubemap> mipChain(const Cubemap& source) {
  std::vector<Cubemap> chain{source};
  while (chain.back().size > 1) chain.push_back(downsample(chain.back()));
  return chain;
}

// The chain read at fractional level `lod` (clamped to the chain): bilinear in the two levels
// around it, blended linearly.
glm::vec3 sampleTrilinear(const std::vector<Cubemap>& chain, glm::vec3 dir, float lod) {
  const float top = float(chain.size() - 1);
  lod = std::clamp(lod, 0.0f, top);
  const int level = int(lod);
  const float f = lod - float(level);
  const glm::vec3 a = sampleCubemap(chain[size_t(level)], dir);
  if (f <= 0.0f || level + 1 >= int(chain.size())) return a;
  return glm::mix(a, sampleCubemap(chain[size_t(level + 1)], dir), f);
}

// r = 0: the source at the resolution of outSize.
Cubemap resample(const std::vector<Cubemap>& chain, int outSize) {
  const Cubemap& source = chain.front();
  if (outSize == source.size) return source;
  Cubemap out = makeCubemap(outSize);
  const float lod = std::max(0.0f, std::log2(float(source.size) / float(outSize)));
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < outSize; ++y)
      for (int x = 0; x < outSize; ++x)
        out.at(face, x, y) =
            sampleTrilinear(chain, cubemapTexelDirection(face, x, y, outSize), lod);
  return out;
}

// One GGX sample in the frame of n = v: the reflected direction's local coordinates, its
// weight n·l, and the part of its mip level that does not depend on where it lands.
struct LobeSample {
  glm::vec3 l;        // (t, b, n) components
  float nDotL;
  float halfLog2Omega;  // 0.5 · log2(1 / (samples · p(l)))
};

std::vector<LobeSample> lobeSamples(float alpha, int samples) {
  std::vector<LobeSample> out;
  out.reserve(size_t(samples));
  for (int i = 0; i < samples; ++i) {
    const glm::vec2 xi = hammersley(i, samples);
    const float cosTheta = ggxCosTheta(xi.x, alpha);
    const float sinTheta = std::sqrt(std::max(0.0f, 1.0f - cosTheta * cosTheta));
    const float phi = 2.0f * kPi * xi.y;
    const glm::vec3 h(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta);
    // l = reflect(−v, h) with v = n = (0, 0, 1): 2 (v·h) h − v.
    const glm::vec3 l = 2.0f * cosTheta * h - glm::vec3(0.0f, 0.0f, 1.0f);
    if (l.z <= 0.0f) continue;
    // p(l) = D(h) (n·h) / (4 (v·h)) = D(h) / 4 since n = v.
    const float pdf = 0.25f * ggxD(cosTheta, alpha);
    out.push_back({l, l.z, -0.5f * std::log2(float(samples) * pdf)});
  }
  return out;
}

Cubemap prefilterFromChain(const std::vector<Cubemap>& chain, float perceptualRoughness,
                           int outSize, int samples) {
  if (!(perceptualRoughness > 0.0f) || samples <= 0) return resample(chain, outSize);
  const float r = std::min(perceptualRoughness, 1.0f);
  const float alpha = r * r;
  const std::vector<LobeSample> lobe = lobeSamples(alpha, samples);
  const float sourceSize = float(chain.front().size);
  // A source texel at the face plane point of direction l (unit) subtends, to first order,
  // its area (2/size)² times the major component |l|_max cubed (the 1/r² and cos terms), up
  // to 5.2 times less at a cube corner than at a face centre; the local value, not the mean
  // 4π/(6 size²), keeps the blur the footprint's everywhere.
  const float halfLog2TexelArea = std::log2(2.0f / sourceSize);

  Cubemap out = makeCubemap(outSize);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < outSize; ++y) {
      for (int x = 0; x < outSize; ++x) {
        const glm::vec3 n = cubemapTexelDirection(face, x, y, outSize);
        glm::vec3 t, b;
        frameAround(n, t, b);
        // Double sums: a constant environment must come out constant to float precision.
        glm::dvec3 sum(0.0);
        double weight = 0.0;
        for (const LobeSample& s : lobe) {
          const glm::vec3 l = s.l.x * t + s.l.y * b + s.l.z * n;
          const glm::vec3 m = glm::abs(l);
          const float major = std::max(m.x, std::max(m.y, m.z));
          // lod = 0.5 log2(Ω_sample / Ω_texel) + bias, Ω_texel = (2/size)² major³.
          const float lod =
              s.halfLog2Omega - halfLog2TexelArea - 1.5f * std::log2(major) + kLodBias;
          sum += glm::dvec3(sampleTrilinear(chain, l, lod)) * double(s.nDotL);
          weight += double(s.nDotL);
        }
        out.at(face, x, y) =
            weight > 0.0 ? glm::vec3(sum / weight) : sampleTrilinear(chain, n, 0.0f);
      }
    }
  }
  return out;
}

}  // namespace

float mipOfRoughness(float perceptualRoughness, int mipCount) {
  const float r = std::clamp(perceptualRoughness, 0.0f, 1.0f);
  return r * (1.7f - 0.7f * r) * float(std::max(mipCount - 1, 0));
}

float roughnessOfMip(float mip, int mipCount) {
  if (mipCount <= 1) return 0.0f;
  const float m = std::clamp(mip / float(mipCount - 1), 0.0f, 1.0f);
  // The smaller root of 0.7 r² − 1.7 r + m = 0; the larger is > 1 for every m ∈ [0, 1].
  return std::min(1.0f, (1.7f - std::sqrt(std::max(0.0f, 2.89f - 2.8f * m))) / 1.4f);
}

Cubemap prefilterGgx(const Cubemap& source, float perceptualRoughness, int outSize,
                     int samples) {
  if (source.size <= 0 || outSize <= 0) return Cubemap{};
  return prefilterFromChain(mipChain(source), perceptualRoughness, outSize, samples);
}

std::vector<Cubemap> prefilterChain(const Cubemap& source, int mipCount, int samples) {
  std::vector<Cubemap> out;
  if (source.size <= 0 || mipCount <= 0) return out;
  if (samples <= 0) {
    const std::shared_ptr<const PrefilterPlan> plan = sharedPrefilterPlan(source.size, mipCount);
    if (plan) return plan->prefilter(source);
    samples = kPrefilterSamples;
  }
  const std::vector<Cubemap> chain = mipChain(source);
  out.reserve(size_t(mipCount));
  for (int m = 0; m < mipCount; ++m)
    out.push_back(prefilterFromChain(chain, roughnessOfMip(float(m), mipCount),
                                     std::max(1, source.size >> m), samples));
  return out;
}

glm::vec2 integrateDfg(float nDotV, float perceptualRoughness, int samples) {
  if (samples <= 0) return glm::vec2(0.0f);
  nDotV = std::clamp(nDotV, 1e-4f, 1.0f);
  const float r = std::clamp(perceptualRoughness, 0.0f, 1.0f);
  const float alpha = r * r;
  const float a2 = alpha * alpha;
  const glm::vec3 v(std::sqrt(1.0f - nDotV * nDotV), 0.0f, nDotV);
  // 2 (n·v) / G1(v) for Smith's GGX masking, G1(v) = 2 (n·v) / ((n·v) + √(α² + (1 − α²)(n·v)²)).
  const float twoNdotVOverG1 = nDotV + std::sqrt(a2 + (1.0f - a2) * nDotV * nDotV);
  double scale = 0.0;
  double bias = 0.0;
  for (int i = 0; i < samples; ++i) {
    const glm::vec3 h = sampleVisibleNormal(v, alpha, hammersley(i, samples));
    const float vDotH = glm::dot(v, h);
    const float nDotL = 2.0f * vDotH * h.z - nDotV;  // (2 (v·h) h − v)·n
    if (nDotL <= 0.0f || vDotH <= 0.0f) continue;
    // f (n·l) / p(l) with p(l) = G1(v) D (v·h)⁺ / (n·v) / (4 (v·h)): D cancels and leaves
    // F · G2 / G1(v) = F · 4 Vis (n·l)(n·v) / G1(v), at most F.
    const float g = 2.0f * visibilitySmithGgxCorrelated(nDotV, nDotL, alpha) * nDotL *
                    twoNdotVOverG1;
    const float fc = std::pow(1.0f - vDotH, 5.0f);
    scale += double(g * (1.0f - fc));
    bias += double(g * fc);
  }
  return glm::vec2(float(scale / samples), float(bias / samples));
}

std::vector<glm::vec2> dfgTable(int size, int samples) {
  std::vector<glm::vec2> table;
  if (size <= 0) return table;
  table.reserve(size_t(size) * size_t(size));
  for (int row = 0; row < size; ++row)
    for (int column = 0; column < size; ++column)
      table.push_back(integrateDfg((float(column) + 0.5f) / float(size),
                                   (float(row) + 0.5f) / float(size), samples));
  return table;
}

}  // namespace afterglow::runtime
