// Cosine-distributed gather rays in batches (GatherBatch): shared by the texels' gather
// (gather.cpp, gather_refine.cpp), the back-side clusters' rays (links.cpp) and the light
// probes' (probe_transfer.cpp), so that all of them classify hits the same way. The per-ray
// methods that queue rays stay inline; tracing and reading a batch are in gather_batch.cpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/gather.h"
#include "afterglow/baker/texels.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/trace/raytracer.h"
#include "precompute/sight_search.h"
#include "shading/sampling.h"

namespace afterglow::baker {

class GlassSky;
class TexelLookup;

// Cosine-distributed rays of one or several texels (or a cluster), traced together: the bigger
// the batch, the longer Embree runs before hit processing touches other memory.
class GatherBatch {
 public:
  // What a range of rays saw, summed.
  struct Summary {
    double sky[runtime::kShCount] = {};  // Σ SH basis over the rays that escaped
    int backfaces = 0;                   // rays that hit the back of single-sided geometry
    double inverseDistance = 0.0;        // Σ 1/t over rays that hit anything
    int close = 0;                       // rays that hit anything nearer than `near`
  };

  void clear() {
    rays_.clear();
    codes_.clear();
    skyShares_.clear();
    firstGlass_.clear();
  }
  // The sky through glass is also sampled through the glass (GlassSky): a ray whose first
  // surface is glass brings the sky beyond only with the balance heuristic's weight (through
  // summarize's GlassWeights), and none to skyShare.
  void setGlassSky(const GlassSky* sky) { glassSky_ = sky; }
  size_t size() const { return rays_.size(); }

  // Queues one cosine-distributed ray about the frame's normal. Directions below the geometric
  // surface are mirrored above it: a shading normal tilted away from the face must not send
  // rays into the surface the sample lies on.
  void add(glm::vec3 origin, const sampling::Frame& frame, glm::vec3 geometricNormal, glm::vec2 u) {
    glm::vec3 dir = frame.toWorld(sampling::cosineHemisphere(u));
    const float below = glm::dot(dir, geometricNormal);
    if (below < 0.0f) dir = glm::normalize(dir - 2.0f * below * geometricNormal);
    trace::Ray& ray = rays_.emplace_back();  // in place: a copy of a fresh Ray stalls store forwarding
    ray.origin = origin;
    ray.direction = dir;
  }

  // Queues one ray along a unit direction (the light probes' rays over the whole sphere).
  void addDirection(glm::vec3 origin, glm::vec3 direction) {
    trace::Ray& ray = rays_.emplace_back();
    ray.origin = origin;
    ray.direction = direction;
  }

  // Traces the rays queued since the last trace(); with `lookup`, also finds the texel each
  // hit lands on (codes()), without, only what summarize() needs. The rays go through glass as
  // light does (trace::Glass::Light: each passes, stops or is absorbed by its own chance), so
  // a texel behind a window sees the sky and the room beyond it in the window's proportion.
  // With `sightLines` off, a hit on a texel near other geometry takes that texel without the
  // check that its sample is in sight (TexelOfHit): cheaper, for rays whose hits are averaged
  // over many directions anyway (the light probes').
  void trace(const trace::RayTracer& tracer, const TexelSet& texels, const TexelLookup* lookup,
             bool sightLines = true);

  // The albedo codes (TexelGather::hitAlbedo) of rays [from, from + n)'s hits into out: on the
  // front of a textured material nearer than maxDistance, the texture's grey modulation at the
  // hit (the diffuse albedo over the material's factor, as the transport's
  // clusterAlbedoTexture); else 0. A hit is a point sample: of a large texture (256 texels or
  // more a side) its nearest texel serves as well as the bilinear lookup, and reads a quarter
  // as much; a small one is read bilinearly, as the reference reads it. The base colour texels
  // are prefetched first: scattered reads over large textures are what this costs (the
  // precompute's ray rate fell from 71% of raw Embree's to 67% without, on Sponza).
  void albedoCodes(const scenes::Scene& scene, const trace::RayTracer& tracer, size_t from, size_t n,
                   float maxDistance, uint8_t* out);

  // Per traced ray, a TexelGather hit code.
  const std::vector<uint32_t>& codes() const { return codes_; }
  // Per traced ray, what it hit, and the ray.
  const std::vector<trace::Hit>& hits() const { return hits_; }
  const std::vector<trace::Ray>& rays() const { return rays_; }

  // How summarize weighs the rays whose first surface is glass against GlassSky's samples: the
  // rays' origin's shading normal, their number and the most samples (GlassSky::rayWeight,
  // GlassSky::samplesFor).
  struct GlassWeights {
    glm::vec3 normal;
    uint32_t rays, samples;
  };
  // Sky: Σ over the rays of what each lets through to the sky × the SH basis of its direction
  // (with `glass`, from one origin, the rays through glass weighed against its samples).
  Summary summarize(const trace::RayTracer& tracer, size_t first, size_t last, float near = 0.0f,
                    const GlassWeights* glass = nullptr) const;

  // What traced ray k lets through to the sky: 1 for a miss, 0 for a hit, except where glass
  // is met (skyThroughGlass).
  float skyShare(size_t k) const {
    if (!skyShares_.empty()) return skyShares_[k];
    return hits_[k].valid() ? 0.0f : 1.0f;
  }

 private:
  void skyThroughGlass(const trace::RayTracer& tracer, size_t first);
  // trace()'s steps after Embree's, in order.
  void findSlots(const trace::RayTracer& tracer, const TexelLookup& lookup, size_t first);
  void resolveTexels(const trace::RayTracer& tracer, const TexelSet& texels,
                     const TexelLookup& lookup, size_t first, bool sightLines);
  void checkSightLines(const trace::RayTracer& tracer, const TexelSet& texels);
  void keepTexelsBehindGlass(const trace::RayTracer& tracer);
  bool checkLights(const trace::RayTracer& tracer, const TexelSet& texels,
                   const TexelLookup& lookup, size_t first);
  void matchLights(const trace::RayTracer& tracer, const TexelSet& texels,
                   const TexelLookup& lookup);

  // Ray k's code: texel t (kNoTexel: none), on the side the ray arrived at.
  void setCode(size_t k, uint32_t t) {
    if (t != runtime::kNoTexel)
      codes_[k] = hits_[k].frontFace ? t : (t | TexelGather::kBackSide);
  }

  // Ray k's own number in [0, 1), a hash of its origin and direction: the same for the same
  // ray whichever thread traces it.
  float rayChance(size_t k) const {
    uint64_t h = 0;
    for (int i = 0; i < 3; ++i)
      h = sampling::mix64(h ^ ((uint64_t(floatBits(rays_[k].origin[i])) << 32) |
                               floatBits(rays_[k].direction[i])));
    return float(h >> 40) * (1.0f / 16777216.0f);
  }
  static uint32_t floatBits(float f) {
    uint32_t b;
    std::memcpy(&b, &f, sizeof(b));
    return b;
  }

  // Where ray k hit (TexelOfHit: the ray's own arithmetic is close enough).
  glm::vec3 hitPoint(size_t k) const { return rays_[k].origin + hits_[k].t * rays_[k].direction; }

  // What a hit's geometry is, per geometry looked up once (a hit's material and instance sit
  // behind several dependent loads): kStatic, kBackReflects for double-sided materials, kGlass
  // for transmissive ones.
  static constexpr uint8_t kStatic = 1, kBackReflects = 2, kGlass = 4, kUnknown = 0xff;
  uint8_t sides(const trace::RayTracer& tracer, const trace::Hit& hit) const {
    if (hit.geometry >= sides_.size()) sides_.resize(size_t(hit.geometry) + 1, kUnknown);
    uint8_t& s = sides_[hit.geometry];
    if (s == kUnknown)
      s = uint8_t((tracer.scene().instances[hit.instance].isStatic ? kStatic : 0) |
                  (tracer.material(hit).doubleSided ? kBackReflects : 0) |
                  (tracer.transmissive(hit) ? kGlass : 0));
    return s;
  }

  // A hit on a surface that takes part in bounces: static, and seen from a side that reflects.
  // Dynamic instances block rays and take no part; a ray absorbed in glass carries nothing.
  bool lit(const trace::RayTracer& tracer, const trace::Hit& hit) const {
    if (!hit.valid() || hit.absorbed) return false;
    const uint8_t s = sides(tracer, hit);
    return (s & kStatic) && (hit.frontFace || (s & kBackReflects));
  }

  std::vector<trace::Ray> rays_;
  std::vector<trace::Hit> hits_;
  std::vector<float> skyShares_;  // per ray, with glass in the scene (skyShare)
  // With a GlassSky, per ray whose first surface is glass: that triangle of glass (else -1),
  // how far and at what cosine, and the grey transmittance beyond to the sky.
  struct FirstGlass {
    int glass = -1;
    float distance = 0.0f, cosine = 0.0f, through = 0.0f;
  };
  std::vector<FirstGlass> firstGlass_;
  std::vector<trace::Hit> firstHits_;  // skyThroughGlass's scratch
  const GlassSky* glassSky_ = nullptr;
  std::vector<trace::Ray> skyRays_;       // skyThroughGlass's scratch
  std::vector<uint32_t> skyRayOf_;
  std::vector<float> skyThrough_;
  std::vector<glm::vec2> albedoUvs_;   // albedoCodes' scratch
  std::vector<int> albedoMaterials_;
  std::vector<uint32_t> codes_;
  std::vector<glm::vec2> uvs_;
  std::vector<const glm::vec2*> corners_;  // per hit, its triangle's lightmap UVs
  std::vector<const uint32_t*> slots_;
  std::vector<uint8_t> lit_;
  std::vector<trace::Ray> sightRays_;                    // sight lines of hits on near texels
  std::vector<std::pair<uint32_t, uint32_t>> sightOf_;  // per sight line: ray, texel
  OcclusionFlags blocked_;                               // per sight line (or light ray)
  std::vector<uint32_t> searchedLines_;  // per stand-in search, its sight line
  std::vector<trace::Ray> glassLines_;   // keepTexelsBehindGlass's scratch
  std::vector<float> glassThrough_;
  std::vector<std::pair<uint32_t, uint32_t>> checks_;      // light checks: ray, lights reached
  std::vector<trace::Ray> lightRays_;                      // ... their shadow rays
  std::vector<std::pair<uint32_t, uint32_t>> lightRayOf_;  // per shadow ray: check, light
  SightSearch search_;  // stand-ins and light matches
  mutable std::vector<uint8_t> sides_;  // per tracer geometry, kUnknown until first hit
};

// A near texel's hit code (TexelGather), flagged kFar when the texel hit lies beyond `from`'s
// near field (nearField texel edges): measured to the sample of the texel hit, which sits
// within that texel of the hit point.
inline uint32_t nearFieldCode(const TexelSet& texels, float nearField, uint32_t from,
                              uint32_t code) {
  if (code == TexelGather::kNoHit) return code;
  const uint32_t hit = code & TexelGather::kTexelMask;
  const float reach = nearField * texels.edge[from];
  const glm::vec3 d = texels.position[hit] - texels.position[from];
  return glm::dot(d, d) > reach * reach ? (code | TexelGather::kFar) : code;
}

}  // namespace afterglow::baker
