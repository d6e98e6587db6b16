#include "afterglow/runtime/probe_lights.h"

#include <algorithm>
#include <cmath>

#include "afterglow/core/math.h"

namespace afterglow::runtime {

namespace {

constexpr float kY00 = 0.282094791773878f;
constexpr float kY1 = 0.488602511902920f;
// The concentration R where a source starts (and ends) being read as one direction (header).
constexpr float kFirstR = 0.93f, kFullR = 0.99f;

// deringed()'s weight for band l (1 without a window).
float bandWeight(int l, float window) {
  if (!(window > 0.0f)) return 1.0f;
  return float(l) > window ? 0.0f : 0.5f * (1.0f + std::cos(kPi * float(l) / window));
}

}  // namespace

bool concentratedPart(const float sh[kShCount], glm::vec3* direction, float* power) {
  const float flux = sh[0] / kY00;
  const glm::vec3 moment = glm::vec3(sh[3], sh[1], sh[2]) / kY1;
  const float length = glm::length(moment);
  if (!(flux > 0.0f) || !(length > 0.0f) || !std::isfinite(length)) return false;
  const float r = std::min(length / flux, 1.0f);
  const float f = std::clamp((r - kFirstR) / (kFullR - kFirstR), 0.0f, 1.0f);
  if (f == 0.0f) return false;
  *direction = moment / length;
  *power = f * length;
  return true;
}

glm::vec3 lightCorrectionOverPi(const ProbeDirection& light, glm::vec3 normal, float window) {
  const float c = glm::dot(normal, light.direction);
  const float sh = (1.0f + 2.0f * bandWeight(1, window) * c +
                    0.625f * bandWeight(2, window) * (3.0f * c * c - 1.0f)) * 0.25f;
  return light.power * ((std::max(c, 0.0f) - sh) / kPi);
}

std::vector<glm::vec3> directScales(const TransportData& data) {
  std::vector<glm::vec3> out;
  for (const Source& s : data.sources) out.push_back(directScale(data, s));
  return out;
}

size_t probeLightCapacity(const TransportData& data) {
  size_t sources = 0;
  for (const Source& s : data.sources) sources += s.probeTransfer.empty() ? 0 : 1;
  return data.probes.count() * sources;
}

ProbeDirectionList probeLights(const TransportData& data, const std::vector<glm::vec3>& scales) {
  ProbeDirectionList out;
  probeLights(data, scales, out);
  return out;
}

void probeLights(const TransportData& data, const std::vector<glm::vec3>& scales,
                 ProbeDirectionList& out) {
  out.start.clear();
  out.lights.clear();
  const size_t probes = data.probes.count();
  if (probes == 0) return;
  out.start.push_back(0);
  for (size_t p = 0; p < probes; ++p) {
    for (size_t s = 0; s < data.sources.size() && s < scales.size(); ++s) {
      const std::vector<float>& transfer = data.sources[s].probeTransfer;
      if (transfer.size() < (p + 1) * kShCount || scales[s] == glm::vec3(0.0f)) continue;
      ProbeDirection light;
      float unit = 0.0f;
      if (!concentratedPart(&transfer[p * kShCount], &light.direction, &unit)) continue;
      light.power = scales[s] * unit;
      out.lights.push_back(light);
    }
    out.start.push_back(uint32_t(out.lights.size()));
  }
}

glm::vec3 ProbeLighting::irradianceOverPi(glm::vec3 normal, float window) const {
  glm::vec3 e = runtime::irradianceOverPi(sh, normal);
  for (const ProbeDirection& l : lights) e += lightCorrectionOverPi(l, normal, window);
  return e;
}

ProbeLighting mixProbeLighting(const ProbeLocation& where, const std::vector<ShL2>& probeSh,
                               const ProbeDirectionList& lights) {
  ProbeLighting out;
  out.sh = mixProbes(where, probeSh);
  for (int k = 0; k < 4; ++k) {
    const int p = where.probes[k];
    if (p < 0 || where.weights[k] == 0.0f || size_t(p) >= lights.count()) continue;
    for (uint32_t i = lights.start[size_t(p)]; i < lights.start[size_t(p) + 1]; ++i) {
      ProbeDirection l = lights.lights[i];
      l.power *= where.weights[k];
      out.lights.push_back(l);
    }
  }
  return out;
}

}  // namespace afterglow::runtime
