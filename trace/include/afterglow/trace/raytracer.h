// RayTracer: the one wrapper around Embree 3 that all of afterglow uses (the precompute's texels,
// direct light and form factors, the reference path tracer, probe placement, `afterglow render`).
// Embree types stay inside trace/src/raytracer.cpp; afterglow_trace is the only library that
// links Embree.
//
// Choices, and why:
// - Instances are flattened: every (instance, primitive) becomes one world-space triangle
//   geometry in a single-level BVH. A lightmapper traces billions of incoherent rays against a
//   static level; a flat BVH avoids the second traversal level and the per-instance ray
//   transform, and world-space vertices make position() exact. Memory is no reason for
//   instancing here: Sponza's 262k instanced triangles take 23 MB in Embree (31 MB peak during
//   the 0.2 s build), nothing next to the bake.
// - The BVH is built at RTC_BUILD_QUALITY_HIGH (build time is tiny next to the rays), and
//   RTC_SCENE_FLAG_ROBUST is on by default: rays leaving texels near wall corners must not slip
//   through the shared edge of two triangles, or light leaks. Measured in the furnace box: rays
//   aimed exactly at shared edges and vertices leak 15-25% of the time without the flag, and
//   only at exact cube corners (3 faces meeting, ~0.02%) with it.
// - Back faces are reported, never culled: Hit::frontFace says which side was hit and the baker
//   decides (a back-face hit on single-sided geometry marks a sample invalid).
// - alphaMode MASK materials get intersection and occlusion filters that sample base-colour
//   alpha (TEXCOORD per the TextureRef, KHR_texture_transform applied) × baseColorFactor.a and
//   let rays through below alphaCutoff, for every query.
// - Glass: alphaMode BLEND and KHR_materials_transmission let light through, a fraction `open`
//   tinted by the base colour (scenes::transmission in material_eval.h: 1 − alpha for BLEND,
//   the transmission for KHR_materials_transmission); the rest meets the surface, which
//   reflects it with its bounce albedo. What a query does with such a surface is the caller's
//   choice (Glass): geometry questions (where a texel's sample may sit, whether a wall
//   separates two texels, where probes may go, what a camera sees) take it as solid, as
//   before; light takes it as glass. Light-carrying rays cannot split, so an intersect with
//   Glass::Light lets each ray through at random with the surface's grey transmittance
//   (Transmission::grey, the precompute's scalar transport), stops it with probability
//   1 − open (the surface reflects), and absorbs the rest (Hit::absorbed: the tint took it).
//   The random number is a hash of the ray's origin and direction and the triangle, so a ray
//   meets the same fate whichever thread traces it, as often as it is traced. Shadow rays need
//   no chance: transmittance() and greyTransmittance() multiply the transmittance of every
//   transmissive surface along the segment (0 at an opaque one), and an occluded() with
//   Glass::Light blocks only where no light gets through. Only transmissive geometries get
//   filters, so a scene without glass traces exactly as fast, and the same rays, as before.
//   RayTracerOptions::blendAsMask cuts BLEND out at its alphaCutoff instead (for foliage
//   wrongly authored as BLEND).
// - Ray masks: every geometry carries kMaskVisible; shadow-casting instances also carry
//   kMaskShadowCasters. Shadow and visibility rays use kMaskShadowCasters so instances with
//   castShadows = false are skipped; camera and gather rays use the default mask (all bits).
//
// Thread safety: build() once, then every const member may be called from many threads at
// once. The Scene passed to build() must outlive the RayTracer (normals, UVs, materials and
// textures are read from it, not copied).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>

#include <glm/glm.hpp>

#include "afterglow/core/status.h"
#include "afterglow/scenes/material_eval.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::trace {

// Geometry mask bits (see the header comment).
constexpr uint32_t kMaskVisible = 1u << 0;        // every geometry
constexpr uint32_t kMaskShadowCasters = 1u << 1;  // instances with castShadows = true
constexpr uint32_t kMaskAll = ~0u;                // camera and gather rays

constexpr uint32_t kInvalidId = ~0u;

// A ray segment [tnear, tfar] along origin + t·direction. direction need not be unit length;
// t is then measured in multiples of it.
struct Ray {
  glm::vec3 origin{0.0f};
  float tnear = 0.0f;                                     // world units along direction
  glm::vec3 direction{0.0f, 0.0f, 1.0f};
  float tfar = std::numeric_limits<float>::infinity();   // world units along direction
  uint32_t mask = kMaskAll;  // hits geometry whose mask shares a bit with this
};

// How a query treats transmissive surfaces (glass; see the header comment).
enum class Glass : uint8_t {
  Solid,  // they stop rays like any other surface (geometry questions)
  Light,  // as light meets them: intersect passes, stops or absorbs each ray by its own chance;
          // occluded blocks only where no light gets through
};

struct Hit {
  float t = std::numeric_limits<float>::infinity();  // ray parameter of the hit
  uint32_t instance = kInvalidId;   // index into Scene::instances
  uint32_t primitive = kInvalidId;  // index into that instance's Mesh::primitives
  uint32_t triangle = kInvalidId;   // triangle index within the primitive
  uint32_t geometry = kInvalidId;   // the tracer's internal geometry index (for its helpers)
  // Embree's u, v: point = (1-u-v)·v0 + u·v1 + v·v2 for the triangle's vertices in index order.
  glm::vec2 barycentric{0.0f};
  // World space, unit length, pointing out of the glTF front side (counter-clockwise winding,
  // clockwise when the instance transform mirrors, as glTF defines).
  glm::vec3 geometricNormal{0.0f};
  bool frontFace = false;  // the ray arrived on the side geometricNormal points to
  // Glass::Light intersect: the ray ended in a transmissive surface's tint (it carries no light
  // from here, and sees no sky); false for a ray the surface stopped, which sees the surface.
  bool absorbed = false;
  // Glass::Light intersect: the ray passed glass before its hit (or, for a miss, on its way
  // out to the sky).
  bool throughGlass = false;

  bool valid() const { return instance != kInvalidId; }
};

struct RayTracerOptions {
  bool robust = true;            // RTC_SCENE_FLAG_ROBUST: no rays through shared edges; on
                                 // Sponza ~25% slower intersect, occluded about the same
  bool highQualityBuild = true;  // RTC_BUILD_QUALITY_HIGH (SAH with spatial splits) vs MEDIUM
  bool alphaTest = true;         // cut out alphaMode MASK materials (false: all opaque)
  bool blendAsMask = false;      // cut out alphaMode BLEND materials at their alphaCutoff
                                 // instead of letting light through them as glass
  // The lightmap UVs lightmapUvs() and lightmapUv() give: TEXCOORD_1, or the indirect grid's
  // (the precompute's texels when bounced light is solved coarse).
  scenes::LightmapUvSet lightmapUvSet = scenes::LightmapUvSet::Lightmap;
};

// What build() did with the scene, for report.json and warnings.
struct RayTracerStats {
  size_t geometries = 0;          // Embree geometries (one per instance × primitive)
  size_t triangles = 0;           // world-space triangles handed to Embree
  size_t alphaTestedGeometries = 0;
  size_t transmissiveGeometries = 0;  // glass: BLEND or KHR_materials_transmission
  size_t invalidTriangles = 0;    // out-of-range indices or non-finite vertices, made degenerate
  size_t skippedInstances = 0;    // instances with no valid mesh
  double buildSeconds = 0.0;
  size_t embreeBytes = 0;         // held by Embree after the build (vertices, indices, BVH)
  size_t embreePeakBytes = 0;     // Embree's peak during the build
};

class RayTracer {
 public:
  // Builds the BVH over every instance of the scene. Embree errors come back as a Status.
  static Result<std::unique_ptr<RayTracer>> build(const scenes::Scene& scene,
                                                  const RayTracerOptions& options = {});
  // The tracer reads the scene after build(), so a temporary scene would dangle.
  static Result<std::unique_ptr<RayTracer>> build(scenes::Scene&& scene,
                                                  const RayTracerOptions& options = {}) = delete;
  ~RayTracer();
  RayTracer(const RayTracer&) = delete;
  RayTracer& operator=(const RayTracer&) = delete;

  // Closest hit; an invalid Hit on a miss.
  Hit intersect(const Ray& ray, Glass glass = Glass::Solid) const;
  // true when anything (after alpha cut-outs and masks) lies within [tnear, tfar]; with
  // Glass::Light, anything that lets no light through.
  bool occluded(const Ray& ray, Glass glass = Glass::Solid) const;
  // Batched forms: same results as the single-ray calls, and faster: Embree traces them
  // together (see raytracer.cpp). Intersect batches go as coherent streams sorted by direction
  // octant, best with rays from a few neighbouring points (hundreds to a few thousand);
  // occluded batches go as packets of 16 consecutive rays, best when neighbours in the batch
  // share an origin and nearly a direction (one receiver's shadow rays toward one light).
  void intersect(const Ray* rays, Hit* hits, size_t count, Glass glass = Glass::Solid) const;
  void occluded(const Ray* rays, bool* blocked, size_t count, Glass glass = Glass::Solid) const;
  // The light that gets through the segment [tnear, tfar]: the product of the transmissive
  // surfaces' Transmission::rgb() along it, 0 at anything opaque (1 where nothing lies). A
  // segment through more than 16 transmissive triangles counts as blocked.
  glm::vec3 transmittance(const Ray& ray) const;
  // The same per ray with each surface's Transmission::grey() (the precompute's scalar light),
  // traced as occluded() traces a batch; without glass in the scene exactly !occluded().
  void greyTransmittance(const Ray* rays, float* out, size_t count) const;
  // What the surface of a valid hit lets through there (nothing for an opaque one).
  scenes::Transmission transmission(const Hit& hit) const;
  // Whether a valid hit's geometry is transmissive anywhere (its material is glass).
  bool transmissive(const Hit& hit) const;
  // Whether any geometry is transmissive (stats().transmissiveGeometries > 0).
  bool hasGlass() const;

  enum class Query { Intersect, Occluded };
  // Rays traced so far by all threads (intersect and occluded, or one kind), including
  // measureRawThroughput.
  uint64_t raysTraced() const;
  uint64_t raysTraced(Query query) const;
  void resetRayCount();

  // Surface attributes at a valid hit.
  // World position interpolated from the triangle's world vertices (exact, unlike o + t·d).
  glm::vec3 position(const Hit& hit) const;
  // Interpolated vertex normal in world space, unit, on the front side (not flipped toward the
  // ray); the geometric normal when the primitive has no usable normals.
  glm::vec3 shadingNormal(const Hit& hit) const;
  // Interpolated UV of set 0 (TEXCOORD_0), 1 (TEXCOORD_1) or 2 (the indirect grid's,
  // Primitive::indirectUv); (0, 0) when the set is absent.
  glm::vec2 uv(const Hit& hit, int set) const;
  // The hit triangle's lightmap UVs (RayTracerOptions::lightmapUvSet) at its three corners, next
  // to each other (one cache line to prefetch), or nullptr without that set; mixCorners()
  // interpolates them.
  const glm::vec2* lightmapUvs(const Hit& hit) const;
  // Their value at the hit ((0, 0) without).
  glm::vec2 lightmapUv(const Hit& hit) const {
    const glm::vec2* corners = lightmapUvs(hit);
    return corners ? mixCorners(corners, hit) : glm::vec2(0.0f);
  }
  static glm::vec2 mixCorners(const glm::vec2* corners, const Hit& hit) {
    const float u = hit.barycentric.x, v = hit.barycentric.y;
    return (1.0f - u - v) * corners[0] + u * corners[1] + v * corners[2];
  }
  // World-space area of the hit triangle.
  float triangleArea(const Hit& hit) const;
  // The hit primitive's material (Scene::material, so the glTF default for -1); the baker reads
  // doubleSided from it to decide whether a back-face hit is valid.
  const scenes::Material& material(const Hit& hit) const;

  const scenes::Scene& scene() const;
  const RayTracerStats& stats() const;
  // World bounds of everything in the BVH.
  scenes::Bounds bounds() const;

  // Traces the rays on the calling thread with bare rtcIntersect1/rtcOccluded1 loops (no Hit
  // conversion, no counters) and returns rays per second, so a benchmark can compare the
  // wrapper's and the baker's throughput against Embree's raw one on the same rays.
  double measureRawThroughput(const Ray* rays, size_t count, Query query) const;

 private:
  struct Impl;
  explicit RayTracer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace afterglow::trace
