#include "afterglow/trace/raytracer.h"

#include <algorithm>
#include <cstring>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <vector>

#include <embree3/rtcore.h>

#include "afterglow/core/math.h"
#include "afterglow/core/timer.h"

namespace afterglow::trace {
namespace {

// One flattened (instance, primitive): where its world data lives and how to cut it out.
struct Geometry {
  uint32_t instance = kInvalidId;
  uint32_t primitive = kInvalidId;
  const scenes::Primitive* source = nullptr;
  const float* vertices = nullptr;   // world xyz per vertex, in Embree's buffer
  const uint32_t* indices = nullptr; // 3 per triangle, in Embree's buffer, always in range
  // Maps object normals to world normals on the glTF front side: sign(det) × cofactor(M),
  // i.e. M⁻ᵀ up to a positive scale, and still defined when M is singular.
  glm::mat3 normalMatrix{1.0f};
  // +1, or -1 when the transform mirrors: Embree's Ng follows the world winding, while glTF's
  // front side turns to clockwise under a negative determinant.
  float frontSign = 1.0f;
  // Alpha cut-out (filter functions are only installed when alphaTested).
  bool alphaTested = false;
  float alphaFactor = 1.0f;
  float alphaCutoff = 0.5f;
  const scenes::Texture* alphaTexture = nullptr;     // null: baseColorFactor.a alone
  const scenes::TextureRef* alphaRef = nullptr;
  const std::vector<glm::vec2>* alphaUv = nullptr;   // the UV set the texture reads
  // Glass (filters are installed when transmissive): what passes, everywhere when untextured,
  // else evaluated at the hit (scenes::transmission; `blend`: BLEND counts, not cut out).
  bool transmissive = false;
  bool transmissionTextured = false;
  bool blend = true;
  scenes::Transmission transmission;
  const scenes::Scene* scene = nullptr;
  int material = -1;
  // TEXCOORD_1 at each triangle's corners, three in a row (empty without the set): a hit's
  // lightmap UV in one cache line, where the index and vertex buffers cost two misses in a row
  // (the gather looks up the texel of every hit).
  std::vector<glm::vec2> lightmapUv;

  glm::vec3 vertex(uint32_t i) const {
    return glm::vec3(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
  }

  float alpha(uint32_t triangle, float u, float v) const {
    float a = alphaFactor;
    if (alphaTexture) {
      const uint32_t* t = indices + 3 * size_t(triangle);
      const std::vector<glm::vec2>& uv = *alphaUv;
      const glm::vec2 st = (1.0f - u - v) * uv[t[0]] + u * uv[t[1]] + v * uv[t[2]];
      a *= alphaTexture->sample(alphaRef->transform(st)).a;
    }
    return a;
  }

  scenes::Transmission transmissionAt(uint32_t triangle, float u, float v) const {
    if (!transmissionTextured) return transmission;
    glm::vec2 uv0(0.0f);
    if (source->uv0.size() == source->positions.size()) {
      const uint32_t* t = indices + 3 * size_t(triangle);
      const std::vector<glm::vec2>& uv = source->uv0;
      uv0 = (1.0f - u - v) * uv[t[0]] + u * uv[t[1]] + v * uv[t[2]];
    }
    return scenes::transmission(*scene, material, uv0, blend);
  }
};

// What a query does at glass (Glass, and the transmittance queries), for the filters.
enum class AtGlass : uint8_t {
  Stop,           // Glass::Solid: every hit counts
  Chance,         // Glass::Light intersect: pass, stop or absorb by the ray's own chance
  Open,           // Glass::Light occluded: pass wherever light gets through
  Transmittance,  // pass, multiplying the ray's Layers by what gets through
};

uint32_t floatBits(float f) {
  uint32_t b;
  std::memcpy(&b, &f, sizeof(b));
  return b;
}

// A ray's crossing of a surface: Embree may call a filter more than once for one triangle
// (with spatial splits, RTC_BUILD_QUALITY_HIGH), and a ray through the edge two triangles
// share meets both at one distance; each is one crossing of the surface, which counts once.
// Crossings of one geometry within 3·10⁻⁵ of the distance are one.
struct Crossing {
  uint32_t geometry;
  float t;
  bool same(const Crossing& o) const {
    return geometry == o.geometry && std::abs(t - o.t) <= 3e-5f * std::max(t, o.t);
  }
  // As a key (the distance rounded to 2⁻¹⁵ of itself), for the ray's random number there.
  uint64_t key() const { return (uint64_t(geometry) << 32) | ((floatBits(t) + 0x80u) >> 8); }
};

// One ray's transmittance so far, and the crossings that made it.
struct Layers {
  static constexpr int kMax = 16;
  glm::vec3 value{1.0f};
  int count = 0;
  Crossing seen[kMax];

  void clear() {
    value = glm::vec3(1.0f);
    count = 0;
  }
  // Multiplies in a crossing's share, once; false when the ray is blocked.
  bool add(const Crossing& at, glm::vec3 share) {
    for (int k = 0; k < count; ++k)
      if (seen[k].same(at)) return true;
    if (count == kMax) return false;
    seen[count++] = at;
    value *= share;
    return value != glm::vec3(0.0f);
  }
};

// Embree's context extended with what the filters need (Embree passes filters the pointer it
// was given, so the extension rides along; the documented way to hand filters per-query data).
struct Context {
  RTCIntersectContext embree;  // first
  AtGlass atGlass = AtGlass::Stop;
  bool grey = false;           // Transmittance: each surface's grey share, else its RGB one
  Layers* layers = nullptr;    // Transmittance: per ray, by the ray's id
  // Chance: per ray, by its id, the nearest distance at which it passed glass (∞: none yet).
  // Embree offers candidates in no order, so one beyond the ray's hit may have passed too.
  float* passedAt = nullptr;

  explicit Context(AtGlass at,
                   RTCIntersectContextFlags flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT)
      : atGlass(at) {
    rtcInitIntersectContext(&embree);
    embree.flags = flags;
  }
};

AtGlass atGlass(Glass glass, RayTracer::Query query) {
  if (glass == Glass::Solid) return AtGlass::Stop;
  return query == RayTracer::Query::Intersect ? AtGlass::Chance : AtGlass::Open;
}

// The ray's own random number in [0, 1) at one crossing of a surface: a hash of its origin,
// direction and the crossing, so the same ray meets the same fate on any thread, however often
// Embree asks, and (but where the rounding splits the two distances) one fate at the edge two
// triangles share.
float chance(glm::vec3 origin, glm::vec3 direction, const Crossing& at) {
  uint64_t h = mix64(at.key());
  for (int k = 0; k < 3; ++k)
    h = mix64(h ^ ((uint64_t(floatBits(origin[k])) << 32) | floatBits(direction[k])));
  return float(h >> 40) * (1.0f / 16777216.0f);
}

// What a ray whose chance is u does at a surface that lets `t` through: it stops (the surface
// reflects) with probability 1 − open, passes with the grey transmittance, else is absorbed.
enum class Fate : uint8_t { Stop, Pass, Absorb };
Fate fateOf(float u, const scenes::Transmission& t) {
  const float stop = 1.0f - t.open;
  if (u < stop) return Fate::Stop;
  return u < stop + t.grey() ? Fate::Pass : Fate::Absorb;
}

// Shared by the intersection and occlusion filters of alpha-tested and transmissive
// geometries: rejecting a candidate hit makes Embree continue traversal past it.
void surfaceFilter(const RTCFilterFunctionNArguments* args) {
  const auto* geometry = static_cast<const Geometry*>(args->geometryUserPtr);
  const auto* context = reinterpret_cast<const Context*>(args->context);
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    const uint32_t triangle = RTCHitN_primID(args->hit, n, i);
    const float u = RTCHitN_u(args->hit, n, i);
    const float v = RTCHitN_v(args->hit, n, i);
    if (geometry->alphaTested && geometry->alpha(triangle, u, v) < geometry->alphaCutoff) {
      args->valid[i] = 0;
      continue;
    }
    if (!geometry->transmissive || context->atGlass == AtGlass::Stop) continue;
    const scenes::Transmission t = geometry->transmissionAt(triangle, u, v);
    // Embree puts the candidate's distance in the ray's tfar while a filter runs.
    const Crossing at{RTCHitN_geomID(args->hit, n, i), RTCRayN_tfar(args->ray, n, i)};
    bool passes = false;
    if (context->atGlass == AtGlass::Chance) {
      const glm::vec3 origin(RTCRayN_org_x(args->ray, n, i), RTCRayN_org_y(args->ray, n, i),
                             RTCRayN_org_z(args->ray, n, i));
      const glm::vec3 direction(RTCRayN_dir_x(args->ray, n, i), RTCRayN_dir_y(args->ray, n, i),
                                RTCRayN_dir_z(args->ray, n, i));
      passes = fateOf(chance(origin, direction, at), t) == Fate::Pass;
      float& passed = context->passedAt[RTCRayN_id(args->ray, n, i)];
      if (passes) passed = std::min(passed, at.t);
    } else if (context->atGlass == AtGlass::Open) {
      passes = t.grey() > 0.0f;
    } else {
      Layers& layers = context->layers[RTCRayN_id(args->ray, n, i)];
      passes = layers.add(at, context->grey ? glm::vec3(t.grey()) : t.rgb());
    }
    if (passes) args->valid[i] = 0;
  }
}


// Rays Embree must not see: it asserts tnear ≤ tfar and finite inputs only in debug builds.
bool traceable(const Ray& ray) {
  return finite(ray.origin) && finite(ray.direction) && ray.tnear <= ray.tfar &&
         !std::isnan(ray.tfar) && ray.direction != glm::vec3(0.0f);
}

void toEmbree(const Ray& ray, RTCRay& out) {
  out.org_x = ray.origin.x;
  out.org_y = ray.origin.y;
  out.org_z = ray.origin.z;
  out.tnear = ray.tnear > 0.0f ? ray.tnear : 0.0f;
  out.dir_x = ray.direction.x;
  out.dir_y = ray.direction.y;
  out.dir_z = ray.direction.z;
  out.time = 0.0f;
  out.tfar = ray.tfar;
  out.mask = ray.mask;
  out.id = 0;
  out.flags = 0;
}

void toEmbree(const Ray& ray, RTCRayHit& out) {
  toEmbree(ray, out.ray);
  out.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  out.hit.primID = RTC_INVALID_GEOMETRY_ID;
  out.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

glm::mat3 cofactor(const glm::mat3& m) {
  return glm::mat3(glm::cross(m[1], m[2]), glm::cross(m[2], m[0]), glm::cross(m[0], m[1]));
}

// Per-thread ray counters. The first kCounterSlots threads that trace each own one cache line
// and count with a plain relaxed load and store (a locked add per ray cost ~4% of a Cornell-box
// ray); later threads share an overflow slot and pay for fetch_add.
constexpr size_t kCounterSlots = 64;
struct alignas(64) Counter {
  std::atomic<uint64_t> rays[2] = {};  // RayTracer::Query::Intersect, Occluded
};

// The calling thread's own slot, or kCounterSlots for the shared overflow slot.
size_t threadSlot() {
  static std::atomic<size_t> next{0};
  thread_local const size_t slot =
      std::min(next.fetch_add(1, std::memory_order_relaxed), kCounterSlots);
  return slot;
}

}  // namespace

struct RayTracer::Impl {
  const scenes::Scene* scene = nullptr;
  RayTracerOptions options;
  RayTracerStats stats;
  RTCDevice device = nullptr;
  RTCScene rtcScene = nullptr;
  std::vector<Geometry> geometries;  // indexed by Embree geomID

  std::mutex errorMutex;
  std::string firstError;

  // Embree's own allocations, from its memory monitor (called from its build threads).
  std::atomic<int64_t> embreeBytes{0};
  std::atomic<int64_t> embreePeakBytes{0};

  mutable std::array<Counter, kCounterSlots + 1> counters;  // + the overflow slot

  ~Impl() {
    if (rtcScene) rtcReleaseScene(rtcScene);
    if (device) rtcReleaseDevice(device);
  }

  void count(uint64_t rays, Query query) const {
    const size_t slot = threadSlot();
    std::atomic<uint64_t>& c = counters[slot].rays[query == Query::Intersect ? 0 : 1];
    if (slot < kCounterSlots)
      c.store(c.load(std::memory_order_relaxed) + rays, std::memory_order_relaxed);
    else
      c.fetch_add(rays, std::memory_order_relaxed);
  }

  static void onError(void* user, RTCError code, const char* message) {
    auto* self = static_cast<Impl*>(user);
    std::lock_guard<std::mutex> lock(self->errorMutex);
    if (self->firstError.empty())
      self->firstError = format("Embree error %d: %s", int(code), message ? message : "");
  }

  static bool onMemory(void* user, ssize_t bytes, bool post) {
    auto* self = static_cast<Impl*>(user);
    const int64_t now = self->embreeBytes.fetch_add(int64_t(bytes)) + int64_t(bytes);
    int64_t peak = self->embreePeakBytes.load();
    while (now > peak && !self->embreePeakBytes.compare_exchange_weak(peak, now)) {
    }
    return true;
  }

  std::string takeError() {
    std::lock_guard<std::mutex> lock(errorMutex);
    std::string e = firstError;
    if (e.empty() && device) {
      const RTCError code = rtcGetDeviceError(device);
      if (code != RTC_ERROR_NONE) e = format("Embree error %d", int(code));
    }
    return e;
  }

  Status addGeometry(uint32_t instanceIndex, uint32_t primitiveIndex);

  // Whether a material is glass, once per material (a BLEND material's texture is searched
  // for an alpha below 1): -1 unknown, else 0 or 1.
  std::vector<int8_t> transmissiveMaterial;
  void setTransmission(Geometry& g, int material) {
    const size_t slot = size_t(material + 1);  // -1: glTF's default material
    if (transmissiveMaterial.size() <= slot) transmissiveMaterial.resize(slot + 1, -1);
    const bool blend = !options.blendAsMask;
    if (transmissiveMaterial[slot] < 0)
      transmissiveMaterial[slot] = scenes::transmissive(*scene, material, blend) ? 1 : 0;
    if (!transmissiveMaterial[slot]) return;
    const scenes::Material& m = scene->material(material);
    g.transmissive = true;
    g.blend = blend;
    g.scene = scene;
    g.material = material;
    g.transmissionTextured = m.baseColorTexture.valid() || m.transmissionTexture.valid();
    g.transmission = scenes::transmission(*scene, material, glm::vec2(0.0f), blend);
  }

  // `chance`: the query let rays through glass by their own chance (AtGlass::Chance), so a
  // ray that ended in glass was stopped or absorbed, as the filter decided alike; `passedAt`:
  // the nearest glass it passed (Context::passedAt).
  Hit toHit(const Ray& ray, const RTCRayHit& rh, bool chance, float passedAt) const {
    Hit hit;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
      hit.throughGlass = chance && passedAt < std::numeric_limits<float>::infinity();
      return hit;
    }
    hit.throughGlass = chance && passedAt < rh.ray.tfar;
    const Geometry& g = geometries[rh.hit.geomID];
    if (chance && g.transmissive)
      hit.absorbed = fateOf(trace::chance(glm::vec3(rh.ray.org_x, rh.ray.org_y, rh.ray.org_z),
                                          glm::vec3(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z),
                                          Crossing{rh.hit.geomID, rh.ray.tfar}),
                            g.transmissionAt(rh.hit.primID, rh.hit.u, rh.hit.v)) == Fate::Absorb;
    hit.t = rh.ray.tfar;
    hit.instance = g.instance;
    hit.primitive = g.primitive;
    hit.triangle = rh.hit.primID;
    hit.geometry = rh.hit.geomID;
    hit.barycentric = glm::vec2(rh.hit.u, rh.hit.v);
    const glm::vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    const float length = glm::length(ng);
    hit.geometricNormal = length > 0.0f ? ng * (g.frontSign / length) : glm::vec3(0.0f);
    hit.frontFace = glm::dot(ray.direction, hit.geometricNormal) < 0.0f;
    return hit;
  }
};

Status RayTracer::Impl::addGeometry(uint32_t instanceIndex, uint32_t primitiveIndex) {
  const scenes::Instance& inst = scene->instances[instanceIndex];
  const scenes::Primitive& prim = scene->meshes[size_t(inst.mesh)].primitives[primitiveIndex];
  const size_t triangles = prim.triangleCount();
  const size_t vertexCount = prim.positions.size();
  if (triangles == 0 || vertexCount == 0) return Status::ok();
  if (vertexCount > size_t(UINT32_MAX) || triangles > size_t(UINT32_MAX))
    return Status::error(format("instance '%s' primitive %u: too large for 32-bit indices",
                                inst.name.c_str(), primitiveIndex));

  Geometry g;
  g.instance = instanceIndex;
  g.primitive = primitiveIndex;
  g.source = &prim;
  const glm::mat3 linear(inst.transform);
  const float det = glm::determinant(linear);
  g.frontSign = det < 0.0f ? -1.0f : 1.0f;
  g.normalMatrix = g.frontSign * cofactor(linear);

  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  if (!geom) return Status::error("Embree could not create a triangle geometry: " + takeError());
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertexCount));
  auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), triangles));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geom);
    return Status::error(format("instance '%s' primitive %u: Embree buffer allocation failed: %s",
                                inst.name.c_str(), primitiveIndex, takeError().c_str()));
  }

  // Non-finite vertices (a NaN transform, say) would poison the BVH bounds; they are parked on
  // a finite vertex and every triangle touching them is made degenerate, which Embree never
  // hits, so triangle ids keep matching the primitive.
  std::vector<bool> bad(vertexCount, false);
  glm::vec3 parking(0.0f);
  bool haveParking = false;
  for (size_t i = 0; i < vertexCount; ++i) {
    const glm::vec3 w = inst.toWorld(prim.positions[i]);
    if (finite(w)) {
      if (!haveParking) parking = w, haveParking = true;
    } else {
      bad[i] = true;
    }
    vertices[3 * i] = w.x;
    vertices[3 * i + 1] = w.y;
    vertices[3 * i + 2] = w.z;
  }
  for (size_t i = 0; i < vertexCount; ++i) {
    if (!bad[i]) continue;
    vertices[3 * i] = parking.x;
    vertices[3 * i + 1] = parking.y;
    vertices[3 * i + 2] = parking.z;
  }
  for (size_t t = 0; t < triangles; ++t) {
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      const uint32_t index = prim.indices[3 * t + size_t(k)];
      ok = ok && index < vertexCount && !bad[index];
    }
    for (int k = 0; k < 3; ++k) indices[3 * t + size_t(k)] = ok ? prim.indices[3 * t + size_t(k)] : 0u;
    if (!ok) ++stats.invalidTriangles;
  }
  g.vertices = vertices;
  g.indices = indices;
  if (const std::vector<glm::vec2>& uvs = scenes::lightmapUvs(prim, options.lightmapUvSet);
      uvs.size() == vertexCount) {
    g.lightmapUv.resize(3 * triangles);
    for (size_t i = 0; i < 3 * triangles; ++i) g.lightmapUv[i] = uvs[indices[i]];
  }

  rtcSetGeometryMask(geom, kMaskVisible | (inst.castShadows ? kMaskShadowCasters : 0u));

  const scenes::Material& material = scene->material(prim.material);
  setTransmission(g, prim.material);
  const bool cutOut = options.alphaTest &&
                      (material.alphaMode == scenes::AlphaMode::Mask ||
                       (material.alphaMode == scenes::AlphaMode::Blend && options.blendAsMask));
  if (cutOut) {
    g.alphaTested = true;
    g.alphaFactor = material.baseColorFactor.a;
    g.alphaCutoff = material.alphaCutoff;
    const scenes::TextureRef& ref = material.baseColorTexture;
    const std::vector<glm::vec2>* uv = ref.texCoord == 0   ? &prim.uv0
                                       : ref.texCoord == 1 ? &prim.uv1
                                                           : nullptr;
    if (ref.valid() && size_t(ref.texture) < scene->textures.size() &&
        scene->textures[size_t(ref.texture)].loaded() && uv && uv->size() == vertexCount) {
      g.alphaTexture = &scene->textures[size_t(ref.texture)];
      g.alphaRef = &ref;
      g.alphaUv = uv;
    }
    // Untextured and above the cutoff everywhere: no need to pay for filter calls.
    if (!g.alphaTexture && g.alphaFactor >= g.alphaCutoff) g.alphaTested = false;
  }

  const uint32_t id = uint32_t(geometries.size());
  geometries.push_back(g);
  if (g.alphaTested || g.transmissive) {
    // geometries is reserved up front, so this pointer stays valid.
    rtcSetGeometryUserData(geom, &geometries.back());
    rtcSetGeometryIntersectFilterFunction(geom, surfaceFilter);
    rtcSetGeometryOccludedFilterFunction(geom, surfaceFilter);
    if (g.alphaTested) ++stats.alphaTestedGeometries;
    if (g.transmissive) ++stats.transmissiveGeometries;
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(rtcScene, geom, id);
  rtcReleaseGeometry(geom);
  ++stats.geometries;
  stats.triangles += triangles;
  const std::string error = takeError();
  if (!error.empty())
    return Status::error(format("instance '%s' primitive %u: %s", inst.name.c_str(),
                                primitiveIndex, error.c_str()));
  return Status::ok();
}

Result<std::unique_ptr<RayTracer>> RayTracer::build(const scenes::Scene& scene,
                                                    const RayTracerOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto impl = std::make_unique<Impl>();
  impl->scene = &scene;
  impl->options = options;
  impl->device = rtcNewDevice(nullptr);
  if (!impl->device)
    return Result<std::unique_ptr<RayTracer>>::error(
        format("Embree device creation failed (error %d)", int(rtcGetDeviceError(nullptr))));
  rtcSetDeviceErrorFunction(impl->device, &Impl::onError, impl.get());
  rtcSetDeviceMemoryMonitorFunction(impl->device, &Impl::onMemory, impl.get());

  impl->rtcScene = rtcNewScene(impl->device);
  if (!impl->rtcScene)
    return Result<std::unique_ptr<RayTracer>>::error("Embree scene creation failed: " +
                                                     impl->takeError());
  rtcSetSceneFlags(impl->rtcScene, options.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(impl->rtcScene, options.highQualityBuild ? RTC_BUILD_QUALITY_HIGH
                                                                   : RTC_BUILD_QUALITY_MEDIUM);

  size_t total = 0;
  for (const scenes::Instance& inst : scene.instances)
    if (inst.mesh >= 0 && size_t(inst.mesh) < scene.meshes.size())
      total += scene.meshes[size_t(inst.mesh)].primitives.size();
  impl->geometries.reserve(total);

  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const scenes::Instance& inst = scene.instances[i];
    if (inst.mesh < 0 || size_t(inst.mesh) >= scene.meshes.size()) {
      ++impl->stats.skippedInstances;
      continue;
    }
    const size_t primitives = scene.meshes[size_t(inst.mesh)].primitives.size();
    for (size_t p = 0; p < primitives; ++p) {
      Status status = impl->addGeometry(uint32_t(i), uint32_t(p));
      if (!status) return Result<std::unique_ptr<RayTracer>>(status);
    }
  }

  rtcCommitScene(impl->rtcScene);
  const std::string error = impl->takeError();
  if (!error.empty())
    return Result<std::unique_ptr<RayTracer>>::error("building the ray-tracing BVH: " + error);
  impl->stats.embreeBytes = size_t(std::max<int64_t>(0, impl->embreeBytes.load()));
  impl->stats.embreePeakBytes = size_t(std::max<int64_t>(0, impl->embreePeakBytes.load()));
  impl->stats.buildSeconds = secondsSince(start);
  return std::unique_ptr<RayTracer>(new RayTracer(std::move(impl)));
}

RayTracer::RayTracer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RayTracer::~RayTracer() = default;

Hit RayTracer::intersect(const Ray& ray, Glass glass) const {
  impl_->count(1, Query::Intersect);
  if (!traceable(ray)) return Hit{};
  Context context(atGlass(glass, Query::Intersect));
  float passedAt = std::numeric_limits<float>::infinity();
  context.passedAt = &passedAt;
  RTCRayHit rh;
  toEmbree(ray, rh);  // id 0: passedAt
  rtcIntersect1(impl_->rtcScene, &context.embree, &rh);
  return impl_->toHit(ray, rh, context.atGlass == AtGlass::Chance, passedAt);
}

bool RayTracer::occluded(const Ray& ray, Glass glass) const {
  impl_->count(1, Query::Occluded);
  if (!traceable(ray)) return false;
  Context context(atGlass(glass, Query::Occluded));
  RTCRay r;
  toEmbree(ray, r);
  rtcOccluded1(impl_->rtcScene, &context.embree, &r);
  // Embree marks an occluded ray by setting tfar to -inf.
  return r.tfar < 0.0f;
}

glm::vec3 RayTracer::transmittance(const Ray& ray) const {
  impl_->count(1, Query::Occluded);
  if (!traceable(ray)) return glm::vec3(1.0f);
  Layers layers;
  Context context(AtGlass::Transmittance);
  context.layers = &layers;
  RTCRay r;
  toEmbree(ray, r);  // id 0: layers[0]
  rtcOccluded1(impl_->rtcScene, &context.embree, &r);
  return r.tfar < 0.0f ? glm::vec3(0.0f) : layers.value;
}

scenes::Transmission RayTracer::transmission(const Hit& hit) const {
  if (!hit.valid()) return {};
  const Geometry& g = impl_->geometries[hit.geometry];
  if (!g.transmissive) return {};
  return g.transmissionAt(hit.triangle, hit.barycentric.x, hit.barycentric.y);
}

bool RayTracer::transmissive(const Hit& hit) const {
  return hit.valid() && impl_->geometries[hit.geometry].transmissive;
}

bool RayTracer::hasGlass() const { return impl_->stats.transmissiveGeometries > 0; }

namespace {

// A batch of rays in Embree's layout, ordered one direction octant after another (a stable
// counting sort), for coherent ray streams: a batch's rays leave a few neighbouring texels, so
// the rays of one octant form packets that traverse the BVH together. On the Cornell box that
// makes about 1.3x the rays per second of rtcIntersect1 on the same rays, where unsorted
// streams, or packets of one texel's rays (all over the hemisphere), are slower than it. Each
// ray's hit is the one rtcIntersect1 would give.
struct OctantStream {
  std::vector<RTCRayHit> rays;
  std::vector<uint32_t> order;  // position in the stream -> index of the caller's ray
  std::vector<uint8_t> octant;  // per caller's ray, kUntraceable when Embree must not see it
  static constexpr uint8_t kUntraceable = 8;

  // Fills the stream from `in`, and an empty hit for every ray Embree must not see; returns
  // how many rays the stream holds.
  uint32_t fill(const Ray* in, Hit* hits, size_t count) {
    octant.resize(count);
    // The octants' sizes, counted as runs: consecutive rays mostly share an octant, and
    // incrementing one counter per ray would make every increment wait for the one before.
    uint32_t size[9] = {};
    uint8_t run = kUntraceable;
    uint32_t runLength = 0;
    for (size_t i = 0; i < count; ++i) {
      const Ray& r = in[i];
      const uint8_t k = !traceable(r) ? kUntraceable
                        : uint8_t((r.direction.x < 0.0f ? 1 : 0) |
                                  (r.direction.y < 0.0f ? 2 : 0) |
                                  (r.direction.z < 0.0f ? 4 : 0));
      octant[i] = k;
      if (k != run) {
        size[run] += runLength;
        run = k;
        runLength = 0;
      }
      ++runLength;
    }
    size[run] += runLength;
    uint32_t start[9];
    for (int k = 0, at = 0; k < 9; ++k) {
      start[k] = uint32_t(at);
      at += int(size[k]);
    }
    const uint32_t traced = start[kUntraceable];
    rays.resize(traced);
    order.resize(traced);
    for (size_t i = 0; i < count; ++i) {
      const uint8_t k = octant[i];
      if (k == kUntraceable) {
        hits[i] = Hit{};
        continue;
      }
      const uint32_t at = start[k]++;
      order[at] = uint32_t(i);
      toEmbree(in[i], rays[at]);
    }
    return traced;
  }
};

}  // namespace

void RayTracer::intersect(const Ray* rays, Hit* hits, size_t count, Glass glass) const {
  impl_->count(count, Query::Intersect);
  thread_local OctantStream stream;
  const uint32_t traced = stream.fill(rays, hits, count);
  if (traced == 0) return;
  Context context(atGlass(glass, Query::Intersect), RTC_INTERSECT_CONTEXT_FLAG_COHERENT);
  const bool chance = context.atGlass == AtGlass::Chance;
  thread_local std::vector<float> passedAt;
  if (chance && hasGlass()) {
    passedAt.assign(traced, std::numeric_limits<float>::infinity());
    for (uint32_t k = 0; k < traced; ++k) stream.rays[k].ray.id = k;
    context.passedAt = passedAt.data();
  }
  rtcIntersect1M(impl_->rtcScene, &context.embree, stream.rays.data(), traced,
                 sizeof(RTCRayHit));
  const float never = std::numeric_limits<float>::infinity();
  for (uint32_t k = 0; k < traced; ++k) {
    const uint32_t i = stream.order[k];
    hits[i] = impl_->toHit(rays[i], stream.rays[k], chance,
                           context.passedAt ? passedAt[k] : never);
  }
}

namespace {

// Traces rays as occlusion queries in packets of 16 consecutive rays and calls
// seen(i, lane, blocked) for each: a receiver's shadow rays toward one light share an origin
// and nearly a direction, and sight lines between neighbouring texels are short and close
// together, the coherent cases Embree's packet traversal is made for. On the Cornell box that
// is two to three times the rays per second of rtcOccluded1 on the same rays; sorting them by
// octant first, or a coherent stream as for intersect, is slower. Rays Embree must not see
// are not traced (blocked false). Each ray's id is its lane, for the filters' per-ray state.
template <class Begin, class Seen>
void occludedPackets(RTCScene scene, Context& context, const Ray* rays, size_t count,
                     Begin&& beginPacket, Seen&& seen) {
  constexpr size_t kPacket = 16;
  alignas(64) RTCRay16 packet;
  alignas(64) int valid[kPacket];
  for (size_t base = 0; base < count; base += kPacket) {
    const size_t n = std::min(kPacket, count - base);
    beginPacket();
    if (n == 1) {  // a lone ray: the single-ray call skips the packet's setup
      if (!traceable(rays[base])) {
        seen(base, 0, false);
        continue;
      }
      RTCRay r;
      toEmbree(rays[base], r);
      rtcOccluded1(scene, &context.embree, &r);
      seen(base, 0, r.tfar < 0.0f);
      continue;
    }
    for (size_t i = 0; i < kPacket; ++i) {
      const Ray* r = i < n ? &rays[base + i] : nullptr;
      valid[i] = (r && traceable(*r)) ? -1 : 0;
      RTCRay one;
      if (valid[i]) toEmbree(*r, one);
      else std::memset(&one, 0, sizeof(one));
      packet.org_x[i] = one.org_x;
      packet.org_y[i] = one.org_y;
      packet.org_z[i] = one.org_z;
      packet.tnear[i] = one.tnear;
      packet.dir_x[i] = one.dir_x;
      packet.dir_y[i] = one.dir_y;
      packet.dir_z[i] = one.dir_z;
      packet.time[i] = 0.0f;
      packet.tfar[i] = valid[i] ? one.tfar : -1.0f;
      packet.mask[i] = one.mask;
      packet.id[i] = unsigned(i);
      packet.flags[i] = 0;
    }
    rtcOccluded16(valid, scene, &context.embree, &packet);
    for (size_t i = 0; i < n; ++i) seen(base + i, i, valid[i] && packet.tfar[i] < 0.0f);
  }
}

}  // namespace

void RayTracer::occluded(const Ray* rays, bool* blocked, size_t count, Glass glass) const {
  impl_->count(count, Query::Occluded);
  Context context(atGlass(glass, Query::Occluded));
  occludedPackets(impl_->rtcScene, context, rays, count, [] {},
                  [&](size_t i, size_t, bool b) { blocked[i] = b; });
}

void RayTracer::greyTransmittance(const Ray* rays, float* out, size_t count) const {
  impl_->count(count, Query::Occluded);
  Layers layers[16];
  Context context(AtGlass::Transmittance);
  context.grey = true;
  context.layers = layers;
  // Without glass no filter touches the layers: a ray gets through whole or not at all.
  const bool glass = hasGlass();
  occludedPackets(impl_->rtcScene, context, rays, count,
                  [&] {
                    if (glass)
                      for (Layers& l : layers) l.clear();
                  },
                  [&](size_t i, size_t lane, bool b) {
                    out[i] = b ? 0.0f : glass ? layers[lane].value.x : 1.0f;
                  });
}

uint64_t RayTracer::raysTraced() const {
  return raysTraced(Query::Intersect) + raysTraced(Query::Occluded);
}

uint64_t RayTracer::raysTraced(Query query) const {
  uint64_t total = 0;
  const int k = query == Query::Intersect ? 0 : 1;
  for (const Counter& c : impl_->counters) total += c.rays[k].load(std::memory_order_relaxed);
  return total;
}

void RayTracer::resetRayCount() {
  for (Counter& c : impl_->counters)
    for (std::atomic<uint64_t>& r : c.rays) r.store(0, std::memory_order_relaxed);
}

glm::vec3 RayTracer::position(const Hit& hit) const {
  if (!hit.valid()) return glm::vec3(0.0f);
  const Geometry& g = impl_->geometries[hit.geometry];
  const uint32_t* t = g.indices + 3 * size_t(hit.triangle);
  const float u = hit.barycentric.x, v = hit.barycentric.y;
  return (1.0f - u - v) * g.vertex(t[0]) + u * g.vertex(t[1]) + v * g.vertex(t[2]);
}

glm::vec3 RayTracer::shadingNormal(const Hit& hit) const {
  if (!hit.valid()) return glm::vec3(0.0f);
  const Geometry& g = impl_->geometries[hit.geometry];
  const std::vector<glm::vec3>& normals = g.source->normals;
  if (normals.size() != g.source->positions.size()) return hit.geometricNormal;
  const uint32_t* t = g.indices + 3 * size_t(hit.triangle);
  const float u = hit.barycentric.x, v = hit.barycentric.y;
  const glm::vec3 n =
      g.normalMatrix * ((1.0f - u - v) * normals[t[0]] + u * normals[t[1]] + v * normals[t[2]]);
  const float length = glm::length(n);
  // Opposing vertex normals can cancel out; the geometric normal is the only sensible answer.
  if (!(length > 1e-12f) || !std::isfinite(length)) return hit.geometricNormal;
  return n / length;
}

const glm::vec2* RayTracer::lightmapUvs(const Hit& hit) const {
  if (!hit.valid()) return nullptr;
  const Geometry& g = impl_->geometries[hit.geometry];
  return g.lightmapUv.empty() ? nullptr : &g.lightmapUv[3 * size_t(hit.triangle)];
}

glm::vec2 RayTracer::uv(const Hit& hit, int set) const {
  if (!hit.valid()) return glm::vec2(0.0f);
  const Geometry& g = impl_->geometries[hit.geometry];
  if (set == 1 && !g.lightmapUv.empty() &&
      impl_->options.lightmapUvSet == scenes::LightmapUvSet::Lightmap)
    return mixCorners(&g.lightmapUv[3 * size_t(hit.triangle)], hit);
  const std::vector<glm::vec2>* uvs = set == 0   ? &g.source->uv0
                                      : set == 1 ? &g.source->uv1
                                      : set == 2 ? &g.source->indirectUv
                                                 : nullptr;
  if (!uvs || uvs->size() != g.source->positions.size()) return glm::vec2(0.0f);
  const uint32_t* t = g.indices + 3 * size_t(hit.triangle);
  const float u = hit.barycentric.x, v = hit.barycentric.y;
  return (1.0f - u - v) * (*uvs)[t[0]] + u * (*uvs)[t[1]] + v * (*uvs)[t[2]];
}

float RayTracer::triangleArea(const Hit& hit) const {
  if (!hit.valid()) return 0.0f;
  const Geometry& g = impl_->geometries[hit.geometry];
  const uint32_t* t = g.indices + 3 * size_t(hit.triangle);
  const glm::vec3 a = g.vertex(t[0]);
  return 0.5f * glm::length(glm::cross(g.vertex(t[1]) - a, g.vertex(t[2]) - a));
}

const scenes::Material& RayTracer::material(const Hit& hit) const {
  const int index = hit.valid() ? impl_->geometries[hit.geometry].source->material : -1;
  return impl_->scene->material(index);
}

const scenes::Scene& RayTracer::scene() const { return *impl_->scene; }
const RayTracerStats& RayTracer::stats() const { return impl_->stats; }

scenes::Bounds RayTracer::bounds() const {
  scenes::Bounds b;
  if (impl_->geometries.empty()) return b;
  RTCBounds rb;
  rtcGetSceneBounds(impl_->rtcScene, &rb);
  b.min = glm::vec3(rb.lower_x, rb.lower_y, rb.lower_z);
  b.max = glm::vec3(rb.upper_x, rb.upper_y, rb.upper_z);
  return b;
}

double RayTracer::measureRawThroughput(const Ray* rays, size_t count, Query query) const {
  if (count == 0) return 0.0;
  std::vector<RTCRayHit> prepared(count);
  for (size_t i = 0; i < count; ++i) toEmbree(rays[i], prepared[i]);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  // Summing a result keeps the compiler from dropping the loop and costs nothing measurable.
  volatile uint64_t sink = 0;
  uint64_t acc = 0;
  const auto start = std::chrono::steady_clock::now();
  if (query == Query::Intersect) {
    for (size_t i = 0; i < count; ++i) {
      RTCRayHit rh = prepared[i];
      rtcIntersect1(impl_->rtcScene, &context, &rh);
      acc += rh.hit.geomID;
    }
  } else {
    for (size_t i = 0; i < count; ++i) {
      RTCRay r = prepared[i].ray;
      rtcOccluded1(impl_->rtcScene, &context, &r);
      acc += r.tfar < 0.0f ? 1u : 0u;
    }
  }
  const double seconds = secondsSince(start);
  sink = acc;
  (void)sink;
  impl_->count(count, query);
  return seconds > 0.0 ? double(count) / seconds : 0.0;
}

}  // namespace afterglow::trace
