#include "afterglow/runtime/solver.h"

#include <algorithm>
#include <cmath>

namespace afterglow::runtime {

namespace {

// Unity's albedo boost: pulls albedo toward white as the boost grows (1 leaves it unchanged).
glm::vec3 boostAlbedo(glm::vec3 albedo, float boost) {
  if (boost <= 1.0f) return albedo;
  glm::vec3 a = glm::clamp(albedo, glm::vec3(0.0f), glm::vec3(1.0f));
  return glm::pow(a, glm::vec3(1.0f / boost));
}

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

void constantSkySh(glm::vec3 radiance, glm::vec3 sh[kShCount]) {
  // Y00 = 1 / (2 sqrt(pi)); projecting a constant L gives L * sqrt(4 pi) * ... = L * 2 sqrt(pi).
  for (int i = 0; i < kShCount; ++i) sh[i] = glm::vec3(0.0f);
  sh[0] = radiance * (2.0f * std::sqrt(3.14159265358979f));
}

Solver::Solver(const TransportData& data) : data_(data) {
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

float Solver::iterate() {
  const SparseLinks& links = data_.clusterLinks;
  float maxChange = 0.0f;
  for (uint32_t c = 0; c < data_.clusterCount; ++c) {
    glm::vec3 gathered(0.0f);
    for (uint32_t k = links.rowStart[c]; k < links.rowStart[c + 1]; ++k)
      gathered += links.weight[k] * reflected_[links.target[k]];
    glm::vec3 r = albedo_[c] * (clusterDirect_[c] + gathered);
    glm::vec3 diff = glm::abs(r - reflected_[c]);
    float mag = std::max({r.x, r.y, r.z});
    float change = std::max({diff.x, diff.y, diff.z});
    if (mag > 1e-20f) maxChange = std::max(maxChange, change / mag);
    next_[c] = r;
  }
  reflected_.swap(next_);
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
  const uint32_t n = data_.texelCount;
  texels.assign(n, glm::vec3(0.0f));
  const SparseLinks& links = data_.texelLinks;
  const bool hasSky = !data_.texelSky.empty();
  for (uint32_t t = 0; t < n; ++t) {
    glm::vec3 indirect(0.0f);
    for (uint32_t k = links.rowStart[t]; k < links.rowStart[t + 1]; ++k)
      indirect += links.weight[k] * reflected_[links.target[k]];
    glm::vec3 v = data_.indirectIntensity * indirect;
    if (hasSky) v += evalSky(data_.skySh, &data_.texelSky[size_t(t) * kShCount]);
    texels[t] = v;
  }
  for (const Source& s : data_.sources) {
    glm::vec3 scale = sourceScale(data_, s);
    if (scale == glm::vec3(0.0f) || s.texelTransfer.empty()) continue;
    for (uint32_t t = 0; t < n; ++t) texels[t] += scale * s.texelTransfer[t];
  }
}

}  // namespace afterglow::runtime
