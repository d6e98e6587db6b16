// The light probes' transfer (runtime::ProbeTransport): what each probe sees, from the same
// clusters, far clusters, sources and sky as the lightmaps, so the runtime relights probes with
// the lightmaps' own solution.
//
// A probe casts one ray per cell of an equal-area grid over the sphere (probe_directions.h).
// Per ray:
//   - a miss adds its direction's share to the sky's transfer (K = Σ_misses Ω Y Yᵀ, with the
//     misses' share of the grid's quadrature error: a probe in the open sees the sky exactly, one
//     in a closed room none);
//   - a hit on a lit surface links that surface's cluster (or the far cluster that stands in
//     for it from this far) in the ray's region: a region's row is the mean over its rays, and
//     the regions' means enter the SH through least-squares weights;
//   - a hit on an emitting side of an emissive surface adds its emission, weighted against the
//     area samples of that emitter (multiple importance sampling; the area samples are cast
//     too).
// Lights: shadow rays toward the light (over its extent), projected onto SH ray by ray.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/probe_transfer.h"
#include "afterglow/core/stages.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_visibility.h"
#include "shading/emitters.h"
#include "precompute/far_targets.h"
#include "precompute/gather_batch.h"
#include "shading/light_model.h"
#include "precompute/probe_directions.h"
#include "precompute/texel_lookup.h"
#include "shading/sampling.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::kShCount;

// Per probe, what its rays and shadow rays gave, before the probes are joined in order.
struct ProbeResult {
  runtime::SparseLinks rows;  // per region, its links (encoded in the worker: the join copies)
  double blocked[runtime::kProbeSkyCount] = {};  // I − K: the sky the hits block
  std::vector<double> source;                    // sources × kShCount
  uint16_t depth[runtime::kProbeDepthValues] = {};  // the rays' distances (probe_visibility.h)
};

// A probe's shadow rays toward its sources, traced together: per ray its source and the weight
// its SH projection takes when unblocked (times what glass lets through).
struct ShadowBatch {
  std::vector<trace::Ray> rays;
  std::vector<size_t> source;
  std::vector<double> weight;
  std::unique_ptr<float[]> through;
  size_t capacity = 0;  // of through

  void clear() {
    rays.clear();
    source.clear();
    weight.clear();
  }
  void add(glm::vec3 origin, glm::vec3 direction, float length, size_t s, double w) {
    trace::Ray& ray = rays.emplace_back();
    ray.origin = origin;
    ray.direction = direction;
    ray.tfar = length;
    ray.mask = trace::kMaskShadowCasters;
    source.push_back(s);
    weight.push_back(w);
  }
};

// Everything a probe's rays are read against: the scene, the texels' clusters and far
// clusters, the sources in the transport's order, and the shared directions.
class ProbeTracer {
 public:
  ProbeTracer(const scenes::Scene& scene, const trace::RayTracer& tracer, const TexelSet& texels,
              const Clusters& clusters, const FarTargets& far, uint32_t targetCount,
              const ProbeOptions& options, const ProbeDirections& directions,
              const std::vector<glm::vec3>& positions)
      : scene_(scene), tracer_(tracer), texels_(texels), clusters_(clusters), far_(far),
        targetCount_(targetCount), options_(options), dirs_(directions), positions_(positions),
        emitters_(collectEmitters(scene)),
        rayDensity_(double(directions.rays) / (4.0 * double(kPi))),
        depthFilter_(runtime::probeDepthFilter(directions.direction.data(), directions.rays)) {}

  // Matches the transport's sources to the scene's lights (in order) and emitters (by
  // material), as computeDirect made them.
  Status matchSources(const std::vector<runtime::Source>& sources) {
    lights_.assign(sources.size(), nullptr);
    emitterOf_.assign(sources.size(), nullptr);
    sourceOfMaterial_.assign(scene_.materials.size() + 1, -1);
    size_t light = 0;
    for (size_t s = 0; s < sources.size(); ++s) {
      if (sources[s].kind == runtime::SourceKind::Light) {
        if (light >= scene_.lights.size())
          return Status::error("computeProbeTransfer: more light sources than the scene's lights");
        lights_[s] = &scene_.lights[light++];
        continue;
      }
      for (const Emitter& e : emitters_)
        if (e.material == sources[s].material) emitterOf_[s] = &e;
      if (emitterOf_[s] && sources[s].material < sourceOfMaterial_.size()) {
        sourceOfMaterial_[sources[s].material] = int(s);
        anyEmitter_ = true;
      }
    }
    return Status::ok();
  }

  // Fetches a probe's hit texels' clusters and far clusters into the cache, ahead of readRays.
  void prefetch(const GatherBatch& batch, size_t base, size_t stride) const {
    for (uint32_t r = 0; r < dirs_.rays; ++r) {
      const uint32_t code = batch.codes()[base + r * stride];
      if (code == TexelGather::kNoHit) continue;
      const uint32_t t = code & TexelGather::kTexelMask;
      __builtin_prefetch(&clusters_.texelCluster[t]);
      if (code & TexelGather::kBackSide) continue;
      for (const std::vector<uint32_t>& level : far_.ofTexel) __builtin_prefetch(&level[t]);
    }
  }

  // Reads a probe's rays: ray r at base + r × stride of the batch.
  void readRays(const GatherBatch& batch, size_t base, size_t stride, ProbeResult& res,
                std::vector<uint32_t>& targets, std::vector<float>& weights) const {
    uint32_t hits = 0;
    // Every ray's distance for the depth map (a miss far; glass counts where the ray stopped).
    float distance[1024];
    std::vector<float> moreDistances;
    float* distances = distance;
    if (dirs_.rays > 1024) {
      moreDistances.resize(dirs_.rays);
      distances = moreDistances.data();
    }
    for (uint32_t r = 0; r < dirs_.rays; ++r) {
      const trace::Hit& hit = batch.hits()[base + r * stride];
      distances[r] = hit.valid() ? hit.t : runtime::kProbeDepthFar;
    }
    runtime::probeDepthMoments(depthFilter_, distances, res.depth);
    // Region by region (the directions are in region order): its rays' targets, sorted, then
    // counted into the region's row; a hit weighs 1 / (the region's rays) in the region's mean.
    res.rows = runtime::SparseLinks(targetCount_);
    res.rows.rowStart.reserve(dirs_.regions + 1);  // one allocation each, not a dozen
    res.rows.rowScale.reserve(dirs_.regions);
    res.rows.link.reserve(dirs_.rays + (runtime::kLinkGroup - 1) * dirs_.regions);
    for (uint32_t b = 0, r = 0; b < dirs_.regions; ++b) {
      targets.clear();
      for (const uint32_t end = r + dirs_.raysOfRegion[b]; r < end; ++r) {
        const trace::Hit& hit = batch.hits()[base + r * stride];
        if (!hit.valid()) continue;
        ++hits;
        if (anyEmitter_ && !hit.absorbed) emissionAlongRay(hit, r, res);
        // Bounced light: the hit's cluster, or the far cluster standing in for it from here.
        const uint32_t code = batch.codes()[base + r * stride];
        if (code == TexelGather::kNoHit) continue;
        const uint32_t t = code & TexelGather::kTexelMask;
        uint32_t target = kNoTexel;
        if (code & TexelGather::kBackSide) {
          target = clusters_.texelBackCluster.empty() ? kNoTexel : clusters_.texelBackCluster[t];
        } else {
          // (The hit's distance, not its texel's sample's: the same within a texel, and no
          // cache miss.)
          if (!far_.empty()) target = far_.of(t, hit.t * hit.t);
          if (target == kNoTexel) target = clusters_.texelCluster[t];
        }
        if (target != kNoTexel) targets.push_back(target);
      }
      std::sort(targets.begin(), targets.end());
      weights.clear();
      size_t unique = 0;
      for (size_t i = 0; i < targets.size(); ++i) {
        if (i > 0 && targets[i] == targets[i - 1]) {
          weights.back() += 1.0f;
          continue;
        }
        targets[unique++] = targets[i];
        weights.push_back(1.0f);
      }
      for (float& w : weights) w /= float(dirs_.raysOfRegion[b]);
      res.rows.appendRow(targets.data(), weights.data(), unique);
    }
    // The sky the hits block: summed over the hits, or over the misses taken from the whole
    // sphere's sum, whichever are fewer. Through glass a ray blocks what the glass does not
    // let through (GatherBatch::skyShare).
    const bool overHits = hits <= dirs_.rays / 2;
    if (overHits) std::fill(res.blocked, res.blocked + runtime::kProbeSkyCount, 0.0);
    else std::copy(dirs_.allProducts, dirs_.allProducts + runtime::kProbeSkyCount, res.blocked);
    for (uint32_t r = 0; r < dirs_.rays; ++r) {
      const double share = double(batch.skyShare(base + r * stride));
      const double weight = overHits ? 1.0 - share : -share;
      if (weight == 0.0) continue;
      const float* pk = &dirs_.products[size_t(r) * runtime::kProbeSkyCount];
      for (int k = 0; k < runtime::kProbeSkyCount; ++k) res.blocked[k] += weight * double(pk[k]);
    }
    // The rays' sum over the whole sphere is the identity only up to the grid's quadrature
    // error (I − Σ Ω Y Yᵀ, a few thousandths). The hits block their share of that error too, so
    // the sky's transfer is the misses' sum plus the misses' share of it: exactly I for a probe
    // in the open, exactly 0 for one in a closed room (which saw the error as a sky of a few
    // thousandths, some of it negative).
    const double hitShare = double(hits) / double(dirs_.rays);
    for (int i = 0; i < kShCount; ++i)
      for (int j = i; j < kShCount; ++j) {
        const int k = runtime::probeSkyIndex(i, j);
        res.blocked[k] += ((i == j ? 1.0 : 0.0) - dirs_.allProducts[k]) * hitShare;
      }
  }

  // Probe p's direct light from every source: area samples on the emitters, shadow rays to the
  // lights, queued and traced together (Embree's packets of 16 do several times the rate of
  // rays one by one), then projected onto SH where unblocked.
  void sourceSamples(size_t p, ProbeResult& res, ShadowBatch& batch) const {
    batch.clear();
    for (size_t s = 0; s < lights_.size(); ++s) {
      if (emitterOf_[s]) queueEmitter(p, s, *emitterOf_[s], batch);
      else if (lights_[s]) queueLight(p, s, *lights_[s], batch);
    }
    if (batch.rays.empty()) return;
    if (batch.capacity < batch.rays.size()) {
      batch.capacity = batch.rays.size();
      batch.through.reset(new float[batch.capacity]);
    }
    tracer_.greyTransmittance(batch.rays.data(), batch.through.get(), batch.rays.size());
    for (size_t k = 0; k < batch.rays.size(); ++k) {
      if (!(batch.through[k] > 0.0f)) continue;
      float y[kShCount];
      runtime::shBasis(batch.rays[k].direction, y);
      double* sh = &res.source[batch.source[k] * kShCount];
      const double weight = batch.weight[k] * double(batch.through[k]);
      for (int i = 0; i < kShCount; ++i) sh[i] += weight * double(y[i]);
    }
  }

 private:

  // The rays' share of a direction on an emitter, against its area samples: the power
  // heuristic, with the rays counted kRayQuality times over (a quadrature of cell centres, not
  // random samples) against the area samples' density there *without the emitter's slope*,
  // emitterSamples · d² / area. Any two shares that sum to one keep the estimate unbiased (the
  // area samples are still weighed by their true density, slope included). Leaving the slope
  // out keeps the share continuous where two walls meet and along a wall's grazing band: with
  // it, the share jumped there, and the rays' quadrature of that step left probes beside a
  // furnace's walls up to 5% off (0.4-0.6% without). So a large emitter seen from near (a
  // furnace wall) goes to the rays and a small lamp few rays hit to the area samples.
  double rayShare(float distance, const Emitter& e) const {
    constexpr double kRayQuality = 4.0;
    const double a = kRayQuality * rayDensity_;
    const double b = double(options_.emitterSamples) * double(distance) * double(distance) /
                     double(e.totalArea);
    return a * a / (a * a + b * b);
  }
  // The area samples' density (samples × their pdf per steradian) toward a point of the emitter.
  double areaDensity(float distance, float cosEmit, const Emitter& e) const {
    return double(options_.emitterSamples) * double(distance) * double(distance) /
           (double(cosEmit) * double(e.totalArea));
  }

  // Emission seen along ray r (its share against the emitter's area samples).
  void emissionAlongRay(const trace::Hit& hit, uint32_t r, ProbeResult& res) const {
    const scenes::Instance& inst = scene_.instances[hit.instance];
    const int material = scene_.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
    if (material < 0 || size_t(material) >= sourceOfMaterial_.size()) return;
    const int s = sourceOfMaterial_[size_t(material)];
    if (s < 0) return;
    const Emitter& e = *emitterOf_[size_t(s)];
    const scenes::Material& m = scene_.materials[size_t(material)];
    const float cosEmit = std::abs(glm::dot(hit.geometricNormal, dirs_.direction[r]));
    if (!(hit.frontFace || e.doubleSided) || cosEmit <= 0.0f) return;
    const int set = m.emissiveTexture.texCoord == 1 ? 1 : 0;
    const float mod = emissionModulation(scene_, m, tracer_.uv(hit, set));
    const double w = double(mod) * rayShare(hit.t, e) / rayDensity_;
    const float* y = &dirs_.basis[size_t(r) * kShCount];
    for (int i = 0; i < kShCount; ++i) res.source[size_t(s) * kShCount + size_t(i)] += w * double(y[i]);
  }

  void queueEmitter(size_t p, size_t s, const Emitter& e, ShadowBatch& batch) const {
    const glm::vec3 origin = positions_[p];
    const scenes::Material& m = scene_.materials[e.material];
    const uint32_t n = uint32_t(options_.emitterSamples);
    for (uint32_t i = 0; i < n; ++i) {
      sampling::Rng rng(sampling::Stream::Probes, p, (uint64_t(s + 1) << 32) | i);
      const EmitterSample q = sampleEmitter(e, sampling::stratified2(rng, i, n));
      glm::vec3 w = q.point - origin;
      const float dist = glm::length(w);
      if (!(dist > 0.0f)) continue;
      w /= dist;
      float cosEmit = -glm::dot(q.normal, w);
      if (e.doubleSided) cosEmit = std::abs(cosEmit);
      if (cosEmit <= 0.0f) continue;
      const float mod = emissionModulation(scene_, m, q.uv);
      if (mod <= 0.0f) continue;
      const double area = areaDensity(dist, cosEmit, e);
      batch.add(origin, w, dist * (1.0f - kShadowShorten), s,
                double(mod) * (1.0 - rayShare(dist, e)) / area);
    }
  }

  void queueLight(size_t p, size_t s, const scenes::Light& light, ShadowBatch& batch) const {
    const glm::vec3 origin = positions_[p];
    // The light's unshadowed strength at the probe (E⊥ for colour 1, intensity 1): viewLight
    // with a normal facing the light, whose cosine is then 1.
    const glm::vec3 toLight = viewLight(light, origin, glm::vec3(0.0f, 1.0f, 0.0f)).toCentre;
    if (toLight == glm::vec3(0.0f)) return;
    const LightView v = viewLight(light, origin, toLight);
    const double strength = double(v.transfer) * double(kPi);
    if (!(strength > 0.0)) return;
    const uint32_t n = v.hasExtent ? uint32_t(options_.lightSamples) : 1u;
    for (uint32_t i = 0; i < n; ++i) {
      sampling::Rng rng(sampling::Stream::Probes, p, (uint64_t(s + 1) << 32) | i);
      glm::vec3 dir;
      float length = 0.0f;
      lightShadowRay(light, v, origin, sampling::stratified2(rng, i, n), &dir, &length);
      batch.add(origin, dir, length, s, strength / double(n));
    }
  }

  const scenes::Scene& scene_;
  const trace::RayTracer& tracer_;
  const TexelSet& texels_;
  const Clusters& clusters_;
  const FarTargets& far_;
  const uint32_t targetCount_;  // the links' targets: clusters and far clusters
  const ProbeOptions& options_;
  const ProbeDirections& dirs_;
  const std::vector<glm::vec3>& positions_;
  const std::vector<Emitter> emitters_;
  const double rayDensity_;  // rays × their solid-angle pdf, rays / 4π
  const runtime::ProbeDepthFilter depthFilter_;  // the rays to the depth map's texels
  std::vector<const scenes::Light*> lights_;  // per source: its light, or null
  std::vector<const Emitter*> emitterOf_;     // per source: its emitter, or null
  std::vector<int> sourceOfMaterial_;         // per material: its emissive source, or -1
  bool anyEmitter_ = false;
};

}  // namespace

Status computeProbeTransfer(const scenes::Scene& scene, const trace::RayTracer& tracer,
                            const TexelSet& texels, const Clusters& clusters,
                            const std::vector<Clusters>& farLevels, float farDistance,
                            float farLightRatio,
                            const runtime::ProbeTetrahedra& mesh, const ProbeOptions& options,
                            runtime::TransportData& transport, Progress& progress) {
  runtime::ProbeTransport& out = transport.probes;
  out = runtime::ProbeTransport();
  for (runtime::Source& s : transport.sources) s.probeTransfer.clear();
  const size_t count = mesh.positions.size();
  if (count == 0) return Status::ok();
  if (options.raysSide <= 0 || options.binsSide <= 0 || options.binsSide * 2 > options.raysSide ||
      options.raysSide > 256)
    return Status::error(format("probe rays: %d² rays in %d² regions: want 1 to 256 rays a side "
                                "and at least two a region's side",
                                options.raysSide, options.binsSide));
  if (options.emitterSamples < 0 || options.lightSamples <= 0)
    return Status::error("probe rays: emitter samples must be >= 0, light samples positive");
  if (clusters.texelCluster.size() != texels.size())
    return Status::error("computeProbeTransfer: the clusters do not match the texel set");

  const ProbeDirections dirs(uint32_t(options.raysSide), uint32_t(options.binsSide));
  out.mesh = mesh;
  out.bins = dirs.regions;
  out.binSh = dirs.regionSh;

  // The same far targets as the gather points' links, numbered alike (computeLinks made the
  // rows of transport.farClusters from the same inputs); only the distance from which a far
  // cluster stands in may differ.
  const FarTargets far = farTargets(texels, clusters, farLevels,
                                    options.farDistance > 0.0f ? options.farDistance : farDistance,
                                    nullptr, clusterLight(transport, farLightRatio));
  if (far.rows != transport.farClusters.rows())
    return Status::error("computeProbeTransfer: the far clusters differ from the links'");

  const uint32_t targetCount = transport.sharedFarBase();
  ProbeTracer probes(scene, tracer, texels, clusters, far, targetCount, options, dirs, mesh.positions);
  if (Status st = probes.matchSources(transport.sources); !st) return st;
  const size_t sourceCount = transport.sources.size();

  std::vector<ProbeResult> results(count);
  const TexelLookup lookup(texels);
  progress.begin(stageName(Stage::Probes), count);
  // Several probes' rays per trace, as the texels' gather does (Embree's streams and the hit
  // lookup's prefetching do better on a couple of thousand rays than on one probe's), queued
  // direction by direction: the batch's probes are neighbours, so consecutive rays run nearly
  // side by side through the scene and Embree's coherent stream traces them 7% faster than
  // probe by probe.
  constexpr size_t kProbesPerBatch = 16;
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    ShadowBatch shadows;
    std::vector<uint32_t> targets;
    std::vector<float> weights;
    for (size_t first = begin; first < end && !progress.cancelled(); first += kProbesPerBatch) {
      const size_t last = std::min(end, first + kProbesPerBatch), n = last - first;
      batch.clear();
      for (uint32_t k = 0; k < dirs.rays; ++k)
        for (size_t p = first; p < last; ++p) batch.addDirection(mesh.positions[p], dirs.direction[k]);
      // Without the sight-line check on texels near other geometry (the gather's TexelOfHit):
      // a probe averages its rays over regions of the sphere, where the odd ray that takes a
      // texel's light through a joint does not show (McGuire's box: 2.7% against the reference
      // either way), and the check cost a sixth of the probes' time on Sponza.
      batch.trace(tracer, texels, &lookup, /*sightLines=*/false);
      probes.prefetch(batch, 0, n);
      for (size_t p = first; p < last; ++p) {
        if (p + 1 < last) probes.prefetch(batch, p + 1 - first, n);
        ProbeResult& res = results[p];
        res.source.assign(sourceCount * kShCount, 0.0);
        probes.readRays(batch, p - first, n, res, targets, weights);
        probes.sourceSamples(p, res, shadows);
      }
      progress.advance(n);
    }
  }, 8);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");

  // Joined in probe order.
  out.links = runtime::SparseLinks(targetCount);
  size_t linkTotal = 0;
  for (const ProbeResult& res : results) linkTotal += res.rows.link.size();
  out.links.link.reserve(linkTotal);
  out.links.rowStart.reserve(count * dirs.regions + 1);
  out.links.rowScale.reserve(count * dirs.regions);
  out.sky.assign(count * runtime::kProbeSkyCount, 0);
  out.depth.resize(count * runtime::kProbeDepthValues);
  for (runtime::Source& s : transport.sources) s.probeTransfer.assign(count * kShCount, 0.0f);
  for (size_t p = 0; p < count; ++p) {
    ProbeResult& res = results[p];
    const uint32_t at = uint32_t(out.links.link.size());
    out.links.link.insert(out.links.link.end(), res.rows.link.begin(), res.rows.link.end());
    out.links.rowScale.insert(out.links.rowScale.end(), res.rows.rowScale.begin(), res.rows.rowScale.end());
    for (size_t row = 1; row < res.rows.rowStart.size(); ++row)
      out.links.rowStart.push_back(at + res.rows.rowStart[row]);
    res.rows = runtime::SparseLinks();
    std::copy(res.depth, res.depth + runtime::kProbeDepthValues,
              out.depth.begin() + std::ptrdiff_t(p * runtime::kProbeDepthValues));
    for (int i = 0; i < kShCount; ++i)
      for (int j = i; j < kShCount; ++j) {
        const int k = runtime::probeSkyIndex(i, j);
        const double identity = i == j ? 1.0 : 0.0;
        out.sky[p * runtime::kProbeSkyCount + size_t(k)] =
            runtime::floatToHalf(float(identity - res.blocked[k]));
      }
    for (size_t s = 0; s < sourceCount; ++s)
      for (int i = 0; i < kShCount; ++i)
        transport.sources[s].probeTransfer[p * kShCount + size_t(i)] =
            float(res.source[s * kShCount + size_t(i)]);
  }
  return Status::ok();
}

}  // namespace afterglow::baker
