// The C API (afterglow_runtime.h) over Runtime. No exception crosses it: load() turns
// std::bad_alloc into an error message, and the calls that allocate since reflection probes
// (update and update_reflection_probes build new cubemaps, reflection_probes_at its list)
// return 0 on it; nothing else here throws.
#include "afterglow_runtime.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/runtime.h"

using afterglow::runtime::Runtime;

struct AfterglowRuntime {
  std::unique_ptr<Runtime> runtime;
};

namespace {

void writeError(char* err, size_t size, const std::string& message) {
  if (!err || size == 0) return;
  const size_t n = std::min(size - 1, message.size());
  std::memcpy(err, message.data(), n);
  err[n] = '\0';
}

const char* nameOrNull(const std::string& name, bool valid) { return valid ? name.c_str() : nullptr; }

}  // namespace

extern "C" {

void afterglow_runtime_default_options(AfterglowUpdateOptions* options) {
  if (!options) return;
  const afterglow::runtime::UpdateOptions defaults;
  options->max_bounces = defaults.maxBounces;
  options->tolerance = defaults.tolerance;
  options->time_budget_ms = defaults.timeBudgetMs;
  options->from_scratch = defaults.fromScratch ? 1 : 0;
  options->probes = defaults.probes ? 1 : 0;
  options->reflection_passes = defaults.reflectionPasses;
}

AfterglowRuntime* afterglow_runtime_load(const char* path, char* err, size_t err_size) {
  if (!path) {
    writeError(err, err_size, "afterglow_runtime_load: no path");
    return nullptr;
  }
  try {
    std::string error;
    std::unique_ptr<Runtime> runtime = Runtime::load(path, &error);
    if (!runtime) {
      writeError(err, err_size, error);
      return nullptr;
    }
    writeError(err, err_size, "");
    return new AfterglowRuntime{std::move(runtime)};
  } catch (const std::exception& e) {
    writeError(err, err_size, std::string(path) + ": " + e.what());
    return nullptr;
  }
}

void afterglow_runtime_free(AfterglowRuntime* runtime) { delete runtime; }

int afterglow_runtime_light_count(const AfterglowRuntime* rt) {
  return rt ? rt->runtime->lightCount() : 0;
}

const char* afterglow_runtime_light_name(const AfterglowRuntime* rt, int light) {
  if (!rt) return nullptr;
  return nameOrNull(rt->runtime->lightName(light), light >= 0 && light < rt->runtime->lightCount());
}

int afterglow_runtime_find_light(const AfterglowRuntime* rt, const char* name) {
  return rt && name ? rt->runtime->findLight(name) : -1;
}

int afterglow_runtime_set_light_color(AfterglowRuntime* rt, int light, float r, float g, float b) {
  return rt && rt->runtime->setLightColor(light, glm::vec3(r, g, b));
}

int afterglow_runtime_set_light_intensity(AfterglowRuntime* rt, int light, float intensity) {
  return rt && rt->runtime->setLightIntensity(light, intensity);
}

int afterglow_runtime_set_bounce_intensity(AfterglowRuntime* rt, int light, float scale) {
  return rt && rt->runtime->setBounceIntensity(light, scale);
}

int afterglow_runtime_set_light_enabled(AfterglowRuntime* rt, int light, int enabled) {
  return rt && rt->runtime->setLightEnabled(light, enabled != 0);
}

int afterglow_runtime_set_sky(AfterglowRuntime* rt, float r, float g, float b) {
  return rt && rt->runtime->setSky(glm::vec3(r, g, b));
}

int afterglow_runtime_set_sky_sh(AfterglowRuntime* rt, const float* sh27) {
  if (!rt || !sh27) return 0;
  glm::vec3 sh[afterglow::runtime::kShCount];
  for (int i = 0; i < afterglow::runtime::kShCount; ++i)
    sh[i] = glm::vec3(sh27[3 * i], sh27[3 * i + 1], sh27[3 * i + 2]);
  return rt->runtime->setSkySh(sh);
}

int afterglow_runtime_material_count(const AfterglowRuntime* rt) {
  return rt ? rt->runtime->materialCount() : 0;
}

const char* afterglow_runtime_material_name(const AfterglowRuntime* rt, int material) {
  if (!rt) return nullptr;
  return nameOrNull(rt->runtime->materialName(material),
                    material >= 0 && material < rt->runtime->materialCount());
}

int afterglow_runtime_find_material(const AfterglowRuntime* rt, const char* name) {
  return rt && name ? rt->runtime->findMaterial(name) : -1;
}

int afterglow_runtime_set_albedo(AfterglowRuntime* rt, int material, float r, float g, float b) {
  return rt && rt->runtime->setAlbedo(material, glm::vec3(r, g, b));
}

int afterglow_runtime_set_emission(AfterglowRuntime* rt, int material, float r, float g, float b) {
  return rt && rt->runtime->setEmission(material, glm::vec3(r, g, b));
}

int afterglow_runtime_can_set_emission(const AfterglowRuntime* rt, int material) {
  return rt && rt->runtime->canSetEmission(material);
}

int afterglow_runtime_set_indirect_intensity(AfterglowRuntime* rt, float scale) {
  return rt && rt->runtime->setIndirectIntensity(scale);
}

namespace {
void copyStats(const afterglow::runtime::UpdateStats& s, AfterglowUpdateStats* stats) {
  if (!stats) return;
  stats->bounces = s.bounces;
  stats->converged = s.converged ? 1 : 0;
  stats->change = s.change;
  stats->milliseconds = s.milliseconds;
  stats->probes = s.probes;
  stats->probe_milliseconds = s.probeMilliseconds;
  stats->reflection_passes = s.reflectionPasses;
  stats->reflection_milliseconds = s.reflectionMilliseconds;
}
}  // namespace

int afterglow_runtime_update(AfterglowRuntime* rt, const AfterglowUpdateOptions* options,
                             AfterglowUpdateStats* stats) {
  if (!rt) return 0;
  afterglow::runtime::UpdateOptions o;
  if (options) {
    o.maxBounces = options->max_bounces;
    o.tolerance = options->tolerance;
    o.timeBudgetMs = options->time_budget_ms;
    o.fromScratch = options->from_scratch != 0;
    o.probes = options->probes != 0;
    o.reflectionPasses = options->reflection_passes;
  }
  try {
    copyStats(rt->runtime->update(o), stats);
  } catch (const std::bad_alloc&) {
    return 0;  // the reflection probes' passes allocate their cubemaps
  }
  return 1;
}

int afterglow_runtime_probe_count(const AfterglowRuntime* rt) {
  return rt ? rt->runtime->probeCount() : 0;
}

int afterglow_runtime_probe_position(const AfterglowRuntime* rt, int probe, float* xyz) {
  if (!rt || !xyz || probe < 0 || probe >= rt->runtime->probeCount()) return 0;
  const glm::vec3 p = rt->runtime->probePosition(probe);
  xyz[0] = p.x, xyz[1] = p.y, xyz[2] = p.z;
  return 1;
}

namespace {
void copySh(const afterglow::runtime::ShL2& sh, float* sh27) {
  for (int i = 0; i < afterglow::runtime::kShCount; ++i)
    for (int c = 0; c < 3; ++c) sh27[3 * i + c] = sh.c[i][c];
}
}  // namespace

int afterglow_runtime_probe_sh(const AfterglowRuntime* rt, int probe, float* sh27) {
  afterglow::runtime::ShL2 sh;
  if (!rt || !sh27 || !rt->runtime->probeSh(probe, &sh)) return 0;
  copySh(sh, sh27);
  return 1;
}

int afterglow_runtime_sample_probes(const AfterglowRuntime* rt, float x, float y, float z,
                                    int* hint, float* sh27) {
  if (!rt || !sh27) return 0;
  copySh(rt->runtime->sampleProbes(glm::vec3(x, y, z), hint), sh27);
  return 1;
}

void afterglow_runtime_evaluate_irradiance(const float* sh27, float nx, float ny, float nz,
                                           float* rgb) {
  if (!sh27 || !rgb) return;
  afterglow::runtime::ShL2 sh;
  for (int i = 0; i < afterglow::runtime::kShCount; ++i)
    sh.c[i] = glm::vec3(sh27[3 * i], sh27[3 * i + 1], sh27[3 * i + 2]);
  const glm::vec3 e = afterglow::runtime::Runtime::evaluateIrradiance(sh, glm::vec3(nx, ny, nz));
  rgb[0] = e.x, rgb[1] = e.y, rgb[2] = e.z;
}

int afterglow_runtime_sample_probe_irradiance(const AfterglowRuntime* rt, float x, float y,
                                              float z, float nx, float ny, float nz, int* hint,
                                              float* rgb) {
  if (!rt || !rgb) return 0;
  const glm::vec3 e =
      rt->runtime->sampleProbeLighting(glm::vec3(x, y, z), hint).irradianceOverPi(glm::vec3(nx, ny, nz));
  rgb[0] = e.x, rgb[1] = e.y, rgb[2] = e.z;
  return 1;
}

int afterglow_runtime_update_probes(AfterglowRuntime* rt, double budget_ms,
                                    AfterglowUpdateStats* stats) {
  if (!rt) return 0;
  copyStats(rt->runtime->updateProbes(budget_ms), stats);
  return 1;
}

// ---- Reflection probes ------------------------------------------------------------------------

namespace {

using afterglow::runtime::ReflectionProbeBox;

void copyVec3(glm::vec3 v, float* out) { out[0] = v.x, out[1] = v.y, out[2] = v.z; }
glm::vec3 vec3Of(const float* v) { return glm::vec3(v[0], v[1], v[2]); }

// Field by field both ways, so the C box and ReflectionProbeBox need not share a layout.
void boxToC(const ReflectionProbeBox& b, AfterglowReflectionProbeBox* out) {
  copyVec3(b.centre, out->centre);
  for (int k = 0; k < 3; ++k) copyVec3(b.axes[k], out->axes + 3 * k);
  copyVec3(b.halfSize, out->half_size);
  out->blend_distance = b.blendDistance;
  out->importance = b.importance;
  out->box_projection = b.boxProjection ? 1 : 0;
  copyVec3(b.capturePosition, out->capture_position);
  copyVec3(b.projectionCentre, out->projection_centre);
  copyVec3(b.projectionHalfSize, out->projection_half_size);
}

ReflectionProbeBox boxFromC(const AfterglowReflectionProbeBox& b) {
  ReflectionProbeBox out;
  out.centre = vec3Of(b.centre);
  for (int k = 0; k < 3; ++k) out.axes[k] = vec3Of(b.axes + 3 * k);
  out.halfSize = vec3Of(b.half_size);
  out.blendDistance = b.blend_distance;
  out.importance = b.importance;
  out.boxProjection = b.box_projection != 0;
  out.capturePosition = vec3Of(b.capture_position);
  out.projectionCentre = vec3Of(b.projection_centre);
  out.projectionHalfSize = vec3Of(b.projection_half_size);
  return out;
}

}  // namespace

int afterglow_runtime_reflection_probe_count(const AfterglowRuntime* rt) {
  return rt ? rt->runtime->reflectionProbeCount() : 0;
}

int afterglow_runtime_reflection_mip_count(const AfterglowRuntime* rt) {
  return rt ? rt->runtime->reflectionMipCount() : 0;
}

int afterglow_runtime_reflection_face_size(const AfterglowRuntime* rt, int probe, int mip) {
  return rt ? rt->runtime->reflectionFaceSize(probe, mip) : 0;
}

int afterglow_runtime_read_cubemap(const AfterglowRuntime* rt, int probe, int mip, int face,
                                   float* rgb, size_t float_count) {
  if (!rt || !rgb) return 0;
  const size_t size = size_t(rt->runtime->reflectionFaceSize(probe, mip));
  if (size == 0 || float_count < size * size * 3) return 0;
  return rt->runtime->readCubemap(probe, mip, face, rgb);
}

float afterglow_runtime_reflection_mip_of_roughness(const AfterglowRuntime* rt, float r) {
  if (!rt || rt->runtime->reflectionMipCount() == 0) return 0.0f;
  return afterglow::runtime::mipOfRoughness(r, rt->runtime->reflectionMipCount());
}

int afterglow_runtime_reflection_probes_at(const AfterglowRuntime* rt, float x, float y, float z,
                                           int* probes, float* weights, int capacity) {
  if (!rt || (capacity > 0 && (!probes || !weights))) return 0;
  std::vector<afterglow::runtime::ProbeWeight> found;
  try {
    found = rt->runtime->reflectionProbesAt(glm::vec3(x, y, z));
  } catch (const std::bad_alloc&) {
    return 0;
  }
  for (size_t i = 0; i < found.size() && capacity > 0 && i < size_t(capacity); ++i) {
    probes[i] = found[i].probe;
    weights[i] = found[i].weight;
  }
  return int(found.size());
}

int afterglow_runtime_reflection_probe_box(const AfterglowRuntime* rt, int probe,
                                           AfterglowReflectionProbeBox* box) {
  if (!rt || !box) return 0;
  const ReflectionProbeBox* b = rt->runtime->reflectionProbeBox(probe);
  if (!b) return 0;
  boxToC(*b, box);
  return 1;
}

int afterglow_runtime_box_project(const AfterglowReflectionProbeBox* box, float px, float py,
                                  float pz, float dx, float dy, float dz, float* xyz) {
  if (!box || !xyz) return 0;
  copyVec3(afterglow::runtime::boxProject(boxFromC(*box), glm::vec3(px, py, pz),
                                          glm::vec3(dx, dy, dz)),
           xyz);
  return 1;
}

int afterglow_runtime_dfg_size(const AfterglowRuntime* rt) {
  return rt && !rt->runtime->dfgTable().empty() ? afterglow::runtime::kDfgSize : 0;
}

int afterglow_runtime_read_dfg(const AfterglowRuntime* rt, float* scale_bias, size_t float_count) {
  if (!rt || !scale_bias) return 0;
  const std::vector<glm::vec2>& table = rt->runtime->dfgTable();
  if (table.empty() || float_count < table.size() * 2) return 0;
  for (size_t i = 0; i < table.size(); ++i) {
    scale_bias[2 * i] = table[i].x;
    scale_bias[2 * i + 1] = table[i].y;
  }
  return 1;
}

int afterglow_runtime_update_reflection_probes(AfterglowRuntime* rt, int passes, double budget_ms,
                                               AfterglowUpdateStats* stats) {
  if (!rt) return 0;
  try {
    copyStats(rt->runtime->updateReflectionProbes(passes, budget_ms), stats);
  } catch (const std::bad_alloc&) {
    return 0;
  }
  return 1;
}

int afterglow_runtime_atlas_count(const AfterglowRuntime* rt) {
  return rt ? rt->runtime->atlasCount() : 0;
}

int afterglow_runtime_atlas_width(const AfterglowRuntime* rt, int atlas) {
  return rt ? rt->runtime->atlasWidth(atlas) : 0;
}

int afterglow_runtime_atlas_height(const AfterglowRuntime* rt, int atlas) {
  return rt ? rt->runtime->atlasHeight(atlas) : 0;
}

int afterglow_runtime_read_atlas(const AfterglowRuntime* rt, int atlas, float* rgb,
                                 size_t float_count) {
  if (!rt || !rgb) return 0;
  const size_t needed =
      size_t(rt->runtime->atlasWidth(atlas)) * size_t(rt->runtime->atlasHeight(atlas)) * 3;
  if (needed == 0 || float_count < needed) return 0;
  return rt->runtime->readAtlas(atlas, rgb);
}

int afterglow_runtime_texel_count(const AfterglowRuntime* rt) {
  return rt ? rt->runtime->texelCount() : 0;
}

int afterglow_runtime_read_texels(const AfterglowRuntime* rt, float* rgb, size_t float_count) {
  if (!rt || !rgb || float_count < size_t(rt->runtime->texelCount()) * 3) return 0;
  rt->runtime->readTexels(rgb);
  return 1;
}

}  // extern "C"
