// Cosine-distributed gather rays in batches: shared by the texels' gather (gather.cpp) and the
// back-side clusters' rays (links.cpp), so both classify hits the same way.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/clusters.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/texels.h"
#include "afterglow/baker/gather.h"
#include "afterglow/scenes/material_eval.h"
#include "precompute/light_visibility.h"
#include "shading/sampling.h"

namespace afterglow::baker {

// Two texels on one surface: same instance, normals within 30°, neither above the other's
// plane by more than a fifth of their distance (so neither a step nor a fold lies between
// them). Texels that may share a gather point, a far field, or smooth each other's light.
inline bool sameSurface(const TexelSet& texels, uint32_t a, uint32_t b) {
  if (texels.instance[a] != texels.instance[b]) return false;
  if (glm::dot(texels.normal[a], texels.normal[b]) < 0.866f) return false;
  const glm::vec3 d = texels.position[b] - texels.position[a];
  const float distance = glm::length(d);
  return std::abs(glm::dot(texels.geometricNormal[a], d)) <= 0.2f * distance &&
         std::abs(glm::dot(texels.geometricNormal[b], d)) <= 0.2f * distance;
}

// The ray from `from` to `to`, ending there; false when the two coincide.
inline bool segment(glm::vec3 from, glm::vec3 to, trace::Ray& ray) {
  const glm::vec3 d = to - from;
  const float length = glm::length(d);
  if (!(length > 0.0f)) return false;
  ray.origin = from;
  ray.direction = d / length;
  ray.tfar = length;
  return true;
}

// The sight line from a point on a surface (normal na) to another on the same or a nearby
// surface (nb), both lifted off their surfaces by a quarter of their distance, so the surface
// itself does not block it when it curves within a normal cone; false when the two coincide
// (nothing can stand between them). Clusters test their texels and the filter its neighbours
// with it.
inline bool liftedSightLine(glm::vec3 pa, glm::vec3 na, glm::vec3 pb, glm::vec3 nb, trace::Ray& ray) {
  const float lift = 0.25f * glm::length(pb - pa);
  return segment(pa + na * lift, pb + nb * lift, ray);
}

// texelAtUv as one table lookup per hit (the gather's hottest path after Embree): for every
// atlas pixel, its texel when valid. Built from the texels' validity at the time; a hit on any
// other pixel (padding, or a texel that is unused or buried) takes texelAtUv: the valid
// neighbour nearest to the hit.
class TexelLookup {
 public:
  explicit TexelLookup(const TexelSet& texels) : texels_(texels) {
    resolved_.resize(texels.atlases.size());
    for (size_t a = 0; a < texels.atlases.size(); ++a) {
      const runtime::AtlasLayout& layout = texels.atlases[a];
      std::vector<uint32_t>& out = resolved_[a];
      out.assign(layout.texelOfPixel.size(), runtime::kNoTexel);
      for (size_t p = 0; p < out.size(); ++p) {
        const uint32_t own = layout.texelOfPixel[p];
        if (own != runtime::kNoTexel && texels.valid[own])
          out[p] = own | (texels.nearGeometry[own] ? kNear : 0u);
      }
    }
  }

  // The table entry for a point, or nullptr (outside the atlas, no lightmap): fetch it early
  // with __builtin_prefetch, the load misses the cache for nearly every hit.
  const uint32_t* slot(const scenes::Scene& scene, uint32_t instance, glm::vec2 uv1) const {
    const scenes::LightmapLocation& where = scene.instances[instance].lightmap;
    if (where.atlas < 0 || size_t(where.atlas) >= resolved_.size()) return nullptr;
    const runtime::AtlasLayout& layout = texels_.atlases[size_t(where.atlas)];
    const float px = uv1.x * float(layout.width), py = uv1.y * float(layout.height);
    if (!(px >= 0.0f && py >= 0.0f && px < float(layout.width) && py < float(layout.height)))
      return nullptr;
    return &resolved_[size_t(where.atlas)][size_t(py) * size_t(layout.width) + size_t(px)];
  }

  // The texel, with kNear set when the hit point's sight line to its sample must be checked
  // (TexelOfHit): for a texel near other geometry (TexelSet::nearGeometry, packed in the same
  // table entry to save a second cache miss per hit), and always for a stand-in, the valid
  // neighbour nearest to the hit that texelAtUv finds when the texel under the hit is unused
  // or buried: its sample may lie past the very wall that buried that texel (a roof cutting
  // through a cornice). A texel from the table needs no instance check: a point inside a chart
  // only finds that chart's texels (charts sit `padding` texels apart).
  static constexpr uint32_t kNear = 0x80000000u;

  // Optional: the lights that reach each texel's sample (LightVisibility::texels), so that a
  // hit close to its ray's origin takes the light of a texel lit like the hit point
  // (TexelOfHit::lightMatch). Both must outlive the lookup.
  void setLights(const LightVisibility* lights, const std::vector<uint32_t>* reached) {
    lights_ = lights && !lights->empty() ? lights : nullptr;
    reached_ = reached;
  }
  const LightVisibility* lights() const { return lights_; }
  const std::vector<uint32_t>& reached() const { return *reached_; }

  uint32_t resolve(const scenes::Scene& scene, uint32_t instance, glm::vec2 uv1,
                   const uint32_t* entry) const {
    if (entry && *entry != runtime::kNoTexel) return *entry;
    const uint32_t t = texelAtUv(scene, texels_, instance, uv1);
    return t == runtime::kNoTexel ? t : (t | kNear);
  }

 private:
  const TexelSet& texels_;
  std::vector<std::vector<uint32_t>> resolved_;
  const LightVisibility* lights_ = nullptr;
  const std::vector<uint32_t>* reached_ = nullptr;
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

// The texel whose light a ray hit receives: t, the texel under the hit point, unless a
// wall or object cuts through that texel's footprint and stands between the hit point and the
// texel's sample, as for a floor texel half under a box: a ray from inside the box that lands
// on the hidden half must not collect the light of the sample outside. Then the nearest texel
// of the same chart that the hit point does see stands in; with none, the ray is absorbed.
// Only texels near other geometry (TexelLookup::kNear) are checked. In two steps, so that a
// batch's sight lines are traced together: sightLine() gives the line from the hit point to
// its texel's sample, and when that line is blocked standInCandidates() are searched, a
// batch's searches together (SightSearch). The hit
// point is the ray's origin + t × direction: within micrometres of the surface, which the lift
// off it (texel t's offset, millimetres or more) dwarfs, and without the triangle's vertices
// to fetch.
struct TexelOfHit {
  // The hit point lifted off its surface by texel t's offset, on the side the ray arrived at:
  // where sight lines and the light check start.
  static glm::vec3 lightOrigin(const TexelSet& texels, uint32_t t, const trace::Hit& hit,
                               glm::vec3 hitPoint) {
    const glm::vec3 side = hit.frontFace ? hit.geometricNormal : -hit.geometricNormal;
    return hitPoint + side * texels.offset[t];
  }

  // The line from the hit point (lifted off the surface by texel t's offset) to the sample of
  // texel `target` on the side the ray arrived at; false when the two coincide (nothing can
  // stand between them).
  static bool sightLine(const TexelSet& texels, uint32_t t, const trace::Hit& hit, glm::vec3 hitPoint,
                        uint32_t target, trace::Ray& ray) {
    return segment(lightOrigin(texels, t, hit, hitPoint),
                   hit.frontFace ? texels.position[target] : texels.backPosition(target), ray);
  }

  // The stand-in search's candidates, visit(n, distance, kind): every valid neighbour of t in
  // its chart (kind 0), of which the nearest the hit point sees stands in (kNoTexel: none).
  template <class Visit>
  static void standInCandidates(const TexelSet& texels, uint32_t t, const trace::Hit& hit,
                                glm::vec3 hitPoint, Visit&& visit) {
    const glm::vec3 origin = lightOrigin(texels, t, hit, hitPoint);
    forChartNeighbours(texels, t, 1, [&](uint32_t n) {
      visit(n, glm::length(texels.position[n] - origin), 0);
    });
  }

  // A hit nearer its ray's origin than this many of its texel's edges is checked for light
  // (lightMatch): there the hit point and its texel's sample may lie on either side of a
  // shadow the ray's own surface casts, and the hit covers a wide solid angle. Farther hits
  // each cover little, and their errors average out over the rays. (On Sponza-sun 1, 2 and 4
  // edges give the same figures; on the contact test 4 does best, for 10% more bake time.)
  static constexpr float kLightCheckEdges = 4.0f;

  // Texel t, or the texel whose light a hit should take instead: when the lights that reach
  // the hit point (lifted off its surface like t's sample) are not those that reach t's
  // sample, or are but t's footprint is lit unevenly (its cluster reflects the footprint's
  // mean, LightVisibility::kUneven), the nearest valid texel of t's chart within two texels
  // that is lit like the hit point, evenly if one is, and that the hit point sees. With none:
  // t when its sample is lit like the hit point; kNoTexel (absorbed) when a light reaches t's
  // sample but not the hit point, for a sunlit sample must not light a shadowed contact, whose
  // own light is the little that bounced into it; else t.
  // `want`: the lights that reach the hit point lifted off its surface. In two steps, so that
  // a batch's searches trace their sight lines together: whether a search is needed
  // (needsLightMatch), its candidates (lightMatchCandidates: kind 0 lit evenly, 1 unevenly),
  // and the choice once the nearest of each kind in sight is known (lightMatchChoice).
  static bool needsLightMatch(const TexelLookup& lookup, uint32_t t, uint32_t want) {
    return want != lookup.reached()[t];  // else lit alike, evenly: t
  }
  template <class Visit>
  static void lightMatchCandidates(const TexelSet& texels, const TexelLookup& lookup, uint32_t t,
                                   const trace::Hit& hit, glm::vec3 hitPoint, uint32_t want,
                                   Visit&& visit) {
    constexpr uint32_t kUneven = LightVisibility::kUneven;
    const glm::vec3 origin = lightOrigin(texels, t, hit, hitPoint);
    const std::vector<uint32_t>& reached = lookup.reached();
    forChartNeighbours(texels, t, 2, [&](uint32_t n) {
      if ((reached[n] & ~kUneven) != want) return;
      visit(n, glm::length(texels.position[n] - origin), (reached[n] & kUneven) ? 1 : 0);
    });
  }
  static uint32_t lightMatchChoice(const TexelLookup& lookup, uint32_t t, uint32_t want,
                                   uint32_t nearestEven, uint32_t nearestUneven) {
    const uint32_t own = lookup.reached()[t] & ~LightVisibility::kUneven;
    if (nearestEven != runtime::kNoTexel) return nearestEven;
    if (want == own) return t;
    if (nearestUneven != runtime::kNoTexel) return nearestUneven;
    return (own & ~want) ? runtime::kNoTexel : t;
  }

 private:
  // Calls visit(n) for every valid texel n of t's instance within `radius` atlas pixels of t
  // (t excluded), row by row.
  template <class Visit>
  static void forChartNeighbours(const TexelSet& texels, uint32_t t, int radius, Visit&& visit) {
    const runtime::AtlasLayout& layout = texels.atlases[texels.atlas[t]];
    const int x = texels.pixel[t].x, y = texels.pixel[t].y;
    for (int dy = -radius; dy <= radius; ++dy)
      for (int dx = -radius; dx <= radius; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= layout.width || ny >= layout.height)
          continue;
        const uint32_t n = layout.texelOfPixel[size_t(ny) * size_t(layout.width) + size_t(nx)];
        if (n != runtime::kNoTexel && texels.valid[n] && texels.instance[n] == texels.instance[t])
          visit(n);
      }
  }

};

// Searches for the nearest candidate texel of each kind whose sample a hit point sees, many
// searches at once (TexelOfHit's stand-in and light match): each search's candidates sorted by
// distance, then rounds that trace the next candidate of every search still open as one ray
// stream. The same texels as testing candidates one by one in visit order (ties go to the
// first visited), and no more sight lines: a candidate is only tested while nothing nearer of
// its kind has been seen.
class SightSearch {
 public:
  static constexpr int kKinds = 2;
  void clear() {
    candidates_.clear();
    searches_.clear();
  }
  // Opens a search from hit `ray` of the batch, on behalf of texel `texel`; returns its index.
  uint32_t open(uint32_t ray, uint32_t texel) {
    const uint32_t at = uint32_t(candidates_.size());
    searches_.push_back({ray, texel, at, at, {}, {}});
    return uint32_t(searches_.size() - 1);
  }
  // Adds a candidate to the last search opened.
  void add(uint32_t texel, float distance, int kind) {
    candidates_.push_back({distance, uint32_t(candidates_.size()), texel, uint8_t(kind)});
    searches_.back().end = uint32_t(candidates_.size());
  }
  // Runs every search. line(search's ray, search's texel, candidate, Ray&) gives the sight
  // line, false when none is needed (the hit point is at the candidate's sample).
  template <class Line>
  void run(const trace::RayTracer& tracer, Line&& line) {
    for (Search& s : searches_) {
      std::sort(candidates_.begin() + s.begin, candidates_.begin() + s.end,
                [](const Candidate& a, const Candidate& b) {
                  return a.distance < b.distance || (a.distance == b.distance && a.order < b.order);
                });
      for (int k = 0; k < kKinds; ++k) s.next[k] = s.begin, s.found[k] = runtime::kNoTexel;
    }
    for (;;) {
      rays_.clear();
      tested_.clear();
      for (uint32_t i = 0; i < searches_.size(); ++i) {
        Search& s = searches_[i];
        for (int k = 0; k < kKinds; ++k) {
          // The kind's next candidate; those that need no line are seen at once.
          while (s.found[k] == runtime::kNoTexel && s.next[k] < s.end) {
            const Candidate& c = candidates_[s.next[k]];
            if (c.kind != k) {
              ++s.next[k];
              continue;
            }
            trace::Ray ray;
            if (!line(s.ray, s.texel, c.texel, ray)) {
              s.found[k] = c.texel;
              break;
            }
            rays_.push_back(ray);
            tested_.push_back({i, k});
            break;
          }
        }
      }
      if (rays_.empty()) return;
      if (blockedSize_ < rays_.size()) {
        blockedSize_ = rays_.size();
        blocked_.reset(new bool[blockedSize_]);
      }
      tracer.occluded(rays_.data(), blocked_.get(), rays_.size());
      for (size_t j = 0; j < rays_.size(); ++j) {
        Search& s = searches_[tested_[j].first];
        const int k = tested_[j].second;
        if (blocked_[j]) ++s.next[k];
        else s.found[k] = candidates_[s.next[k]].texel;
      }
    }
  }
  size_t size() const { return searches_.size(); }
  uint32_t ray(uint32_t search) const { return searches_[search].ray; }
  uint32_t texel(uint32_t search) const { return searches_[search].texel; }
  // The nearest candidate of `kind` in sight, or kNoTexel.
  uint32_t nearest(uint32_t search, int kind) const { return searches_[search].found[kind]; }

 private:
  struct Candidate {
    float distance;
    uint32_t order;  // visit order, for ties
    uint32_t texel;
    uint8_t kind;
  };
  struct Search {
    uint32_t ray, texel, begin, end;
    uint32_t next[kKinds];   // per kind, the candidate to test next
    uint32_t found[kKinds];  // per kind, the nearest in sight (kNoTexel: none yet)
  };
  std::vector<Candidate> candidates_;
  std::vector<Search> searches_;
  std::vector<trace::Ray> rays_;
  std::vector<std::pair<uint32_t, int>> tested_;  // per ray of a round: search, kind
  std::unique_ptr<bool[]> blocked_;
  size_t blockedSize_ = 0;
};

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
  }
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
  // hit lands on (codes()), without, only what summarize() needs.
  // With `sightLines` off, a hit on a texel near other geometry takes that texel without the
  // check that its sample is in sight (TexelOfHit): cheaper, for rays whose hits are averaged
  // over many directions anyway (the light probes').
  // The albedo codes (TexelGather::hitAlbedo) of rays [from, from + n)'s hits into out: on the
  // front of a textured material nearer than maxDistance, the texture's grey modulation at the
  // hit (the diffuse albedo over the material's factor, as the transport's
  // clusterAlbedoTexture); else 0. A hit is a point sample: of a large texture (256 texels or
  // more a side) its nearest texel serves as well as the bilinear lookup, and reads a quarter
  // as much; a small one is read bilinearly, as the reference reads it. The base colour texels
  // are prefetched first: scattered reads over large textures are what this costs (the
  // precompute's ray rate fell from 71% of raw Embree's to 67% without, on Sponza).
  static bool nearestAlbedo(const scenes::Scene& scene, int material) {
    const scenes::TextureRef& ref = scene.material(material).baseColorTexture;
    if (!ref.valid() || size_t(ref.texture) >= scene.textures.size()) return false;
    const scenes::Texture& texture = scene.textures[size_t(ref.texture)];
    return texture.width >= 256 && texture.height >= 256;
  }
  void albedoCodes(const scenes::Scene& scene, const trace::RayTracer& tracer, size_t from, size_t n,
                   float maxDistance, uint8_t* out) {
    albedoUvs_.resize(n);
    albedoMaterials_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const trace::Hit& hit = hits_[from + i];
      albedoMaterials_[i] = -2;  // no code
      if (!hit.valid() || !hit.frontFace || !(hit.t < maxDistance)) continue;
      const scenes::Instance& inst = scene.instances[hit.instance];
      const int material = scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
      const scenes::Material& m = scene.material(material);
      if (!albedoTextured(m)) continue;
      albedoMaterials_[i] = material;
      albedoUvs_[i] = tracer.uv(hit, 0);
      if (m.baseColorTexture.valid() &&
          size_t(m.baseColorTexture.texture) < scene.textures.size()) {
        // The bilinear lookup's two rows.
        const scenes::Texture& texture = scene.textures[size_t(m.baseColorTexture.texture)];
        const glm::vec2 uv = m.baseColorTexture.transform(albedoUvs_[i]);
        const float row = 0.5f / float(std::max(1, texture.height));
        if (const glm::vec4* texel = texture.texelAt(uv - glm::vec2(0.0f, row)))
          __builtin_prefetch(texel);
        if (const glm::vec4* texel = texture.texelAt(uv + glm::vec2(0.0f, row)))
          __builtin_prefetch(texel);
      }
    }
    for (size_t i = 0; i < n; ++i) {
      out[i] = 0;
      if (albedoMaterials_[i] == -2) continue;
      const int material = albedoMaterials_[i];
      const glm::vec3 a =
          diffuseAlbedo(scene, material, albedoUvs_[i], nearestAlbedo(scene, material));
      const glm::vec3 f = diffuseAlbedoFactor(scene.material(material));
      glm::vec3 m(1.0f);
      for (int c = 0; c < 3; ++c)
        if (f[c] > 0.0f) m[c] = a[c] / f[c];
      out[i] = TexelGather::albedoCode((m.x + m.y + m.z) / 3.0f);
    }
  }

  void trace(const trace::RayTracer& tracer, const TexelSet& texels, const TexelLookup* lookup,
             bool sightLines = true) {
    const size_t first = codes_.size(), count = rays_.size() - first;
    hits_.resize(rays_.size());
    codes_.resize(rays_.size(), TexelGather::kNoHit);
    tracer.intersect(rays_.data() + first, hits_.data() + first, count);
    if (!lookup) return;
    const scenes::Scene& scene = tracer.scene();
    // Each step's memory for every hit of the batch first, prefetched, then the next step's:
    // one cache miss's latency for the batch instead of one per hit. The lightmap UVs of every
    // hit on a lit surface, then their table entries, then the texels.
    uvs_.resize(rays_.size());
    corners_.assign(rays_.size(), nullptr);
    slots_.assign(rays_.size(), nullptr);
    lit_.assign(rays_.size(), 0);
    for (size_t k = first; k < rays_.size(); ++k) {
      const trace::Hit& hit = hits_[k];
      if (!lit(scene, tracer, hit)) continue;
      lit_[k] = 1;
      corners_[k] = tracer.lightmapUvs(hit);
      if (corners_[k]) __builtin_prefetch(corners_[k]);
    }
    for (size_t k = first; k < rays_.size(); ++k) {
      if (!lit_[k]) continue;
      const trace::Hit& hit = hits_[k];
      uvs_[k] = corners_[k] ? trace::RayTracer::mixCorners(corners_[k], hit) : tracer.uv(hit, 1);
      slots_[k] = lookup->slot(scene, hit.instance, uvs_[k]);
      if (slots_[k]) __builtin_prefetch(slots_[k]);
    }
    // The texels hit; those near other geometry (their samples and offsets prefetched) first
    // have their sight lines traced, all together (TexelOfHit).
    sightRays_.clear();
    sightOf_.clear();
    // The sight line from hit k (on texel t's surface) to texel n's sample.
    auto sightLineOf = [&](uint32_t k, uint32_t t, uint32_t n, trace::Ray& line) {
      return TexelOfHit::sightLine(texels, t, hits_[k], hitPoint(k), n, line);
    };
    auto code = [&](size_t k, uint32_t t) {
      if (t != runtime::kNoTexel)
        codes_[k] = hits_[k].frontFace ? t : (t | TexelGather::kBackSide);
    };
    for (size_t k = first; k < rays_.size(); ++k) {
      if (!lit_[k]) continue;
      const uint32_t entry = lookup->resolve(scene, hits_[k].instance, uvs_[k], slots_[k]);
      if (entry == runtime::kNoTexel || !(entry & TexelLookup::kNear)) {
        code(k, entry);
        continue;
      }
      if (!sightLines) {
        code(k, entry & ~TexelLookup::kNear);
        continue;
      }
      const uint32_t t = entry & ~TexelLookup::kNear;
      __builtin_prefetch(&texels.position[t]);
      __builtin_prefetch(&texels.offset[t]);
      sightOf_.push_back({uint32_t(k), t});
    }
    size_t lines = 0;
    sightRays_.resize(sightOf_.size());  // fresh rays (cleared above)
    for (size_t i = 0; i < sightOf_.size(); ++i) {
      const auto [k, t] = sightOf_[i];
      if (TexelOfHit::sightLine(texels, t, hits_[k], hitPoint(k), t, sightRays_[lines]))
        sightOf_[lines++] = sightOf_[i];
      else
        code(k, t);
    }
    sightOf_.resize(lines);
    if (lines > 0) {
      if (blockedSize_ < lines) {
        blockedSize_ = lines;
        blocked_.reset(new bool[blockedSize_]);
      }
      tracer.occluded(sightRays_.data(), blocked_.get(), lines);
      search_.clear();
      for (size_t i = 0; i < lines; ++i) {
        const auto [k, t] = sightOf_[i];
        if (!blocked_[i]) {
          code(k, t);
          continue;
        }
        search_.open(k, t);
        TexelOfHit::standInCandidates(texels, t, hits_[k], hitPoint(k),
                                      [&](uint32_t n, float d, int kind) { search_.add(n, d, kind); });
      }
      search_.run(tracer, sightLineOf);
      for (uint32_t i = 0; i < search_.size(); ++i) code(search_.ray(i), search_.nearest(i, 0));
    }
    // Close front-side hits take the light of a texel lit like them (TexelOfHit::lightMatch).
    // The lights that reach each hit point first, every hit's shadow rays traced together
    // (one by one they cost the precompute 2-3% of its ray rate).
    if (!sightLines || !lookup->lights()) return;
    const LightVisibility& lights = *lookup->lights();
    checks_.clear();
    lightRays_.clear();
    lightRayOf_.clear();
    for (size_t k = first; k < rays_.size(); ++k) {
      const uint32_t c = codes_[k];
      if (c == TexelGather::kNoHit || (c & TexelGather::kBackSide)) continue;
      const uint32_t t = c & TexelGather::kTexelMask;
      if (!(hits_[k].t < TexelOfHit::kLightCheckEdges * texels.edge[t])) continue;
      const glm::vec3 origin = TexelOfHit::lightOrigin(texels, t, hits_[k], hitPoint(k));
      for (size_t i = 0; i < lights.size(); ++i) {
        trace::Ray& ray = lightRays_.emplace_back();
        if (lights.shadowRayOf(i, origin, hits_[k].geometricNormal, ray))
          lightRayOf_.push_back({uint32_t(checks_.size()), uint32_t(i)});
        else
          lightRays_.pop_back();
      }
      checks_.push_back({uint32_t(k), 0u});
    }
    if (checks_.empty()) return;
    if (blockedSize_ < lightRays_.size()) {
      blockedSize_ = lightRays_.size();
      blocked_.reset(new bool[blockedSize_]);
    }
    tracer.occluded(lightRays_.data(), blocked_.get(), lightRays_.size());
    for (size_t j = 0; j < lightRays_.size(); ++j)
      if (!blocked_[j]) checks_[lightRayOf_[j].first].second |= 1u << lightRayOf_[j].second;
    search_.clear();
    for (const auto& [k, want] : checks_) {
      const uint32_t t = codes_[k] & TexelGather::kTexelMask;
      if (!TexelOfHit::needsLightMatch(*lookup, t, want)) continue;
      search_.open(k, want);
      TexelOfHit::lightMatchCandidates(texels, *lookup, t, hits_[k], hitPoint(k), want,
                                       [&](uint32_t n, float d, int kind) { search_.add(n, d, kind); });
    }
    // The search's texel slot holds `want`; the hit's own texel is still in its code.
    search_.run(tracer, [&](uint32_t k, uint32_t, uint32_t n, trace::Ray& line) {
      return sightLineOf(k, codes_[k] & TexelGather::kTexelMask, n, line);
    });
    for (uint32_t i = 0; i < search_.size(); ++i) {
      const uint32_t k = search_.ray(i), t = codes_[k] & TexelGather::kTexelMask;
      const uint32_t match = TexelOfHit::lightMatchChoice(*lookup, t, search_.texel(i),
                                                          search_.nearest(i, 0),
                                                          search_.nearest(i, 1));
      codes_[k] = match == runtime::kNoTexel ? TexelGather::kNoHit : match;
    }
  }

  // Per traced ray, a TexelGather hit code.
  const std::vector<uint32_t>& codes() const { return codes_; }
  // Per traced ray, what it hit, and the ray.
  const std::vector<trace::Hit>& hits() const { return hits_; }
  const std::vector<trace::Ray>& rays() const { return rays_; }

  Summary summarize(const trace::RayTracer& tracer, size_t first, size_t last, float near = 0.0f) const {
    Summary out;
    for (size_t k = first; k < last; ++k) {
      const trace::Hit& hit = hits_[k];
      if (!hit.valid()) {
        float y[runtime::kShCount];
        sampling::shBasis(rays_[k].direction, y);
        for (int i = 0; i < runtime::kShCount; ++i) out.sky[i] += double(y[i]);
        continue;
      }
      if (hit.t > 0.0f) out.inverseDistance += 1.0 / double(hit.t);
      if (hit.t < near) ++out.close;
      if (!hit.frontFace && !(sides(tracer, hit) & kBackReflects)) ++out.backfaces;
    }
    return out;
  }

 private:
  // Where ray k hit (TexelOfHit: the ray's own arithmetic is close enough).
  glm::vec3 hitPoint(size_t k) const { return rays_[k].origin + hits_[k].t * rays_[k].direction; }

  // What a hit's geometry is, per geometry looked up once (a hit's material and instance sit
  // behind several dependent loads): kStatic, and kBackReflects for double-sided materials.
  static constexpr uint8_t kStatic = 1, kBackReflects = 2, kUnknown = 0xff;
  uint8_t sides(const trace::RayTracer& tracer, const trace::Hit& hit) const {
    if (hit.geometry >= sides_.size()) sides_.resize(size_t(hit.geometry) + 1, kUnknown);
    uint8_t& s = sides_[hit.geometry];
    if (s == kUnknown)
      s = uint8_t((tracer.scene().instances[hit.instance].isStatic ? kStatic : 0) |
                  (tracer.material(hit).doubleSided ? kBackReflects : 0));
    return s;
  }

  // A hit on a surface that takes part in bounces: static, and seen from a side that reflects.
  // Dynamic instances block rays and take no part.
  bool lit(const scenes::Scene& scene, const trace::RayTracer& tracer, const trace::Hit& hit) const {
    if (!hit.valid()) return false;
    const uint8_t s = sides(tracer, hit);
    return (s & kStatic) && (hit.frontFace || (s & kBackReflects));
  }

  std::vector<trace::Ray> rays_;
  std::vector<trace::Hit> hits_;
  std::vector<glm::vec2> albedoUvs_;   // albedoCodes' scratch
  std::vector<int> albedoMaterials_;
  std::vector<uint32_t> codes_;
  std::vector<glm::vec2> uvs_;
  std::vector<const glm::vec2*> corners_;  // per hit, its triangle's lightmap UVs
  std::vector<const uint32_t*> slots_;
  std::vector<uint8_t> lit_;
  std::vector<trace::Ray> sightRays_;                    // sight lines of hits on near texels
  std::vector<std::pair<uint32_t, uint32_t>> sightOf_;  // per sight line: ray, texel
  std::unique_ptr<bool[]> blocked_;               // per sight line (or light ray)
  std::vector<std::pair<uint32_t, uint32_t>> checks_;      // light checks: ray, lights reached
  std::vector<trace::Ray> lightRays_;                             // ... their shadow rays
  std::vector<std::pair<uint32_t, uint32_t>> lightRayOf_;  // per shadow ray: check, light
  size_t blockedSize_ = 0;
  SightSearch search_;  // stand-ins and light matches
  mutable std::vector<uint8_t> sides_;  // per tracer geometry, kUnknown until first hit
};

}  // namespace afterglow::baker
