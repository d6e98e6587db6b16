// The light probes' transfer (runtime::ProbeTransport): what each probe sees, from the same
// clusters, far clusters, sources and sky as the lightmaps, so the runtime relights probes with
// the lightmaps' own solution.
//
// A probe casts raysSide² rays, one per cell of an equal-area octahedral grid over the sphere
// (each cell 4π/N sr), jittered per probe. Per ray:
//   - a miss leaves the sky's transfer where it is; a hit takes its direction's share out of
//     it (K = I − Σ_hits Ω Y Yᵀ: a probe in the open sees the sky exactly);
//   - a hit on a lit surface links that surface's cluster (or the far cluster that stands in for
//     it from this far) in the ray's region: regions are blocks of cells, and a region's row is
//     the mean over its rays, so bounced light enters as piecewise constant per region;
//   - a hit on an emitting side of an emissive surface adds its emission, weighted against the
//     area samples of that emitter (balance heuristic; the area samples are cast too).
// Lights: shadow rays toward the light (over its extent), projected onto SH direction by direction.
#include <algorithm>
#include <cmath>
#include <vector>

#include "afterglow/baker/raytracer.h"
#include "afterglow/baker/transport_precompute.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/probe_sh.h"
#include "emitters.h"
#include "far_targets.h"
#include "gather_rays.h"
#include "light_model.h"
#include "sampling.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::kShCount;
using sampling::kPi;

// Clarberg's equal-area octahedral map from [-1, 1]² to the unit sphere (z up on the square's
// centre): equal areas of the square map to equal solid angles (dω = π du dv).
glm::vec3 equalAreaOctahedral(glm::vec2 p) {
  const float u = std::clamp(p.x, -1.0f, 1.0f), v = std::clamp(p.y, -1.0f, 1.0f);
  const float up = std::abs(u), vp = std::abs(v);
  const float signedDistance = 1.0f - (up + vp);
  const float d = std::abs(signedDistance);
  const float r = 1.0f - d;
  const float phi = (r == 0.0f ? 1.0f : (vp - up) / r + 1.0f) * (kPi / 4.0f);
  const float z = std::copysign(1.0f - r * r, signedDistance);
  const float s = r * std::sqrt(std::max(0.0f, 2.0f - r * r));
  const float cosPhi = std::copysign(std::cos(phi), u), sinPhi = std::copysign(std::sin(phi), v);
  return glm::normalize(glm::vec3(cosPhi * s, sinPhi * s, z));
}

// The probes' rays point at the centres of the cells, the same directions for every probe: a
// quadrature that integrates smooth radiance far better than a random ray per cell (a probe in
// a furnace sees its emission within 0.3% for every normal, against 2% jittered), with every
// probe's errors alike, so interpolation between probes shows no noise. The grid is turned by
// a fixed, generic rotation so that no ray runs exactly along an axis or a diagonal, where a
// level's walls meet (a probe on a room's diagonal would send rays exactly into its corners).
glm::vec3 probeDirection(glm::vec2 square) {
  static const glm::mat3 turn = [] {
    const glm::vec3 a = glm::normalize(glm::vec3(0.5773f, 0.8264f, 0.2341f));
    const float angle = 0.4187f, c = std::cos(angle), s = std::sin(angle);
    const glm::mat3 k(0.0f, a.z, -a.y, -a.z, 0.0f, a.x, a.y, -a.x, 0.0f);  // cross(a, ·)
    return glm::mat3(1.0f) + s * k + (1.0f - c) * (k * k);
  }();
  return glm::normalize(turn * equalAreaOctahedral(square));
}

// ∫_b Y_i dω per region b (blocks of binsSide × binsSide regions over the octahedral square),
// by the midpoint rule on a fine grid (64² points a region: each cell's solid angle is exact,
// the error is Y's variation inside a cell, far below a half float's precision).
std::vector<float> regionSh(int binsSide) {
  constexpr int kFine = 64;
  std::vector<float> out(size_t(binsSide) * size_t(binsSide) * kShCount, 0.0f);
  const double cell = 4.0 * double(kPi) / (double(binsSide) * binsSide * kFine * kFine);
  for (int by = 0; by < binsSide; ++by)
    for (int bx = 0; bx < binsSide; ++bx) {
      double sum[kShCount] = {};
      for (int j = 0; j < kFine; ++j)
        for (int i = 0; i < kFine; ++i) {
          const glm::vec2 p(-1.0f + 2.0f * (float(bx * kFine + i) + 0.5f) / float(binsSide * kFine),
                            -1.0f + 2.0f * (float(by * kFine + j) + 0.5f) / float(binsSide * kFine));
          float y[kShCount];
          runtime::shBasis(probeDirection(p), y);
          for (int k = 0; k < kShCount; ++k) sum[k] += double(y[k]);
        }
      for (int k = 0; k < kShCount; ++k)
        out[size_t(by * binsSide + bx) * kShCount + size_t(k)] = float(sum[k] * cell);
    }
  return out;
}

// The region weights that recover SH L2 from the regions' means: Σ_b ∫_b Y_i · W_b alone
// projects a piecewise constant radiance, which blurs it (band 1 loses about a tenth, band 2
// a third with 16 regions: a probe beside a lit wall would see it dimmer and the dark side
// brighter). The least-squares L2 radiance whose region means are W instead is
// M⁻¹ Σ_b ∫_b Y · W_b, with M_ij = Σ_b ∫_b Y_i ∫_b Y_j / Ω_b: exact for radiance within L2,
// and folded into the weights, so the runtime does the same work.
std::vector<float> leastSquaresRegionSh(const std::vector<float>& integrals, uint32_t bins) {
  const double omega = 4.0 * double(kPi) / double(bins);
  double m[kShCount][2 * kShCount] = {};
  for (int i = 0; i < kShCount; ++i) {
    for (int j = 0; j < kShCount; ++j)
      for (uint32_t b = 0; b < bins; ++b)
        m[i][j] += double(integrals[b * kShCount + size_t(i)]) *
                   double(integrals[b * kShCount + size_t(j)]) / omega;
    m[i][kShCount + i] = 1.0;
  }
  // Gauss-Jordan with partial pivoting (M is symmetric positive definite for enough regions).
  for (int c = 0; c < kShCount; ++c) {
    int pivot = c;
    for (int r = c + 1; r < kShCount; ++r)
      if (std::abs(m[r][c]) > std::abs(m[pivot][c])) pivot = r;
    for (int k = 0; k < 2 * kShCount; ++k) std::swap(m[c][k], m[pivot][k]);
    const double d = m[c][c];
    if (std::abs(d) < 1e-12) return integrals;  // too few regions to resolve L2: keep the plain ones
    for (int k = 0; k < 2 * kShCount; ++k) m[c][k] /= d;
    for (int r = 0; r < kShCount; ++r) {
      if (r == c) continue;
      const double f = m[r][c];
      for (int k = 0; k < 2 * kShCount; ++k) m[r][k] -= f * m[c][k];
    }
  }
  std::vector<float> out(integrals.size());
  for (uint32_t b = 0; b < bins; ++b)
    for (int i = 0; i < kShCount; ++i) {
      double v = 0.0;
      for (int j = 0; j < kShCount; ++j) v += m[i][kShCount + j] * double(integrals[b * kShCount + size_t(j)]);
      out[b * kShCount + size_t(i)] = float(v);
    }
  return out;
}

int materialOf(const scenes::Scene& scene, const Hit& hit) {
  const scenes::Instance& inst = scene.instances[hit.instance];
  return scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
}

// Per probe, what the rays and shadow rays gave, before the rows are joined in probe order.
struct ProbeResult {
  std::vector<std::vector<std::pair<uint32_t, float>>> rows;  // per region: (target, weight)
  double blocked[runtime::kProbeSkyCount] = {};               // Σ_hits Ω Y_i Y_j
  std::vector<double> source;                                 // sources × kShCount
};

}  // namespace

Status computeProbeTransfer(const scenes::Scene& scene, const RayTracer& tracer,
                            const TexelSet& texels, const Clusters& clusters,
                            const std::vector<Clusters>& farLevels, float farDistance,
                            const runtime::ProbeTetrahedra& mesh, const ProbeOptions& options,
                            runtime::TransportData& transport, Progress& progress) {
  runtime::ProbeTransport& out = transport.probes;
  out = runtime::ProbeTransport();
  for (runtime::Source& s : transport.sources) s.probeTransfer.clear();
  const size_t count = mesh.positions.size();
  if (count == 0) return Status::ok();
  if (options.raysSide <= 0 || options.binsSide <= 0 || options.raysSide % options.binsSide != 0)
    return Status::error(format("probe rays: %d² rays cannot be split into %d² regions",
                                options.raysSide, options.binsSide));
  if (options.emitterSamples < 0 || options.lightSamples <= 0)
    return Status::error("probe rays: emitter samples must be >= 0, light samples positive");
  if (clusters.texelCluster.size() != texels.size())
    return Status::error("computeProbeTransfer: the clusters do not match the texel set");

  const uint32_t side = uint32_t(options.raysSide), binsSide = uint32_t(options.binsSide);
  const uint32_t rays = side * side, bins = binsSide * binsSide, perBin = rays / bins;
  const uint32_t cellsPerBin = side / binsSide;
  const float omega = 4.0f * kPi / float(rays);
  out.mesh = mesh;
  out.bins = bins;
  out.binSh = leastSquaresRegionSh(regionSh(options.binsSide), bins);

  // The same far targets as the gather points' links, rebuilt into a scratch matrix (it must
  // equal transport.farClusters, which computeLinks filled: same inputs, same numbering).
  runtime::SparseMatrix farRows;
  const FarTargets far = farTargets(texels, clusters, farLevels, farDistance, farRows);
  if (farRows.rows() != transport.farClusters.rows())
    return Status::error("computeProbeTransfer: the far clusters differ from the links'");
  const uint32_t targets = transport.sharedFarBase();

  // Sources: lights in scene order, emitters by material (computeDirect's order and names).
  const std::vector<Emitter> emitters = collectEmitters(scene);
  struct SourceRef {
    const scenes::Light* light = nullptr;
    const Emitter* emitter = nullptr;
  };
  std::vector<SourceRef> refs(transport.sources.size());
  std::vector<int> emitterSource(scene.materials.size() + 1, -1);  // material -> source
  size_t lightIndex = 0;
  for (size_t s = 0; s < transport.sources.size(); ++s) {
    const runtime::Source& src = transport.sources[s];
    if (src.kind == runtime::SourceKind::Light) {
      if (lightIndex >= scene.lights.size())
        return Status::error("computeProbeTransfer: more light sources than the scene's lights");
      refs[s].light = &scene.lights[lightIndex++];
      continue;
    }
    for (const Emitter& e : emitters)
      if (e.material == src.material) refs[s].emitter = &e;
    if (refs[s].emitter && src.material < emitterSource.size()) emitterSource[src.material] = int(s);
  }
  const size_t sourceCount = transport.sources.size();
  const double rayDensity = double(rays) / (4.0 * double(kPi));  // N × the rays' solid-angle pdf
  const double areaSamples = double(options.emitterSamples);
  // The rays' share of a direction the area samples (density `area`, samples × pdf) may also
  // find: the power heuristic, with the rays counted kRayQuality times over, since they are a
  // quadrature (cell centres) rather than random samples. Any two shares that sum to one keep
  // the estimate unbiased; these leave the rays all but a few percent of a large emitter seen
  // from near (a furnace wall, whose area samples are noisy: 2% directional noise at 64 area
  // samples under the plain power heuristic, 0.25% like this) and the area samples a small
  // lamp that few rays hit.
  constexpr double kRayQuality = 4.0;
  auto misRay = [&](double area) {
    const double a = kRayQuality * rayDensity * kRayQuality * rayDensity, b = area * area;
    return a / (a + b);
  };

  // The directions, in region order (a region's cells together), with their SH basis and the
  // products Ω Y_i Y_j the sky's transfer sums: the same for every probe, computed once.
  std::vector<glm::vec3> directions(rays);
  std::vector<uint32_t> regionOf(rays);
  std::vector<float> basis(size_t(rays) * kShCount), products(size_t(rays) * runtime::kProbeSkyCount);
  double allProducts[runtime::kProbeSkyCount] = {};
  {
    uint32_t k = 0;
    for (uint32_t by = 0; by < binsSide; ++by)
      for (uint32_t bx = 0; bx < binsSide; ++bx)
        for (uint32_t cy = 0; cy < cellsPerBin; ++cy)
          for (uint32_t cx = 0; cx < cellsPerBin; ++cx, ++k) {
            const uint32_t x = bx * cellsPerBin + cx, y = by * cellsPerBin + cy;
            const glm::vec2 q(-1.0f + 2.0f * (float(x) + 0.5f) / float(side),
                              -1.0f + 2.0f * (float(y) + 0.5f) / float(side));
            directions[k] = probeDirection(q);
            regionOf[k] = by * binsSide + bx;
            float* yk = &basis[size_t(k) * kShCount];
            runtime::shBasis(directions[k], yk);
            for (int i = 0; i < kShCount; ++i)
              for (int j = i; j < kShCount; ++j) {
                const int at = runtime::probeSkyIndex(i, j);
                products[size_t(k) * runtime::kProbeSkyCount + size_t(at)] = omega * yk[i] * yk[j];
                allProducts[at] += double(omega) * double(yk[i]) * double(yk[j]);
              }
          }
  }
  bool anyEmitter = false;
  for (int s2 : emitterSource) anyEmitter = anyEmitter || s2 >= 0;

  std::vector<ProbeResult> results(count);
  const TexelLookup lookup(texels);
  progress.begin("probe rays", count);
  // Several probes' rays per trace, as the texels' gather does (Embree's streams and the hit
  // lookup's prefetching do better on a couple of thousand rays than on one probe's).
  constexpr size_t kProbesPerBatch = 4;
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    std::vector<uint8_t> hitRay(rays);
    for (size_t first = begin; first < end && !progress.cancelled(); first += kProbesPerBatch) {
      const size_t last = std::min(end, first + kProbesPerBatch);
      batch.clear();
      for (size_t p = first; p < last; ++p)
        for (uint32_t k = 0; k < rays; ++k) batch.addDirection(mesh.positions[p], directions[k]);
      batch.trace(tracer, texels, &lookup);
      for (size_t p = first; p < last; ++p) {
      const glm::vec3 origin = mesh.positions[p];
      const size_t base = (p - first) * rays;
      ProbeResult& res = results[p];
      res.rows.assign(bins, {});
      res.source.assign(sourceCount * kShCount, 0.0);
      const float rowWeight = 1.0f / float(perBin);
      uint32_t hits = 0;
      for (uint32_t r = 0; r < rays; ++r) {
        const Hit& hit = batch.hits()[base + r];
        hitRay[r] = hit.valid() ? 1 : 0;
        if (!hit.valid()) continue;
        ++hits;
        const glm::vec3 dir = directions[r];
        const float* y = &basis[size_t(r) * kShCount];
        // Emission seen along the ray (its share against the emitter's area samples).
        const int material = anyEmitter ? materialOf(scene, hit) : -1;
        if (material >= 0 && size_t(material) < emitterSource.size() && emitterSource[size_t(material)] >= 0) {
          const size_t s = size_t(emitterSource[size_t(material)]);
          const Emitter& e = *refs[s].emitter;
          const scenes::Material& m = scene.materials[size_t(material)];
          const float cosEmit = std::abs(glm::dot(hit.geometricNormal, dir));
          if ((hit.frontFace || e.doubleSided) && cosEmit > 0.0f) {
            const int set = m.emissiveTexture.texCoord == 1 ? 1 : 0;
            const float mod = emissionModulation(scene, m, tracer.uv(hit, set));
            const double areaPdf = double(hit.t) * double(hit.t) / (double(cosEmit) * double(e.totalArea));
            const double w = double(mod) * misRay(areaSamples * areaPdf) / rayDensity;
            for (int i = 0; i < kShCount; ++i) res.source[s * kShCount + size_t(i)] += w * double(y[i]);
          }
        }
        // Bounced light: the hit's cluster, or the far cluster standing in for it from here.
        const uint32_t code = batch.codes()[base + r];
        if (code == TexelGather::kNoHit) continue;
        const uint32_t t = code & TexelGather::kTexelMask;
        uint32_t target = kNoTexel;
        if (code & TexelGather::kBackSide) {
          target = clusters.texelBackCluster.empty() ? kNoTexel : clusters.texelBackCluster[t];
        } else {
          const glm::vec3 d = texels.position[t] - origin;
          if (!far.empty()) target = far.of(t, glm::dot(d, d));
          if (target == kNoTexel) target = clusters.texelCluster[t];
        }
        if (target != kNoTexel) res.rows[regionOf[r]].emplace_back(target, rowWeight);
      }
      // The sky the hits block: summed over the hits, or over the misses taken from the whole
      // sphere's sum, whichever are fewer.
      const bool overHits = hits <= rays / 2;
      if (overHits) std::fill(res.blocked, res.blocked + runtime::kProbeSkyCount, 0.0);
      else std::copy(allProducts, allProducts + runtime::kProbeSkyCount, res.blocked);
      for (uint32_t r = 0; r < rays; ++r) {
        if (bool(hitRay[r]) != overHits) continue;
        const float* pk = &products[size_t(r) * runtime::kProbeSkyCount];
        const double sign = overHits ? 1.0 : -1.0;
        for (int k = 0; k < runtime::kProbeSkyCount; ++k) res.blocked[k] += sign * double(pk[k]);
      }
      for (auto& row : res.rows) {
        std::sort(row.begin(), row.end());
        size_t w = 0;
        for (size_t i = 0; i < row.size(); ++i) {
          if (w > 0 && row[w - 1].first == row[i].first) row[w - 1].second += row[i].second;
          else row[w++] = row[i];
        }
        row.resize(w);
      }
      // Emitters by area, and lights by shadow rays.
      for (size_t s = 0; s < sourceCount; ++s) {
        double* sh = &res.source[s * kShCount];
        if (const Emitter* e = refs[s].emitter) {
          const scenes::Material& m = scene.materials[e->material];
          const uint32_t n = uint32_t(options.emitterSamples);
          for (uint32_t i = 0; i < n; ++i) {
            sampling::Rng rng(sampling::Stream::Probes, p, (uint64_t(s + 1) << 32) | i);
            const EmitterSample q = sampleEmitter(*e, sampling::stratified2(rng, i, n));
            glm::vec3 w = q.point - origin;
            const float dist = glm::length(w);
            if (!(dist > 0.0f)) continue;
            w /= dist;
            float cosEmit = -glm::dot(q.normal, w);
            if (e->doubleSided) cosEmit = std::abs(cosEmit);
            if (cosEmit <= 0.0f) continue;
            const float mod = emissionModulation(scene, m, q.uv);
            if (mod <= 0.0f) continue;
            Ray ray;
            ray.origin = origin;
            ray.direction = w;
            ray.tfar = dist * (1.0f - kShadowShorten);
            ray.mask = kMaskShadowCasters;
            if (tracer.occluded(ray)) continue;
            const double areaPdf = double(dist) * double(dist) / (double(cosEmit) * double(e->totalArea));
            const double weight = double(mod) * (1.0 - misRay(areaSamples * areaPdf)) / (areaSamples * areaPdf);
            float y[kShCount];
            runtime::shBasis(w, y);
            for (int k2 = 0; k2 < kShCount; ++k2) sh[k2] += weight * double(y[k2]);
          }
          continue;
        }
        const scenes::Light* light = refs[s].light;
        if (!light) continue;
        // The light's unshadowed strength at the probe (E⊥ for colour 1, intensity 1), and
        // where its shadow rays go: a normal facing the light makes viewLight's cosine 1.
        const LightView centre = viewLight(*light, origin, glm::vec3(0.0f, 1.0f, 0.0f));
        glm::vec3 toLight = centre.toCentre;
        if (toLight == glm::vec3(0.0f)) continue;
        const LightView v = viewLight(*light, origin, toLight);
        const double strength = double(v.transfer) * double(kPi);
        if (!(strength > 0.0)) continue;
        const uint32_t n = v.hasExtent ? uint32_t(options.lightSamples) : 1u;
        for (uint32_t i = 0; i < n; ++i) {
          sampling::Rng rng(sampling::Stream::Probes, p, (uint64_t(s + 1) << 32) | i);
          glm::vec3 dir;
          float length = 0.0f;
          lightShadowRay(*light, v, origin, sampling::stratified2(rng, i, n), &dir, &length);
          Ray ray;
          ray.origin = origin;
          ray.direction = dir;
          ray.tfar = length;
          ray.mask = kMaskShadowCasters;
          if (tracer.occluded(ray)) continue;
          float y[kShCount];
          runtime::shBasis(dir, y);
          for (int k2 = 0; k2 < kShCount; ++k2) sh[k2] += strength / double(n) * double(y[k2]);
        }
      }
      progress.advance();
      }
    }
  }, 8);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");

  // Joined in probe order.
  out.links = runtime::SparseLinks(targets);
  out.sky.assign(count * runtime::kProbeSkyCount, 0);
  for (runtime::Source& s : transport.sources) s.probeTransfer.assign(count * kShCount, 0.0f);
  std::vector<uint32_t> rowTargets;
  std::vector<float> rowWeights;
  for (size_t p = 0; p < count; ++p) {
    const ProbeResult& res = results[p];
    for (const auto& row : res.rows) {
      rowTargets.clear();
      rowWeights.clear();
      for (const auto& [target, weight] : row) {
        rowTargets.push_back(target);
        rowWeights.push_back(weight);
      }
      out.links.appendRow(rowTargets.data(), rowWeights.data(), rowTargets.size());
    }
    for (int i = 0; i < kShCount; ++i)
      for (int j = i; j < kShCount; ++j) {
        const int at = runtime::probeSkyIndex(i, j);
        const double identity = i == j ? 1.0 : 0.0;
        out.sky[p * runtime::kProbeSkyCount + size_t(at)] =
            runtime::floatToHalf(float(identity - res.blocked[at]));
      }
    for (size_t s = 0; s < sourceCount; ++s)
      for (int i = 0; i < kShCount; ++i)
        transport.sources[s].probeTransfer[p * kShCount + size_t(i)] =
            float(res.source[s * kShCount + size_t(i)]);
  }
  return Status::ok();
}

}  // namespace afterglow::baker
