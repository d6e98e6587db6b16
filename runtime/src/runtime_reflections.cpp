// Runtime: the reflection probes' update and reads (runtime.h). The capture passes are
// reflection_capture.h's, in the order solveReflectionProbes runs them, so a full round equals
// the bake.
#include <algorithm>
#include <chrono>

#include "afterglow/core/timer.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/runtime.h"

namespace afterglow::runtime {

void Runtime::runReflectionUnits(int passes, double budgetMs, Clock::time_point callStart,
                                 UpdateStats& stats) {
  const size_t probes = data_.reflections.count();
  if (probes == 0 || passes == 0) return;
  const auto start = std::chrono::steady_clock::now();
  if (reflectionPasses_.empty()) {
    reflectionPasses_.assign(size_t(data_.reflections.bounces) + 1, std::vector<CubemapChain>(probes));
    // Pass p's chains as pass p + 1 reads them ([0] the sky); the last pass is read by none.
    reflectionLights_.assign(size_t(data_.reflections.bounces), std::vector<ProbeLight>(probes + 1));
    reflectionBoxes_ = data_.reflections.boxes();
  }
  bool skyChanged = false;
  if (reflectionSkyStale_) {
    reflectionSky_ = runtime::reflectionChain(skyCubemap(data_.skySh, int(kReflectionSkyResolution)));
    reflectionSkyStale_ = false;
    skyChanged = true;
    if (!reflectionLights_.empty()) {
      const ProbeLight sky = probeLight(reflectionSky_);
      for (std::vector<ProbeLight>& pass : reflectionLights_) pass[0] = sky;
    }
  }
  const size_t units = reflectionPasses_.size() * probes;
  size_t todo = passes < 0 ? units : std::min(units, size_t(passes));
  if (passes < 0) reflectionCursor_ = 0;
  const std::vector<std::vector<glm::vec3>>& atlases = images_[front_];
  std::vector<uint8_t> published(probes, 0);
  double lastUnitMs = 0.0;
  for (; todo > 0; --todo) {
    // The call's budget: stop before a unit that would overrun it (the first always runs).
    if (budgetMs > 0.0 && stats.reflectionPasses > 0 &&
        millisecondsSince(callStart) + lastUnitMs > budgetMs)
      break;
    const auto unitStart = std::chrono::steady_clock::now();
    const size_t pass = reflectionCursor_ / probes, probe = reflectionCursor_ % probes;
    const ReflectionLighting* lighting = nullptr;
    ReflectionLighting light;
    if (pass > 0) {
      light = ReflectionLighting{&reflectionBoxes_, &reflectionLights_[pass - 1], &dfg_, kDfgSize};
      lighting = &light;
      // The static half of the probe's specular lookups, built on its first bounce pass.
      if (reflectionSetups_.size() < probes) reflectionSetups_.resize(probes);
      if (reflectionSetups_[probe].start.empty())
        reflectionSetups_[probe] = prepareReflectionShading(data_, probe, dfg_, kDfgSize);
    }
    CubemapChain& chain = reflectionPasses_[pass][probe];
    chain = runtime::reflectionChain(shadeReflectionCapture(
        data_, probe, atlases, lighting, lighting ? &reflectionSetups_[probe] : nullptr));
    // The next pass reads this chain as it is read (bordered, with its irradiance): made once
    // here rather than by every unit of the next pass.
    if (pass < reflectionLights_.size()) reflectionLights_[pass][probe + 1] = probeLight(chain);
    if (pass + 1 == reflectionPasses_.size()) published[probe] = 1;
    reflectionCursor_ = (reflectionCursor_ + 1) % units;
    ++stats.reflectionPasses;
    lastUnitMs = millisecondsSince(unitStart);
  }
  // Publish the probes whose last pass ran (and the sky when it changed).
  std::vector<std::shared_ptr<const CubemapChain>> fresh(probes + 1);
  if (skyChanged) fresh[0] = std::make_shared<const CubemapChain>(reflectionSky_);
  for (size_t i = 0; i < probes; ++i)
    if (published[i]) fresh[i + 1] = std::make_shared<const CubemapChain>(reflectionPasses_.back()[i]);
  {
    std::lock_guard<std::mutex> lock(outputMutex_);
    for (size_t i = 0; i < fresh.size(); ++i)
      if (fresh[i]) reflectionOut_[i] = std::move(fresh[i]);
  }
  stats.reflectionMilliseconds += millisecondsSince(start);
}

UpdateStats Runtime::updateReflectionProbes(int passes, double budgetMs) {
  std::lock_guard<std::mutex> updateLock(updateMutex_);
  const auto start = std::chrono::steady_clock::now();
  UpdateStats stats;
  runReflectionUnits(passes, budgetMs, start, stats);
  stats.milliseconds = millisecondsSince(start);
  return stats;
}

int Runtime::reflectionProbeCount() const {
  return data_.reflections.count() == 0 ? 0 : int(data_.reflections.count()) + 1;
}

int Runtime::reflectionMipCount() const {
  return reflectionProbeCount() > 0 ? kReflectionMipCount : 0;
}

std::shared_ptr<const CubemapChain> Runtime::publishedChain(int probe) const {
  if (probe < 0 || probe >= reflectionProbeCount()) return nullptr;
  std::lock_guard<std::mutex> lock(outputMutex_);
  return reflectionOut_[size_t(probe)];
}

int Runtime::reflectionFaceSize(int probe, int mip) const {
  if (probe < 0 || probe >= reflectionProbeCount() || mip < 0 || mip >= reflectionMipCount())
    return 0;
  const int size = probe == 0 ? int(kReflectionSkyResolution)
                              : int(data_.reflections.probes[size_t(probe - 1)].resolution);
  return std::max(1, size >> mip);
}

bool Runtime::readCubemap(int probe, int mip, int face, float* rgb) const {
  const int size = reflectionFaceSize(probe, mip);
  if (size == 0 || face < 0 || face >= kCubeFaceCount || !rgb) return false;
  const std::shared_ptr<const CubemapChain> chain = publishedChain(probe);
  const size_t n = size_t(size) * size_t(size);
  if (!chain || size_t(mip) >= chain->size() || (*chain)[size_t(mip)].size != size) {
    std::fill(rgb, rgb + 3 * n, 0.0f);  // before the first update: black
    return true;
  }
  const glm::vec3* texels = (*chain)[size_t(mip)].texels.data() + size_t(face) * n;
  for (size_t k = 0; k < n; ++k) {
    rgb[3 * k] = texels[k].x;
    rgb[3 * k + 1] = texels[k].y;
    rgb[3 * k + 2] = texels[k].z;
  }
  return true;
}

CubemapChain Runtime::reflectionChain(int probe) const {
  const std::shared_ptr<const CubemapChain> chain = publishedChain(probe);
  if (chain) return *chain;
  CubemapChain black;
  for (int m = 0; m < reflectionMipCount(); ++m)
    black.push_back(makeCubemap(reflectionFaceSize(probe, m)));
  return black;
}

const ReflectionProbeBox* Runtime::reflectionProbeBox(int probe) const {
  if (probe < 1 || probe >= reflectionProbeCount()) return nullptr;
  return &data_.reflections.probes[size_t(probe - 1)].box;
}

std::vector<ProbeWeight> Runtime::reflectionProbesAt(glm::vec3 position) const {
  if (reflectionProbeCount() == 0) return {{0, 1.0f}};
  return runtime::reflectionProbesAt(data_.reflections.boxes(), position);
}

}  // namespace afterglow::runtime
