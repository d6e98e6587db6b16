#include "afterglow/runtime/runtime.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "afterglow/core/math.h"
#include "afterglow/core/timer.h"
#include "afterglow/runtime/probe_visibility.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/transport_file.h"

namespace afterglow::runtime {

namespace {

const std::string& emptyString() {
  static const std::string empty;
  return empty;
}

}  // namespace

std::unique_ptr<Runtime> Runtime::load(const std::string& path, std::string* error) {
  TransportData data;
  if (!loadTransport(path, data, error)) return nullptr;
  std::string why;
  auto runtime = fromData(std::move(data), &why);
  if (!runtime && error) *error = path + ": " + why;
  return runtime;
}

std::unique_ptr<Runtime> Runtime::fromData(TransportData data, std::string* error) {
  if (std::string why = data.validate(); !why.empty()) {
    if (error) *error = "invalid transport: " + why;
    return nullptr;
  }
  return std::unique_ptr<Runtime>(new Runtime(std::move(data)));
}

Runtime::Runtime(TransportData data) : data_(std::move(data)) {
  solver_ = std::make_unique<Solver>(data_);
  emissiveMaterial_.assign(data_.materials.size(), 0);
  for (size_t i = 0; i < data_.sources.size(); ++i) {
    const Source& s = data_.sources[i];
    if (s.kind == SourceKind::Light) {
      lightSource_.push_back(uint32_t(i));
      lights_.push_back({s.color, s.intensity, s.bounceIntensity, s.enabled});
    } else {
      emissiveMaterial_[s.material] = 1;
    }
  }
  for (const MaterialParams& m : data_.materials) materials_.push_back({m.albedo, m.emission});
  std::copy(data_.skySh, data_.skySh + kShCount, sky_);
  indirectIntensity_ = data_.indirectIntensity;
  // The first update() computes the direct light (the solver's constructor prepared already).
  dirty_ = kDirtyDirect;

  direct_.assign(data_.texelCount, glm::vec3(0.0f));
  if (data_.lightmap.active()) {
    grid_.assign(data_.texelCount, glm::vec3(0.0f));
    lightmapDirect_.assign(data_.lightmap.texelCount, glm::vec3(0.0f));
    for (int b = 0; b < 2; ++b)
      for (const AtlasLayout& layout : data_.atlases)
        gridImages_[b].emplace_back(size_t(layout.width) * size_t(layout.height), glm::vec3(0.0f));
  }
  for (int b = 0; b < 2; ++b) {
    texels_[b].assign(data_.lightmapTexelCount(), glm::vec3(0.0f));
    for (const AtlasLayout& layout : data_.lightmapAtlases())
      images_[b].emplace_back(size_t(layout.width) * size_t(layout.height), glm::vec3(0.0f));
    probes_[b].assign(data_.probes.count(), ShL2());
    if (data_.probes.count() > 0) {
      probeLights_[b].start.reserve(data_.probes.count() + 1);
      probeLights_[b].lights.reserve(probeLightCapacity(data_));
      probeLightScales_[b].reserve(data_.sources.size());
    }
  }
  probeWork_.assign(data_.probes.count(), ShL2());
  if (data_.reflections.count() > 0) {
    dfg_ = runtime::dfgTable(kDfgSize);
    reflectionOut_.resize(data_.reflections.count() + 1);
  }
}

Runtime::~Runtime() = default;

void Runtime::setParallelFor(ParallelFor parallelFor) {
  std::lock_guard<std::mutex> lock(updateMutex_);
  parallelFor_ = parallelFor;
  solver_->setParallelFor(std::move(parallelFor));
}

// ---- Lights -----------------------------------------------------------------------------------

int Runtime::lightCount() const { return int(lightSource_.size()); }

const std::string& Runtime::lightName(int light) const {
  return lightOk(light) ? data_.sources[lightSource_[size_t(light)]].name : emptyString();
}

int Runtime::findLight(const std::string& name) const {
  for (size_t i = 0; i < lightSource_.size(); ++i)
    if (data_.sources[lightSource_[i]].name == name) return int(i);
  return -1;
}

bool Runtime::setLightColor(int light, glm::vec3 linearRgb) {
  if (!lightOk(light) || !finite(linearRgb)) return false;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  LightSettings& l = lights_[size_t(light)];
  if (l.color != linearRgb) {
    l.color = linearRgb;
    dirty_ |= kDirtyLights | kDirtyDirect;
  }
  return true;
}

bool Runtime::setLightIntensity(int light, float intensity) {
  if (!lightOk(light) || !std::isfinite(intensity)) return false;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  LightSettings& l = lights_[size_t(light)];
  if (l.intensity != intensity) {
    l.intensity = intensity;
    dirty_ |= kDirtyLights | kDirtyDirect;
  }
  return true;
}

bool Runtime::setBounceIntensity(int light, float scale) {
  if (!lightOk(light) || !std::isfinite(scale)) return false;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  LightSettings& l = lights_[size_t(light)];
  if (l.bounceIntensity != scale) {
    l.bounceIntensity = scale;
    dirty_ |= kDirtyLights;  // bounced light only: the texels' direct light stays
  }
  return true;
}

bool Runtime::setLightEnabled(int light, bool enabled) {
  if (!lightOk(light)) return false;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  LightSettings& l = lights_[size_t(light)];
  if (l.enabled != enabled) {
    l.enabled = enabled;
    dirty_ |= kDirtyLights | kDirtyDirect;
  }
  return true;
}

bool Runtime::setLightColor(const std::string& name, glm::vec3 linearRgb) {
  return setLightColor(findLight(name), linearRgb);
}
bool Runtime::setLightIntensity(const std::string& name, float intensity) {
  return setLightIntensity(findLight(name), intensity);
}
bool Runtime::setBounceIntensity(const std::string& name, float scale) {
  return setBounceIntensity(findLight(name), scale);
}
bool Runtime::setLightEnabled(const std::string& name, bool enabled) {
  return setLightEnabled(findLight(name), enabled);
}

glm::vec3 Runtime::lightColor(int light) const {
  if (!lightOk(light)) return glm::vec3(0.0f);
  std::lock_guard<std::mutex> lock(settingsMutex_);
  return lights_[size_t(light)].color;
}
float Runtime::lightIntensity(int light) const {
  if (!lightOk(light)) return 0.0f;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  return lights_[size_t(light)].intensity;
}
float Runtime::bounceIntensity(int light) const {
  if (!lightOk(light)) return 0.0f;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  return lights_[size_t(light)].bounceIntensity;
}
bool Runtime::lightEnabled(int light) const {
  if (!lightOk(light)) return false;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  return lights_[size_t(light)].enabled;
}

// ---- Sky --------------------------------------------------------------------------------------

bool Runtime::setSky(glm::vec3 constantRadiance) {
  if (!finite(constantRadiance)) return false;
  glm::vec3 sh[kShCount];
  constantSkySh(constantRadiance, sh);
  return setSkySh(sh);
}

bool Runtime::setSkySh(const glm::vec3 sh[kShCount]) {
  for (int i = 0; i < kShCount; ++i)
    if (!finite(sh[i])) return false;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  if (!std::equal(sh, sh + kShCount, sky_)) {
    std::copy(sh, sh + kShCount, sky_);
    dirty_ |= kDirtySky | kDirtyDirect;
  }
  return true;
}

void Runtime::skySh(glm::vec3 sh[kShCount]) const {
  std::lock_guard<std::mutex> lock(settingsMutex_);
  std::copy(sky_, sky_ + kShCount, sh);
}

// ---- Materials --------------------------------------------------------------------------------

int Runtime::materialCount() const { return int(data_.materials.size()); }

const std::string& Runtime::materialName(int material) const {
  return materialOk(material) ? data_.materials[size_t(material)].name : emptyString();
}

int Runtime::findMaterial(const std::string& name) const {
  for (size_t i = 0; i < data_.materials.size(); ++i)
    if (data_.materials[i].name == name) return int(i);
  return -1;
}

bool Runtime::setAlbedo(int material, glm::vec3 linearRgb) {
  if (!materialOk(material) || !finite(linearRgb)) return false;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  MaterialSettings& m = materials_[size_t(material)];
  if (m.albedo != linearRgb) {
    m.albedo = linearRgb;
    dirty_ |= kDirtyMaterials;  // bounces only
  }
  return true;
}

bool Runtime::setEmission(int material, glm::vec3 linearRgb) {
  if (!canSetEmission(material) || !finite(linearRgb)) return false;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  MaterialSettings& m = materials_[size_t(material)];
  if (m.emission != linearRgb) {
    m.emission = linearRgb;
    dirty_ |= kDirtyMaterials | kDirtyDirect;
  }
  return true;
}

bool Runtime::setAlbedo(const std::string& name, glm::vec3 linearRgb) {
  return setAlbedo(findMaterial(name), linearRgb);
}
bool Runtime::setEmission(const std::string& name, glm::vec3 linearRgb) {
  return setEmission(findMaterial(name), linearRgb);
}

bool Runtime::canSetEmission(int material) const {
  return materialOk(material) && emissiveMaterial_[size_t(material)] != 0;
}

glm::vec3 Runtime::albedo(int material) const {
  if (!materialOk(material)) return glm::vec3(0.0f);
  std::lock_guard<std::mutex> lock(settingsMutex_);
  return materials_[size_t(material)].albedo;
}
glm::vec3 Runtime::emission(int material) const {
  if (!materialOk(material)) return glm::vec3(0.0f);
  std::lock_guard<std::mutex> lock(settingsMutex_);
  return materials_[size_t(material)].emission;
}

bool Runtime::setIndirectIntensity(float scale) {
  if (!std::isfinite(scale)) return false;
  std::lock_guard<std::mutex> lock(settingsMutex_);
  if (indirectIntensity_ != scale) {
    indirectIntensity_ = scale;
    dirty_ |= kDirtyIndirect;
  }
  return true;
}

float Runtime::indirectIntensity() const {
  std::lock_guard<std::mutex> lock(settingsMutex_);
  return indirectIntensity_;
}

// ---- Solving ----------------------------------------------------------------------------------

UpdateStats Runtime::update(const UpdateOptions& options) {
  std::lock_guard<std::mutex> updateLock(updateMutex_);
  const Clock::time_point start = Clock::now();
  UpdateStats stats;

  // Take the pending settings (element-wise copies into storage sized at load: no allocation).
  unsigned dirty;
  {
    std::lock_guard<std::mutex> lock(settingsMutex_);
    dirty = dirty_;
    dirty_ = 0;
    if (dirty & kDirtyLights)
      for (size_t i = 0; i < lights_.size(); ++i) {
        Source& s = data_.sources[lightSource_[i]];
        s.color = lights_[i].color;
        s.intensity = lights_[i].intensity;
        s.bounceIntensity = lights_[i].bounceIntensity;
        s.enabled = lights_[i].enabled;
      }
    if (dirty & kDirtyMaterials)
      for (size_t m = 0; m < materials_.size(); ++m) {
        data_.materials[m].albedo = materials_[m].albedo;
        data_.materials[m].emission = materials_[m].emission;
      }
    if (dirty & kDirtySky) std::copy(sky_, sky_ + kShCount, data_.skySh);
    if (dirty & kDirtyIndirect) data_.indirectIntensity = indirectIntensity_;
  }
  if (dirty & (kDirtyLights | kDirtyMaterials | kDirtySky))
    solver_->prepare(((dirty & kDirtyLights) ? Solver::kSourcesChanged : 0u) |
                     ((dirty & kDirtyMaterials) ? Solver::kMaterialsChanged : 0u) |
                     ((dirty & kDirtySky) ? Solver::kSkyChanged : 0u));
  if (options.fromScratch) solver_->reset();
  stats.prepareMilliseconds = millisecondsSince(start);

  // Passes: the same loop as Solver::solve() (so fromScratch matches a bake), plus the budget.
  const int limit = options.maxBounces > 0 ? options.maxBounces : options.maxBounces == 0 ? 1000 : 0;
  double lastPassMs = 0.0;
  while (stats.bounces < limit) {
    if (options.timeBudgetMs > 0.0 && stats.bounces > 0 &&
        millisecondsSince(start) + lastPassMs + lastOutputMs_ > options.timeBudgetMs)
      break;
    const Clock::time_point passStart = Clock::now();
    stats.change = solver_->iterate();
    lastPassMs = millisecondsSince(passStart);
    ++stats.bounces;
    stats.converged = stats.change < options.tolerance;
    if (options.maxBounces == 0 && stats.converged) break;
  }
  stats.bounceMilliseconds = millisecondsSince(start) - stats.prepareMilliseconds;

  // Texel values as the bake computes them: direct (sky first, then sources) + indirect; with
  // two resolutions the grid's sum brought up to the lightmap's texels beside their direct light.
  const Clock::time_point outputStart = Clock::now();
  // With two resolutions the grid's direct light is its sky alone (the sources' is in the
  // lightmap's layers), so a light or emission change leaves it.
  const unsigned gridDirect = data_.lightmap.active() ? kDirtySky : kDirtyDirect;
  if ((dirty & gridDirect) || firstUpdate_) solver_->directTexels(direct_.data());
  firstUpdate_ = false;
  // The images were zero-filled at their full size at load: refreshAtlas writes only the
  // pixels texels reach.
  const int back = 1 - front_;  // front_ is written only here, under updateLock
  std::vector<glm::vec3>& values = texels_[back];
  bool compose = true;
  if (data_.lightmap.active()) {
    solver_->addIndirectTexels(direct_.data(), grid_.data());
    const int gridBack = 1 - gridFront_;
    for (size_t a = 0; a < data_.atlases.size(); ++a)
      refreshAtlas(data_.atlases[a], grid_, gridImages_[gridBack][a]);
    {
      std::lock_guard<std::mutex> lock(outputMutex_);
      gridFront_ = gridBack;
    }
    // The direct layers follow the sources even when not composed now, so a later composing
    // update sees them current.
    if (dirty & kDirtyDirect) pendingLightmapDirect_ = true;
    compose = options.composeLightmap;
    if (compose) {
      const Clock::time_point composeStart = Clock::now();
      if (pendingLightmapDirect_) solver_->lightmapDirect(lightmapDirect_.data());
      pendingLightmapDirect_ = false;
      solver_->composeLightmap(lightmapDirect_.data(), grid_.data(), values.data());
      stats.composeMilliseconds = millisecondsSince(composeStart);
    }
  } else {
    solver_->addIndirectTexels(direct_.data(), values.data());
  }
  if (compose) {
    const std::vector<AtlasLayout>& atlases = data_.lightmapAtlases();
    for (size_t a = 0; a < atlases.size(); ++a) refreshAtlas(atlases[a], values, images_[back][a]);
    std::lock_guard<std::mutex> lock(outputMutex_);
    front_ = back;
  }
  if (options.directional && data_.hasDirections()) refreshDirectional();
  lastOutputMs_ = stats.outputMilliseconds = millisecondsSince(outputStart);
  if (options.probes && !probeWork_.empty()) {
    const Clock::time_point probeStart = Clock::now();
    stats.probes = int(refreshProbes(0, probeWork_.size()));
    publishProbes();
    stats.probeMilliseconds = millisecondsSince(probeStart);
  }
  if (dirty & kDirtySky) reflectionSkyStale_ = true;
  runReflectionUnits(options.reflectionPasses, options.timeBudgetMs, start, stats);
  stats.milliseconds = millisecondsSince(start);
  return stats;
}

// ---- Light probes -----------------------------------------------------------------------------

size_t Runtime::refreshProbes(size_t first, size_t count) {
  count = std::min(count, probeWork_.size() - std::min(first, probeWork_.size()));
  if (count > 0) solver_->probeRadiance(first, count, probeWork_.data() + first);
  return count;
}

void Runtime::publishProbes() {
  const int back = 1 - probeFront_;  // written only here, under updateMutex_
  std::copy(probeWork_.begin(), probeWork_.end(), probes_[back].begin());
  // The directions depend on the sources' scales alone: a budgeted refresh under unchanged
  // lights (most calls) keeps the buffer's.
  const std::vector<glm::vec3>& scales = solver_->directScales();
  if (!probeLightsValid_[back] || probeLightScales_[back] != scales) {
    runtime::probeLights(data_, scales, probeLights_[back]);
    probeLightScales_[back].assign(scales.begin(), scales.end());
    probeLightsValid_[back] = true;
  }
  std::lock_guard<std::mutex> lock(outputMutex_);
  probeFront_ = back;
}

UpdateStats Runtime::updateProbes(double budgetMs) {
  std::lock_guard<std::mutex> updateLock(updateMutex_);
  const Clock::time_point start = Clock::now();
  UpdateStats stats;
  const size_t n = probeWork_.size();
  if (n == 0) return stats;
  if (!(budgetMs > 0.0)) {
    stats.probes = int(refreshProbes(0, n));
    probeCursor_ = 0;
  } else {
    // Blocks of probes until the budget would be overrun (the first block always runs), at
    // most once round.
    constexpr size_t kProbeBlock = 256;
    double lastBlockMs = 0.0;
    size_t done = 0;
    while (done < n) {
      if (done > 0 && millisecondsSince(start) + lastBlockMs > budgetMs) break;
      const Clock::time_point blockStart = Clock::now();
      const size_t did = refreshProbes(probeCursor_, std::min(kProbeBlock, n - done));
      lastBlockMs = millisecondsSince(blockStart);
      done += did;
      probeCursor_ = (probeCursor_ + did) % n;
    }
    stats.probes = int(done);
  }
  publishProbes();
  stats.probeMilliseconds = stats.milliseconds = millisecondsSince(start);
  return stats;
}

int Runtime::probeCount() const { return int(data_.probes.count()); }

glm::vec3 Runtime::probePosition(int probe) const {
  return probe >= 0 && probe < probeCount() ? data_.probes.mesh.positions[size_t(probe)] : glm::vec3(0.0f);
}

bool Runtime::probeSh(int probe, ShL2* sh) const {
  if (probe < 0 || probe >= probeCount() || !sh) return false;
  std::lock_guard<std::mutex> lock(outputMutex_);
  *sh = probes_[probeFront_][size_t(probe)];
  return true;
}

ProbeLocation Runtime::locateSeen(glm::vec3 position, int* hint) const {
  const ProbeLocation where = locateProbe(data_.probes.mesh, position, hint ? *hint : 0);
  if (hint && where.tetrahedron >= 0) *hint = where.tetrahedron;
  return weighByVisibility(where, data_.probes, position);
}

ShL2 Runtime::sampleProbes(glm::vec3 position, int* hint) const {
  if (probeCount() == 0) return ShL2();
  const ProbeLocation seen = locateSeen(position, hint);
  std::lock_guard<std::mutex> lock(outputMutex_);
  return mixProbes(seen, probes_[probeFront_]);
}

glm::vec3 Runtime::evaluateIrradiance(const ShL2& sh, glm::vec3 normal) {
  return irradianceOverPi(sh, normal);
}

ProbeLighting Runtime::sampleProbeLighting(glm::vec3 position, int* hint) const {
  if (probeCount() == 0) return ProbeLighting();
  const ProbeLocation seen = locateSeen(position, hint);
  std::lock_guard<std::mutex> lock(outputMutex_);
  return mixProbeLighting(seen, probes_[probeFront_], probeLights_[probeFront_]);
}

glm::vec3 Runtime::evaluateIrradiance(const ProbeLighting& lighting, glm::vec3 normal) {
  return lighting.irradianceOverPi(normal);
}

ProbeDirectionList Runtime::probeLights() const {
  std::lock_guard<std::mutex> lock(outputMutex_);
  return probeLights_[probeFront_];
}

// ---- Output -----------------------------------------------------------------------------------

int Runtime::atlasCount() const { return int(data_.lightmapAtlases().size()); }

int Runtime::atlasWidth(int atlas) const {
  return atlas >= 0 && atlas < atlasCount() ? data_.lightmapAtlases()[size_t(atlas)].width : 0;
}

int Runtime::atlasHeight(int atlas) const {
  return atlas >= 0 && atlas < atlasCount() ? data_.lightmapAtlases()[size_t(atlas)].height : 0;
}

bool Runtime::readAtlas(int atlas, float* rgb) const {
  if (atlas < 0 || atlas >= atlasCount()) return false;
  std::lock_guard<std::mutex> lock(outputMutex_);
  const std::vector<glm::vec3>& image = images_[front_][size_t(atlas)];
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "glm::vec3 is three packed floats");
  std::memcpy(rgb, image.data(), image.size() * sizeof(glm::vec3));
  return true;
}

bool Runtime::readAtlas(int atlas, std::vector<glm::vec3>& image) const {
  if (atlas < 0 || atlas >= atlasCount()) return false;
  image.resize(size_t(atlasWidth(atlas)) * size_t(atlasHeight(atlas)));
  return readAtlas(atlas, reinterpret_cast<float*>(image.data()));
}

int Runtime::indirectAtlasCount() const {
  return data_.lightmap.active() ? int(data_.atlases.size()) : 0;
}

int Runtime::indirectAtlasWidth(int atlas) const {
  return atlas >= 0 && atlas < indirectAtlasCount() ? data_.atlases[size_t(atlas)].width : 0;
}

int Runtime::indirectAtlasHeight(int atlas) const {
  return atlas >= 0 && atlas < indirectAtlasCount() ? data_.atlases[size_t(atlas)].height : 0;
}

bool Runtime::readIndirectAtlas(int atlas, std::vector<glm::vec3>& image) const {
  if (atlas < 0 || atlas >= indirectAtlasCount()) return false;
  std::lock_guard<std::mutex> lock(outputMutex_);
  image = gridImages_[gridFront_][size_t(atlas)];
  return true;
}

void Runtime::refreshDirectional() {
  if (!directional_) {
    directional_ = std::make_unique<DirectionalLight>(data_);
    gradient_.resize(data_.texelCount);
    for (std::vector<glm::vec3>& axis : gradientAxis_) axis.resize(data_.texelCount);
    for (int b = 0; b < 2; ++b)
      for (const AtlasLayout& layout : data_.atlases)
        for (int axis = 0; axis < 3; ++axis)
          directionalImages_[b].emplace_back(size_t(layout.width) * size_t(layout.height),
                                             glm::vec3(0.0f));
  }
  directional_->setParallelFor(parallelFor_);
  directional_->texels(*solver_, gradient_.data());
  for (size_t t = 0; t < gradient_.size(); ++t)
    for (int axis = 0; axis < 3; ++axis) gradientAxis_[axis][t] = gradient_[t].axis[axis];
  const int back = 1 - directionalFront_;
  for (size_t a = 0; a < data_.atlases.size(); ++a)
    for (int axis = 0; axis < 3; ++axis)
      refreshAtlas(data_.atlases[a], gradientAxis_[axis], directionalImages_[back][a * 3 + size_t(axis)]);
  std::lock_guard<std::mutex> lock(outputMutex_);
  directionalFront_ = back;
}

int Runtime::directionalAtlasCount() const {
  return data_.hasDirections() ? int(data_.atlases.size()) : 0;
}

bool Runtime::readDirectionalAtlas(int atlas, int axis, std::vector<glm::vec3>& image) const {
  if (atlas < 0 || atlas >= directionalAtlasCount() || axis < 0 || axis > 2) return false;
  const AtlasLayout& layout = data_.atlases[size_t(atlas)];
  std::lock_guard<std::mutex> lock(outputMutex_);
  const std::vector<std::vector<glm::vec3>>& images = directionalImages_[directionalFront_];
  if (images.empty()) image.assign(size_t(layout.width) * size_t(layout.height), glm::vec3(0.0f));
  else image = images[size_t(atlas) * 3 + size_t(axis)];
  return true;
}

int Runtime::texelCount() const { return int(data_.lightmapTexelCount()); }

void Runtime::readTexels(glm::vec3* texels) const {
  std::lock_guard<std::mutex> lock(outputMutex_);
  std::copy(texels_[front_].begin(), texels_[front_].end(), texels);
}

void Runtime::readTexels(float* rgb) const {
  std::lock_guard<std::mutex> lock(outputMutex_);
  std::memcpy(rgb, texels_[front_].data(), texels_[front_].size() * sizeof(glm::vec3));
}

}  // namespace afterglow::runtime
