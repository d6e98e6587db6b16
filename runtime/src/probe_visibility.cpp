#include "afterglow/runtime/probe_visibility.h"

#include <algorithm>
#include <cmath>

namespace afterglow::runtime {

namespace {

constexpr int kLobePower = 200;  // the filter's lobe: cos^200, 4.8° to half weight
constexpr float kBiasShare = 0.02f;    // of μ
constexpr float kBiasMetres = 0.01f;
constexpr float kLeast = 1e-6f;        // the least visibility a probe keeps

float signOf(float v) { return v >= 0.0f ? 1.0f : -1.0f; }

// A unit direction's point on the map, in texels (texel t covers [u, u + 1) × [v, v + 1)).
glm::vec2 mapPoint(glm::vec3 d) {
  const float l1 = std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
  glm::vec2 p = l1 > 0.0f ? glm::vec2(d.x, d.y) / l1 : glm::vec2(0.0f);
  if (d.z < 0.0f)
    p = glm::vec2((1.0f - std::abs(p.y)) * signOf(p.x), (1.0f - std::abs(p.x)) * signOf(p.y));
  return (p * 0.5f + 0.5f) * float(kProbeDepthSide);
}

}  // namespace

int probeDepthTexel(glm::vec3 d) {
  const glm::vec2 p = mapPoint(d);
  const int u = std::clamp(int(p.x), 0, kProbeDepthSide - 1);
  const int v = std::clamp(int(p.y), 0, kProbeDepthSide - 1);
  return v * kProbeDepthSide + u;
}

glm::vec3 probeDepthTexelDirection(int texel) {
  const glm::vec2 p((float(texel % kProbeDepthSide) + 0.5f) / kProbeDepthSide * 2.0f - 1.0f,
                    (float(texel / kProbeDepthSide) + 0.5f) / kProbeDepthSide * 2.0f - 1.0f);
  glm::vec3 d(p.x, p.y, 1.0f - std::abs(p.x) - std::abs(p.y));
  if (d.z < 0.0f) {
    const glm::vec2 folded((1.0f - std::abs(p.y)) * signOf(p.x), (1.0f - std::abs(p.x)) * signOf(p.y));
    d.x = folded.x;
    d.y = folded.y;
  }
  return glm::normalize(d);
}

ProbeDepthFilter probeDepthFilter(const glm::vec3* directions, size_t rays) {
  ProbeDepthFilter f;
  f.start.push_back(0);
  for (int t = 0; t < kProbeDepthTexels; ++t) {
    const glm::vec3 c = probeDepthTexelDirection(t);
    // The weights relative to the nearest ray's, which so always counts (a texel between
    // sparse rays is never left empty).
    float nearest = -1.0f;
    for (size_t r = 0; r < rays; ++r) nearest = std::max(nearest, glm::dot(c, directions[r]));
    for (size_t r = 0; r < rays; ++r) {
      const float cosine = glm::dot(c, directions[r]);
      if (cosine <= 0.0f || nearest <= 0.0f) continue;
      const float lobe = float(std::pow(double(cosine) / double(nearest), kLobePower));
      if (lobe < 1e-3f) continue;
      f.ray.push_back(uint32_t(r));
      f.weight.push_back(lobe);
    }
    f.start.push_back(uint32_t(f.ray.size()));
  }
  return f;
}

void probeDepthMoments(const ProbeDepthFilter& filter, const float* distances, uint16_t* out) {
  for (int t = 0; t < kProbeDepthTexels; ++t) {
    double w = 0.0, m1 = 0.0, m2 = 0.0;
    for (uint32_t k = filter.start[size_t(t)]; k < filter.start[size_t(t) + 1]; ++k) {
      const double lobe = double(filter.weight[k]);
      const double d = std::min(double(distances[filter.ray[k]]), double(kProbeDepthFar));
      w += lobe;
      m1 += lobe * d;
      m2 += lobe * d * d;
    }
    const double mean = w > 0.0 ? m1 / w : double(kProbeDepthFar);
    const double deviation = w > 0.0 ? std::sqrt(std::max(0.0, m2 / w - mean * mean)) : 0.0;
    out[2 * t] = floatToHalf(float(mean));
    out[2 * t + 1] = floatToHalf(float(std::min(deviation, double(kProbeDepthFar))));
  }
}

float probeVisibility(const uint16_t* depth, glm::vec3 offset) {
  const float d = glm::length(offset);
  if (!(d > 0.0f)) return 1.0f;
  // Bilinear between the four texel centres around the direction (clamped at the map's edge,
  // where the octahedron folds: a texel's worth of error there): the nearest texel alone put
  // a direction up to half a texel (12°) from the rays it read.
  const glm::vec2 p = mapPoint(offset / d) - 0.5f;
  const glm::vec2 f = p - glm::floor(p);
  const int u0 = int(std::floor(p.x)), v0 = int(std::floor(p.y));
  float mean = 0.0f, deviation = 0.0f;
  for (int k = 0; k < 4; ++k) {
    const int u = std::clamp(u0 + (k & 1), 0, kProbeDepthSide - 1);
    const int v = std::clamp(v0 + (k >> 1), 0, kProbeDepthSide - 1);
    const float w = ((k & 1) ? f.x : 1.0f - f.x) * ((k >> 1) ? f.y : 1.0f - f.y);
    const int t = v * kProbeDepthSide + u;
    mean += w * halfToFloat(depth[2 * t]);
    deviation += w * halfToFloat(depth[2 * t + 1]);
  }
  const float beyond = d - mean * (1.0f + kBiasShare) - kBiasMetres;
  if (beyond <= 0.0f) return 1.0f;
  const float variance = std::max(deviation * deviation, 1e-8f);
  const float v = variance / (variance + beyond * beyond);
  return v * v * v;
}

ProbeLocation weighByVisibility(const ProbeLocation& where, const std::vector<glm::vec3>& positions,
                                const std::vector<uint16_t>& depth, glm::vec3 point) {
  if (depth.size() != positions.size() * kProbeDepthValues) return where;
  ProbeLocation out = where;
  float sum = 0.0f;
  for (int k = 0; k < 4; ++k) {
    const int p = where.probes[k];
    if (p < 0 || !(where.weights[k] > 0.0f)) continue;
    const float v = probeVisibility(&depth[size_t(p) * kProbeDepthValues],
                                    point - positions[size_t(p)]);
    out.weights[k] = where.weights[k] * std::max(v, kLeast);
    sum += out.weights[k];
  }
  if (sum > 0.0f) out.weights /= sum;
  return out;
}

}  // namespace afterglow::runtime
