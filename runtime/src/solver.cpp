#include "afterglow/runtime/solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace afterglow::runtime {

namespace {

glm::vec3 evalSky(const glm::vec3 sh[kShCount], const float* transfer) {
  glm::vec3 sum(0.0f);
  for (int i = 0; i < kShCount; ++i) sum += sh[i] * transfer[i];
  return sum;
}

glm::vec3 sourceScale(const TransportData& data, const Source& s) {
  if (!s.enabled) return glm::vec3(0.0f);
  if (s.kind == SourceKind::Emissive) return data.materials[s.material].emission;
  return s.color * s.intensity;
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
  if (data.indirectFilterPasses > 0 && data.texelNeighbours.size() == data.texelCount) {
    // Where each texel sits: its atlas and pixel, to find its neighbours.
    std::vector<uint32_t> where(data.texelCount, kNoTexel);
    std::vector<uint16_t> atlasOf(data.texelCount, 0);
    for (size_t a = 0; a < data.atlases.size(); ++a) {
      const AtlasLayout& layout = data.atlases[a];
      for (size_t p = 0; p < layout.texelOfPixel.size(); ++p) {
        const uint32_t t = layout.texelOfPixel[p];
        if (t >= data.texelCount) continue;
        where[t] = uint32_t(p);
        atlasOf[t] = uint16_t(a);
      }
    }
    filterStart_.push_back(0);
    for (uint32_t t = 0; t < data.texelCount; ++t) {
      const uint8_t mask = data.texelNeighbours[t];
      if (mask != 0 && where[t] != kNoTexel) {
        const AtlasLayout& layout = data.atlases[atlasOf[t]];
        const int x = int(where[t] % uint32_t(layout.width)), y = int(where[t] / uint32_t(layout.width));
        const size_t first = filterTexel_.size();
        float sum = 4.0f;
        filterTexel_.push_back(t);
        filterWeight_.push_back(4.0f);
        for (int k = 0; k < 8; ++k) {
          if (!(mask & (1u << k))) continue;
          const int nx = x + kNeighbourOffsets[k][0], ny = y + kNeighbourOffsets[k][1];
          if (nx < 0 || ny < 0 || nx >= layout.width || ny >= layout.height) continue;
          const uint32_t n = layout.texelOfPixel[size_t(ny) * size_t(layout.width) + size_t(nx)];
          if (n >= data.texelCount) continue;
          // Tent: 2 along the axes, 1 on the diagonals.
          const float w = (kNeighbourOffsets[k][0] == 0 || kNeighbourOffsets[k][1] == 0) ? 2.0f : 1.0f;
          filterTexel_.push_back(n);
          filterWeight_.push_back(w);
          sum += w;
        }
        for (size_t i = first; i < filterWeight_.size(); ++i) filterWeight_[i] /= sum;
      }
      filterStart_.push_back(uint32_t(filterTexel_.size()));
    }
    filterScratch_.resize(data.texelCount);
  }
  albedo_.resize(data.clusterCount);
  clusterDirect_.resize(data.clusterCount);
  reflected_.assign(data.clusterCount, glm::vec3(0.0f));
  next_.assign(data.clusterCount, glm::vec3(0.0f));
  prepare();
}

void Solver::prepare() {
  const uint32_t n = data_.clusterCount;
  for (uint32_t c = 0; c < n; ++c) {
    const MaterialParams& m = data_.materials[data_.clusterMaterial[c]];
    albedo_[c] = boostAlbedo(m.albedo * data_.clusterAlbedoTexture[c], data_.albedoBoost);
    glm::vec3 d(0.0f);
    if (!data_.clusterSky.empty()) d += evalSky(data_.skySh, &data_.clusterSky[size_t(c) * kShCount]);
    clusterDirect_[c] = d;
  }
  for (const Source& s : data_.sources) {
    glm::vec3 scale = sourceScale(data_, s);
    if (s.kind == SourceKind::Light) scale *= s.bounceIntensity;
    if (scale == glm::vec3(0.0f) || s.clusterTransfer.empty()) continue;
    for (uint32_t c = 0; c < n; ++c) clusterDirect_[c] += scale * s.clusterTransfer[c];
  }
}

void Solver::reset() { std::fill(reflected_.begin(), reflected_.end(), glm::vec3(0.0f)); }

namespace {
constexpr size_t kBlock = 2048;  // clusters or texels per block of work
}

void Solver::forBlocks(size_t items, const std::function<void(size_t, size_t)>& body) const {
  const size_t blocks = (items + kBlock - 1) / kBlock;
  auto run = [&](size_t begin, size_t end) {
    for (size_t b = begin; b < end; ++b) body(b * kBlock, std::min(items, (b + 1) * kBlock));
  };
  if (parallelFor_ && blocks > 1) parallelFor_(blocks, run);
  else run(0, blocks);
}

float Solver::iterate() {
  const SparseLinks& links = data_.clusterLinks;
  const size_t blocks = (size_t(data_.clusterCount) + kBlock - 1) / kBlock;
  blockChange_.assign(blocks, 0.0f);
  forBlocks(data_.clusterCount, [&](size_t first, size_t last) {
    float maxChange = 0.0f;
    for (size_t c = first; c < last; ++c) {
      glm::vec3 gathered(0.0f);
      for (uint32_t k = links.rowStart[c]; k < links.rowStart[c + 1]; ++k)
        gathered += float(links.weight[k]) * reflected_[links.target[k]];
      gathered *= links.rowScale[c];
      glm::vec3 r = albedo_[c] * (clusterDirect_[c] + gathered);
      glm::vec3 diff = glm::abs(r - reflected_[c]);
      float mag = std::max({r.x, r.y, r.z});
      float change = std::max({diff.x, diff.y, diff.z});
      if (mag > 1e-20f) maxChange = std::max(maxChange, change / mag);
      next_[c] = r;
    }
    blockChange_[first / kBlock] = maxChange;
  });
  reflected_.swap(next_);
  float maxChange = 0.0f;
  for (float c : blockChange_) maxChange = std::max(maxChange, c);
  return maxChange;
}

int Solver::solve(const SolveOptions& options) {
  const int limit = options.maxBounces > 0 ? options.maxBounces : 1000;
  int passes = 0;
  while (passes < limit) {
    float change = iterate();
    ++passes;
    if (options.maxBounces <= 0 && change < options.tolerance) break;
  }
  return passes;
}

void Solver::gatherTexels(std::vector<glm::vec3>& texels) const {
  std::vector<glm::vec3> indirect;
  gatherTexels(texels, indirect);
  for (size_t t = 0; t < texels.size(); ++t) texels[t] += indirect[t];
}

void Solver::gatherTexels(std::vector<glm::vec3>& direct, std::vector<glm::vec3>& indirect) const {
  const uint32_t n = data_.texelCount;
  direct.assign(n, glm::vec3(0.0f));
  indirect.assign(n, glm::vec3(0.0f));
  const SparseLinks& links = data_.texelLinks;
  const bool hasSky = !data_.texelSky.empty();
  std::vector<glm::vec3> scales;
  for (const Source& s : data_.sources) scales.push_back(sourceScale(data_, s));
  forBlocks(n, [&](size_t first, size_t last) {
    for (size_t t = first; t < last; ++t) {
      glm::vec3 sum(0.0f);
      for (uint32_t k = links.rowStart[t]; k < links.rowStart[t + 1]; ++k)
        sum += float(links.weight[k]) * reflected_[links.target[k]];
      indirect[t] = data_.indirectIntensity * links.rowScale[t] * sum;
      glm::vec3 d = hasSky ? evalSky(data_.skySh, &data_.texelSky[t * kShCount]) : glm::vec3(0.0f);
      for (size_t i = 0; i < scales.size(); ++i)
        if (!data_.sources[i].texelTransfer.empty()) d += scales[i] * data_.sources[i].texelTransfer[t];
      direct[t] = d;
    }
  });
  filterIndirect(indirect);
}

void Solver::filterIndirect(std::vector<glm::vec3>& indirect) const {
  if (filterStart_.empty()) return;
  for (int pass = 0; pass < data_.indirectFilterPasses; ++pass) {
    forBlocks(data_.texelCount, [&](size_t first, size_t last) {
      for (size_t t = first; t < last; ++t) {
        const uint32_t begin = filterStart_[t], end = filterStart_[t + 1];
        if (begin == end) {
          filterScratch_[t] = indirect[t];
          continue;
        }
        glm::vec3 sum(0.0f);
        for (uint32_t k = begin; k < end; ++k) sum += filterWeight_[k] * indirect[filterTexel_[k]];
        filterScratch_[t] = sum;
      }
    });
    std::copy(filterScratch_.begin(), filterScratch_.end(), indirect.begin());
  }
}

}  // namespace afterglow::runtime
