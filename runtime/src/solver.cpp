#include "afterglow/runtime/solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#include <xmmintrin.h>
#define AFTERGLOW_SSE2 1
#endif

namespace afterglow::runtime {

namespace {

constexpr size_t kAhead = 16;    // links: how far ahead the bounce prefetches cluster values

glm::vec3 evalSky(const glm::vec3 sh[kShCount], const float* transfer) {
  glm::vec3 sum(0.0f);
  for (int i = 0; i < kShCount; ++i) sum += sh[i] * transfer[i];
  return sum;
}

// Half to float for normal and subnormal halves (the sky transfer holds no Inf or NaN): the
// bits shifted into a float's place are the value × 2^-112, rescaled by one multiply.
inline float halfBits(uint16_t h) {
  const uint32_t bits = uint32_t(h & 0x7fffu) << 13;
  float f;
  std::memcpy(&f, &bits, 4);
  f *= 5.192296858534828e+33f;  // 2^112
  return (h & 0x8000u) ? -f : f;
}

glm::vec3 sourceScale(const TransportData& data, const Source& s) {
  if (!s.enabled) return glm::vec3(0.0f);
  if (s.kind == SourceKind::Emissive) return data.materials[s.material].emission;
  return s.color * s.intensity;
}

// Σ weight[k] · x[column[k]] over a row of a SparseMatrix of vec4 values.
inline glm::vec4 mixRow(const SparseMatrix& m, size_t row, const glm::vec4* x) {
  glm::vec4 sum(0.0f);
  for (uint32_t k = m.rowStart[row]; k < m.rowStart[row + 1]; ++k) sum += m.weight[k] * x[m.column[k]];
  return sum;
}

}  // namespace

glm::vec3 boostAlbedo(glm::vec3 albedo, float boost) {
  if (boost <= 1.0f) return albedo;
  glm::vec3 a = glm::clamp(albedo, glm::vec3(0.0f), glm::vec3(1.0f));
  return glm::pow(a, glm::vec3(1.0f / boost));
}

void constantSkySh(glm::vec3 radiance, glm::vec3 sh[kShCount]) {
  // Y00 = 1 / (2 sqrt(pi)); projecting a constant L gives L * sqrt(4 pi) * ... = L * 2 sqrt(pi).
  for (int i = 0; i < kShCount; ++i) sh[i] = glm::vec3(0.0f);
  sh[0] = radiance * (2.0f * std::sqrt(3.14159265358979f));
}

Solver::Solver(const TransportData& data) : data_(data) {
  const size_t clusters = data.clusterCount, rows = data.links.rows();
  albedo_.resize(clusters);
  clusterDirect_.resize(clusters);
  reflected_.assign(clusters, glm::vec3(0.0f));
  reflected4_.assign(clusters, glm::vec4(0.0f));
  gathered_.assign(rows, glm::vec4(0.0f));
  filtered_.assign(data.gatherPointCount, glm::vec4(0.0f));
  scratch_.assign(data.gatherPointCount, glm::vec4(0.0f));
  blockChange_.assign((clusters + kBlock - 1) / kBlock, 0.0f);
  sourceScale_.resize(data.sources.size());
  prepare();
}

void Solver::prepare() {
  const uint32_t n = data_.clusterCount;
  for (size_t i = 0; i < data_.sources.size(); ++i) sourceScale_[i] = sourceScale(data_, data_.sources[i]);
  for (uint32_t c = 0; c < n; ++c) {
    const MaterialParams& m = data_.materials[data_.clusterMaterial[c]];
    albedo_[c] = boostAlbedo(m.albedo * data_.clusterAlbedoTexture[c], data_.albedoBoost);
    clusterDirect_[c] =
        data_.clusterSky.empty() ? glm::vec3(0.0f) : evalSky(data_.skySh, &data_.clusterSky[size_t(c) * kShCount]);
  }
  for (size_t i = 0; i < data_.sources.size(); ++i) {
    const Source& s = data_.sources[i];
    glm::vec3 scale = sourceScale_[i];
    if (s.kind == SourceKind::Light) scale *= s.bounceIntensity;
    if (scale == glm::vec3(0.0f) || s.clusterTransfer.empty()) continue;
    for (uint32_t c = 0; c < n; ++c) clusterDirect_[c] += scale * s.clusterTransfer[c];
  }
}

void Solver::reset() {
  std::fill(reflected_.begin(), reflected_.end(), glm::vec3(0.0f));
  std::fill(reflected4_.begin(), reflected4_.end(), glm::vec4(0.0f));
  std::fill(gathered_.begin(), gathered_.end(), glm::vec4(0.0f));
}


void Solver::gatherRows() {
  const SparseLinks& links = data_.links;
  const uint32_t* rowStart = links.rowStart.data();
  const uint32_t* target = links.target.data();
  const uint16_t* weight = links.weight.data();
  const glm::vec4* r = reflected4_.data();
  const size_t total = links.target.size();
  forBlocks(links.rows(), [&](size_t first, size_t last) {
    for (size_t row = first; row < last; ++row) {
      const uint32_t begin = rowStart[row], end = rowStart[row + 1];
#ifdef AFTERGLOW_SSE2
      // The hot loop of a bounce: two accumulators, R padded to 16 bytes for aligned loads.
      __m128 a0 = _mm_setzero_ps(), a1 = _mm_setzero_ps();
      uint32_t k = begin;
      for (; k + 2 <= end; k += 2) {
        // R is too big for the cache and the targets hop around: fetch a few links ahead
        // (across the end of the row too; the links run on into the next row).
        if (k + kAhead + 1 < total) {
          _mm_prefetch(reinterpret_cast<const char*>(&r[target[k + kAhead]]), _MM_HINT_T0);
          _mm_prefetch(reinterpret_cast<const char*>(&r[target[k + kAhead + 1]]), _MM_HINT_T0);
        }
        a0 = _mm_add_ps(a0, _mm_mul_ps(_mm_set1_ps(float(weight[k])),
                                       _mm_load_ps(&r[target[k]].x)));
        a1 = _mm_add_ps(a1, _mm_mul_ps(_mm_set1_ps(float(weight[k + 1])),
                                       _mm_load_ps(&r[target[k + 1]].x)));
      }
      if (k < end)
        a0 = _mm_add_ps(a0, _mm_mul_ps(_mm_set1_ps(float(weight[k])), _mm_load_ps(&r[target[k]].x)));
      _mm_store_ps(&gathered_[row].x,
                   _mm_mul_ps(_mm_add_ps(a0, a1), _mm_set1_ps(links.rowScale[row])));
#else
      glm::vec4 sum(0.0f);
      for (uint32_t k = begin; k < end; ++k) sum += float(weight[k]) * r[target[k]];
      gathered_[row] = sum * links.rowScale[row];
#endif
    }
  });
}

float Solver::iterate() {
  const SparseMatrix& take = data_.clusterGather;
  forBlocks(data_.clusterCount, [&](size_t first, size_t last) {
    float maxChange = 0.0f;
    for (size_t c = first; c < last; ++c) {
      const glm::vec4 in = mixRow(take, c, gathered_.data());
      const glm::vec3 r = albedo_[c] * (clusterDirect_[c] + glm::vec3(in));
      const glm::vec3 diff = glm::abs(r - reflected_[c]);
      const float mag = std::max({r.x, r.y, r.z});
      const float change = std::max({diff.x, diff.y, diff.z});
      if (mag > 1e-20f) maxChange = std::max(maxChange, change / mag);
      reflected_[c] = r;
      reflected4_[c] = glm::vec4(r, 0.0f);
    }
    blockChange_[first / kBlock] = maxChange;
  });
  gatherRows();
  float maxChange = 0.0f;
  for (float c : blockChange_) maxChange = std::max(maxChange, c);
  return maxChange;
}

int Solver::solve(const SolveOptions& options) {
  const int limit = options.maxBounces > 0 ? options.maxBounces : 1000;
  int passes = 0;
  while (passes < limit) {
    const float change = iterate();
    ++passes;
    if (options.maxBounces <= 0 && change < options.tolerance) break;
  }
  return passes;
}

void Solver::skyTexels(glm::vec3* sky) const {
  const bool hasSky = !data_.texelSky.empty();
  forBlocks(data_.texelCount, [&](size_t first, size_t last) {
    for (size_t t = first; t < last; ++t) {
      glm::vec3 s(0.0f);
      if (hasSky) {
        const uint16_t* transfer = &data_.texelSky[t * kShCount];
        for (int i = 0; i < kShCount; ++i) s += data_.skySh[i] * halfBits(transfer[i]);
      }
      sky[t] = s;
    }
  });
}

void Solver::directTexels(glm::vec3* direct, bool withSky) const {
  if (withSky) skyTexels(direct);
  forBlocks(data_.texelCount, [&](size_t first, size_t last) {
    if (!withSky) std::fill(direct + first, direct + last, glm::vec3(0.0f));
    for (size_t i = 0; i < data_.sources.size(); ++i) {
      const std::vector<float>& transfer = data_.sources[i].texelTransfer;
      const glm::vec3 scale = sourceScale_[i];
      if (transfer.empty() || scale == glm::vec3(0.0f)) continue;
      for (size_t t = first; t < last; ++t) direct[t] += scale * transfer[t];
    }
  });
}

void Solver::indirectTexels(glm::vec3* indirect) const {
  // Smoothing passes over the gather points, then each texel's mix of them.
  const size_t points = data_.gatherPointCount;
  const glm::vec4* source = gathered_.data();
  if (data_.filterPasses > 0 && data_.pointFilter.rows() == points) {
    std::copy(gathered_.begin(), gathered_.begin() + long(points), filtered_.begin());
    for (int pass = 0; pass < data_.filterPasses; ++pass) {
      forBlocks(points, [&](size_t first, size_t last) {
        for (size_t p = first; p < last; ++p) scratch_[p] = mixRow(data_.pointFilter, p, filtered_.data());
      });
      filtered_.swap(scratch_);
    }
    source = filtered_.data();
  }
  const float scale = data_.indirectIntensity;
  forBlocks(data_.texelCount, [&](size_t first, size_t last) {
    for (size_t t = first; t < last; ++t)
      indirect[t] = scale * glm::vec3(mixRow(data_.texelGather, t, source));
  });
}

void Solver::gatherTexels(std::vector<glm::vec3>& direct, std::vector<glm::vec3>& indirect) const {
  direct.resize(data_.texelCount);
  indirect.resize(data_.texelCount);
  directTexels(direct.data());
  indirectTexels(indirect.data());
}

void Solver::gatherTexels(std::vector<glm::vec3>& texels) const {
  std::vector<glm::vec3> indirect;
  gatherTexels(texels, indirect);
  for (size_t t = 0; t < texels.size(); ++t) texels[t] += indirect[t];
}

}  // namespace afterglow::runtime
