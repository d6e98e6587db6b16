// GatherBatch's tracing and reading: what gather_batch.h declares out of line, compiled once.
#include "precompute/gather_batch.h"

#include <algorithm>
#include <limits>

#include "afterglow/scenes/material_eval.h"
#include "precompute/glass_sky.h"
#include "precompute/light_visibility.h"
#include "precompute/texel_lookup.h"
#include "precompute/texel_of_hit.h"

namespace afterglow::baker {

namespace {

// Whether a material's albedo is read at its nearest texel (albedoCodes): a base colour
// texture of 256 texels or more a side.
bool nearestAlbedo(const scenes::Scene& scene, int material) {
  const scenes::TextureRef& ref = scene.material(material).baseColorTexture;
  if (!ref.valid() || size_t(ref.texture) >= scene.textures.size()) return false;
  const scenes::Texture& texture = scene.textures[size_t(ref.texture)];
  return texture.width >= 256 && texture.height >= 256;
}

}  // namespace

void GatherBatch::trace(const trace::RayTracer& tracer, const TexelSet& texels,
                        const TexelLookup* lookup, bool sightLines) {
  const size_t first = codes_.size(), count = rays_.size() - first;
  hits_.resize(rays_.size());
  codes_.resize(rays_.size(), TexelGather::kNoHit);
  tracer.intersect(rays_.data() + first, hits_.data() + first, count, trace::Glass::Light);
  if (tracer.hasGlass()) skyThroughGlass(tracer, first);
  if (!lookup) return;
  findSlots(tracer, *lookup, first);
  resolveTexels(tracer, texels, *lookup, first, sightLines);
  checkSightLines(tracer, texels);
  // Close front-side hits take the light of a texel lit like them (TexelOfHit's light match).
  if (!sightLines || !lookup->lights()) return;
  if (checkLights(tracer, texels, *lookup, first)) matchLights(tracer, texels, *lookup);
}

// The sky the rays from `first` on see through glass, as the glass lets it through rather
// than as each ray's chance had it: a ray that passed glass on its way out, or that glass
// stopped or absorbed, sees the sky times the grey transmittance of everything along it (0
// behind anything opaque). The same in expectation as counting the rays that escaped, without
// the noise of which did: a room lit by the sky through its windows would otherwise show the
// coin flips of every window ray in its lightmap. The links keep each ray's own fate. With a
// GlassSky the sky beyond is kept with the glass each ray met first (FirstGlass), for
// summarize to weigh against the glass's own samples.
void GatherBatch::skyThroughGlass(const trace::RayTracer& tracer, size_t first) {
  skyShares_.resize(rays_.size());
  skyRays_.clear();
  skyRayOf_.clear();
  for (size_t k = first; k < rays_.size(); ++k) {
    const trace::Hit& hit = hits_[k];
    skyShares_[k] = hit.valid() ? 0.0f : 1.0f;
    // Only a ray that glass ended, or that left through glass, can see the sky through it.
    if (hit.valid() ? !tracer.transmissive(hit) : !hit.throughGlass) continue;
    trace::Ray& ray = skyRays_.emplace_back(rays_[k]);
    ray.tfar = std::numeric_limits<float>::infinity();
    skyRayOf_.push_back(uint32_t(k));
  }
  skyThrough_.resize(skyRays_.size());
  tracer.greyTransmittance(skyRays_.data(), skyThrough_.data(), skyRays_.size());
  if (!glassSky_) {
    for (size_t j = 0; j < skyRays_.size(); ++j) skyShares_[skyRayOf_[j]] = skyThrough_[j];
    return;
  }
  // The glass each met first, as geometry sees it.
  firstHits_.resize(skyRays_.size());
  tracer.intersect(skyRays_.data(), firstHits_.data(), skyRays_.size());
  firstGlass_.resize(rays_.size());
  for (size_t k = first; k < rays_.size(); ++k) firstGlass_[k] = FirstGlass();
  for (size_t j = 0; j < skyRays_.size(); ++j) {
    const size_t k = skyRayOf_[j];
    const trace::Hit& at = firstHits_[j];
    skyShares_[k] = 0.0f;
    firstGlass_[k] = {glassSky_->triangleOf(at), at.t,
                      std::abs(glm::dot(at.geometricNormal, rays_[k].direction)), skyThrough_[j]};
  }
}

// The table entries of the hits from ray `first` on that land on a lit surface (lit_). Each
// step's memory for every hit of the batch first, prefetched, then the next step's: one cache
// miss's latency for the batch instead of one per hit. The lightmap UVs of every hit on a lit
// surface, then their table entries (the texels, in resolveTexels).
void GatherBatch::findSlots(const trace::RayTracer& tracer, const TexelLookup& lookup,
                            size_t first) {
  const scenes::Scene& scene = tracer.scene();
  uvs_.resize(rays_.size());
  corners_.assign(rays_.size(), nullptr);
  slots_.assign(rays_.size(), nullptr);
  lit_.assign(rays_.size(), 0);
  for (size_t k = first; k < rays_.size(); ++k) {
    const trace::Hit& hit = hits_[k];
    if (!lit(tracer, hit)) continue;
    lit_[k] = 1;
    corners_[k] = tracer.lightmapUvs(hit);
    if (corners_[k]) __builtin_prefetch(corners_[k]);
  }
  for (size_t k = first; k < rays_.size(); ++k) {
    if (!lit_[k]) continue;
    const trace::Hit& hit = hits_[k];
    uvs_[k] = corners_[k] ? trace::RayTracer::mixCorners(corners_[k], hit) : tracer.lightmapUv(hit);
    slots_[k] = lookup.slot(scene, hit.instance, uvs_[k]);
    if (slots_[k]) __builtin_prefetch(slots_[k]);
  }
}

// The texels hit. Those near other geometry whose sight lines must be checked (TexelOfHit)
// are left for checkSightLines (sightOf_), their samples and offsets prefetched.
void GatherBatch::resolveTexels(const trace::RayTracer& tracer, const TexelSet& texels,
                                const TexelLookup& lookup, size_t first, bool sightLines) {
  const scenes::Scene& scene = tracer.scene();
  sightOf_.clear();
  for (size_t k = first; k < rays_.size(); ++k) {
    if (!lit_[k]) continue;
    const uint32_t entry = lookup.resolve(scene, hits_[k].instance, uvs_[k], slots_[k]);
    if (entry == runtime::kNoTexel || !(entry & TexelLookup::kNear)) {
      setCode(k, entry);
      continue;
    }
    if (!sightLines) {
      setCode(k, entry & ~TexelLookup::kNear);
      continue;
    }
    const uint32_t t = entry & ~TexelLookup::kNear;
    __builtin_prefetch(&texels.position[t]);
    __builtin_prefetch(&texels.offset[t]);
    sightOf_.push_back({uint32_t(k), t});
  }
}

// The sight lines from the hits on near texels to their samples, traced together; a hit whose
// line is blocked takes the nearest texel of its chart in sight instead (a stand-in), all the
// batch's searches together (SightSearch).
void GatherBatch::checkSightLines(const trace::RayTracer& tracer, const TexelSet& texels) {
  size_t lines = 0;
  sightRays_.clear();
  sightRays_.resize(sightOf_.size());  // fresh rays
  for (size_t i = 0; i < sightOf_.size(); ++i) {
    const auto [k, t] = sightOf_[i];
    if (TexelOfHit::sightLine(texels, t, hits_[k], hitPoint(k), t, sightRays_[lines]))
      sightOf_[lines++] = sightOf_[i];
    else
      setCode(k, t);
  }
  sightOf_.resize(lines);
  if (lines == 0) return;
  tracer.occluded(sightRays_.data(), blocked_.reserve(lines), lines);
  search_.clear();
  searchedLines_.clear();
  for (size_t i = 0; i < lines; ++i) {
    const auto [k, t] = sightOf_[i];
    if (!blocked_[i]) {
      setCode(k, t);
      continue;
    }
    search_.open(k, t);
    searchedLines_.push_back(uint32_t(i));
    TexelOfHit::standInCandidates(texels, t, hits_[k], hitPoint(k),
                                  [&](uint32_t n, float d, int kind) { search_.add(n, d, kind); });
  }
  // The sight line from hit k (on texel t's surface) to texel n's sample.
  search_.run(tracer, [&](uint32_t k, uint32_t t, uint32_t n, trace::Ray& line) {
    return TexelOfHit::sightLine(texels, t, hits_[k], hitPoint(k), n, line);
  });
  for (uint32_t i = 0; i < search_.size(); ++i) setCode(search_.ray(i), search_.nearest(i, 0));
  if (tracer.hasGlass()) keepTexelsBehindGlass(tracer);
}

// The hits left without a stand-in whose texel's sample only glass hides take that texel's
// light as far as the glass lets it through: a texel that a pane cuts through (the reveal of a
// window) often has no neighbour on the hit point's side of the glass, and the light on one
// side of a pane is, to first order, the other side's through it. A hit keeps its texel with
// the grey transmittance of its sight line as its chance (a hash of the ray), else is
// absorbed. Absorbing them all took 4% of a room's bounced light through a skylight whose pane
// lets everything through (alpha 0); keeping them all made the texels of a glass door, whose
// frame's texels straddle the glass, 45% too bright, hits inside taking samples outside.
void GatherBatch::keepTexelsBehindGlass(const trace::RayTracer& tracer) {
  size_t kept = 0;
  for (uint32_t i = 0; i < search_.size(); ++i)
    if (search_.nearest(i, 0) == runtime::kNoTexel) searchedLines_[kept++] = searchedLines_[i];
  if (kept == 0) return;
  glassLines_.clear();
  for (size_t j = 0; j < kept; ++j) glassLines_.push_back(sightRays_[searchedLines_[j]]);
  glassThrough_.resize(kept);
  tracer.greyTransmittance(glassLines_.data(), glassThrough_.data(), kept);
  for (size_t j = 0; j < kept; ++j) {
    const auto [k, t] = sightOf_[searchedLines_[j]];
    if (glassThrough_[j] > 0.0f && rayChance(k) < glassThrough_[j]) setCode(k, t);
  }
}

// The lights that reach each close front-side hit point (checks_: ray, lights as bits), every
// hit's shadow rays traced together (one by one they cost the precompute 2-3% of its ray
// rate); false when no hit needs the check.
bool GatherBatch::checkLights(const trace::RayTracer& tracer, const TexelSet& texels,
                              const TexelLookup& lookup, size_t first) {
  const LightVisibility& lights = *lookup.lights();
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
  if (checks_.empty()) return false;
  // A light reaches a hit point through glass too (as LightVisibility counts it).
  tracer.occluded(lightRays_.data(), blocked_.reserve(lightRays_.size()), lightRays_.size(),
                  trace::Glass::Light);
  for (size_t j = 0; j < lightRays_.size(); ++j)
    if (!blocked_[j]) checks_[lightRayOf_[j].first].second |= 1u << lightRayOf_[j].second;
  return true;
}

// The checked hits lit unlike their texel's sample take the light of the nearest texel in
// sight lit like them (TexelOfHit's light match), or are absorbed; all searches together.
void GatherBatch::matchLights(const trace::RayTracer& tracer, const TexelSet& texels,
                              const TexelLookup& lookup) {
  search_.clear();
  for (const auto& [k, want] : checks_) {
    const uint32_t t = codes_[k] & TexelGather::kTexelMask;
    if (!TexelOfHit::needsLightMatch(lookup, t, want)) continue;
    search_.open(k, want);
    TexelOfHit::lightMatchCandidates(texels, lookup, t, hits_[k], hitPoint(k), want,
                                     [&](uint32_t n, float d, int kind) { search_.add(n, d, kind); });
  }
  // The search's texel slot holds `want`; the hit's own texel is still in its code.
  search_.run(tracer, [&](uint32_t k, uint32_t, uint32_t n, trace::Ray& line) {
    const uint32_t t = codes_[k] & TexelGather::kTexelMask;
    return TexelOfHit::sightLine(texels, t, hits_[k], hitPoint(k), n, line);
  });
  for (uint32_t i = 0; i < search_.size(); ++i) {
    const uint32_t k = search_.ray(i), t = codes_[k] & TexelGather::kTexelMask;
    const uint32_t match = TexelOfHit::lightMatchChoice(lookup, t, search_.texel(i),
                                                        search_.nearest(i, 0),
                                                        search_.nearest(i, 1));
    codes_[k] = match == runtime::kNoTexel ? TexelGather::kNoHit : match;
  }
}

void GatherBatch::albedoCodes(const scenes::Scene& scene, const trace::RayTracer& tracer,
                              size_t from, size_t n, float maxDistance, uint8_t* out) {
  // First every textured hit's material and UV, its texels prefetched.
  albedoUvs_.resize(n);
  albedoMaterials_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const trace::Hit& hit = hits_[from + i];
    albedoMaterials_[i] = -2;  // no code
    if (!hit.valid() || hit.absorbed || !hit.frontFace || !(hit.t < maxDistance)) continue;
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
  // Then their codes.
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

GatherBatch::Summary GatherBatch::summarize(const trace::RayTracer& tracer, size_t first,
                                            size_t last, float near,
                                            const GlassWeights* glass) const {
  Summary out;
  thread_local std::vector<float> chances;  // of the glass samples' triangles, from here
  bool chancesKnown = false;
  for (size_t k = first; k < last; ++k) {
    const trace::Hit& hit = hits_[k];
    float share = skyShare(k);
    if (glass && glassSky_ && !firstGlass_.empty() && firstGlass_[k].through > 0.0f) {
      const FirstGlass& f = firstGlass_[k];
      if (!chancesKnown) {
        glassSky_->chances(rays_[k].origin, glass->normal, chances);
        chancesKnown = true;
      }
      share = f.glass < 0 ? f.through
                          : f.through * glassSky_->rayWeight(chances, glass->normal,
                                                             rays_[k].direction, f.glass,
                                                             f.distance, f.cosine, glass->rays,
                                                             glass->samples);
    }
    if (share > 0.0f) {
      float y[runtime::kShCount];
      sampling::shBasis(rays_[k].direction, y);
      for (int i = 0; i < runtime::kShCount; ++i) out.sky[i] += double(share) * double(y[i]);
    }
    if (!hit.valid()) continue;
    if (hit.t > 0.0f) out.inverseDistance += 1.0 / double(hit.t);
    if (hit.t < near) ++out.close;
    // The back of single-sided glass is no wall to be inside of.
    if (!hit.frontFace && !(sides(tracer, hit) & (kBackReflects | kGlass))) ++out.backfaces;
  }
  return out;
}

}  // namespace afterglow::baker
