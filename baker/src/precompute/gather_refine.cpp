// More gather rays where the first ones leave a gather point's first bounce uncertain
// (transport_precompute.h, refineGather).
//
// A texel in shade that sees a sunlit floor through a gap gets its bounced light from the few
// rays that find the floor: 128 rays find it 2 times or 6, and the texel comes out half or
// twice as bright as it is. On Sponza-sun such texels carried most of the error left after
// issue 16's other changes, while most texels' estimates were already good. So the rays go
// where the estimate's own spread says they are needed.
//
// The spread is measured per light, in unit light (each light's direct light on the clusters
// the rays hit, and on the point itself, per unit colour and intensity): geometry, so the
// same rays are cast whatever the lights' colours and intensities, and a relight still equals
// a rebake. The extra rays are fresh stratified sets from the point's texels, counted like its
// first rays (every ray of a gather point weighs alike), so the estimate stays unbiased.
#include <algorithm>
#include <cmath>
#include <vector>

#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/gather.h"
#include "afterglow/core/stages.h"
#include "afterglow/core/parallel.h"
#include "precompute/gather_batch.h"
#include "precompute/light_visibility.h"
#include "precompute/texel_lookup.h"
#include "shading/sampling.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;

// The seed of the extra rays' sequence (the gather's own sets use 0 to 6).
constexpr uint64_t kRefineSeed = 64;

}  // namespace

Status refineGather(const scenes::Scene& scene, const trace::RayTracer& tracer, const TexelSet& texels,
                    const Clusters& clusters, const runtime::TransportData& transport,
                    const LinkOptions& options, TexelGather& gather, Progress& progress) {
  if (!(options.refineError > 0.0f) || options.refineRays <= 0) return Status::ok();
  const uint32_t count = texels.size();
  const uint32_t points = gather.points();
  if (gather.hitStart.size() != size_t(count) + 1 || clusters.texelCluster.size() != count)
    return Status::error("refineGather: the gather does not match the texel set");

  // The lights' unit direct light on clusters and texels (emissive materials are left out, as
  // in the links' light checks: whether one is a source depends on its emission, which a
  // relight may change), each with a floor below which a point's light does not count as
  // uncertain: a twentieth of the light's mean over clusters.
  struct Channel {
    const std::vector<float>* cluster;
    const std::vector<float>* texel;
    float floor;
  };
  std::vector<Channel> channels;
  for (const runtime::Source& s : transport.sources) {
    if (s.kind != runtime::SourceKind::Light || s.clusterTransfer.size() != clusters.size() ||
        s.texelTransfer.size() != count || channels.size() == 32)
      continue;
    double mean = 0.0;
    for (float v : s.clusterTransfer) mean += double(v);
    mean /= double(std::max<size_t>(s.clusterTransfer.size(), 1));
    if (mean > 0.0) channels.push_back({&s.clusterTransfer, &s.texelTransfer, float(0.05 * mean)});
  }
  if (channels.empty()) return Status::ok();

  // Whether ray i of texel t counts for its point (near rays beyond their near field do not).
  auto counts = [&](uint32_t t, uint32_t i, uint32_t code) {
    return i < gather.fullRays[t] || code == TexelGather::kNoHit || !(code & TexelGather::kFar);
  };

  // Per gather point, how many rays each of its texels adds: enough to bring the largest
  // relative standard error of a light's estimate (its first bounce plus the point's own
  // direct light) down to refineError, at most refineRays for the point.
  std::vector<uint32_t> extra(count, 0);
  parallelFor(points, [&](size_t p) {
    const uint32_t first = gather.pointStart[p], last = gather.pointStart[p + 1];
    uint32_t n = 0;
    for (uint32_t k = first; k < last; ++k) {
      const uint32_t t = gather.pointTexels[k];
      for (uint32_t i = gather.hitStart[t]; i < gather.hitStart[t + 1]; ++i)
        n += counts(t, i - gather.hitStart[t], gather.hits[i]) ? 1 : 0;
    }
    if (n < 2) return;

    double worst = 0.0;
    for (const Channel& ch : channels) {
      double sum = 0.0, squares = 0.0, direct = 0.0;
      for (uint32_t k = first; k < last; ++k) {
        const uint32_t t = gather.pointTexels[k];
        direct += double((*ch.texel)[t]);
        for (uint32_t i = gather.hitStart[t]; i < gather.hitStart[t + 1]; ++i) {
          const uint32_t code = gather.hits[i];
          if (!counts(t, i - gather.hitStart[t], code)) continue;
          const uint32_t c = clusterOfHit(clusters, code);
          if (c == kNoTexel) continue;
          const double v = double((*ch.cluster)[c]);
          sum += v, squares += v * v;
        }
      }
      const double mean = sum / n;
      const double varianceOfMean = std::max(0.0, squares / n - mean * mean) / double(n - 1);
      const double level = mean + direct / double(last - first) + double(ch.floor);
      worst = std::max(worst, varianceOfMean / (level * level));
    }
    const double target = double(options.refineError) * double(options.refineError);
    if (!(worst > target)) return;
    // Rays to reach the target: the variance falls as 1/n.
    const double wanted = std::min(double(options.refineRays), double(n) * (worst / target - 1.0));
    const uint32_t members = last - first;
    const uint32_t each = uint32_t(std::ceil(wanted / double(members)));
    for (uint32_t k = first; k < last; ++k) extra[gather.pointTexels[k]] = each;
  }, 256);

  std::vector<uint32_t> extraStart(size_t(count) + 1, 0);
  for (uint32_t t = 0; t < count; ++t) extraStart[t + 1] = extraStart[t] + extra[t];
  if (extraStart[count] == 0) return Status::ok();
  std::vector<uint32_t> codes(extraStart[count], TexelGather::kNoHit);
  const bool albedoDetail = gather.hitAlbedo.size() == gather.hits.size() && !gather.hits.empty();
  std::vector<uint8_t> albedo(albedoDetail ? codes.size() : 0, 0);

  // Hits resolve as the gather's do: light-matched to a texel lit like the hit point.
  const LightVisibility lights(scene);
  TexelLookup lookup(texels);
  if (options.lightMatch && gather.lightsReached.size() == count)
    lookup.setLights(&lights, &gather.lightsReached);
  progress.begin(stageName(Stage::Refine), count);
  constexpr size_t kRaysPerBatch = 1024;
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    for (size_t t = begin; t < end && !progress.cancelled();) {
      batch.clear();
      const size_t firstTexel = t;
      for (; t < end && batch.size() < kRaysPerBatch; ++t) {
        const uint32_t n = extra[t];
        if (n == 0) continue;
        const sampling::Frame frame(texels.normal[t]);
        const sampling::JitteredGrid grid(n);
        sampling::JitteredGrid::Walk walk(grid);
        sampling::Rng rng(sampling::Stream::TexelLinks, t, kRefineSeed);
        for (uint32_t s = 0; s < n; ++s)
          batch.add(texels.position[t], frame, texels.geometricNormal[t], walk.next(rng));
      }
      if (batch.size() == 0) continue;
      batch.trace(tracer, texels, &lookup);
      std::copy(batch.codes().begin(), batch.codes().end(),
                codes.begin() + long(extraStart[firstTexel]));
      if (albedoDetail)
        for (size_t u = firstTexel; u < t; ++u)
          batch.albedoCodes(scene, tracer, extraStart[u] - extraStart[firstTexel], extra[u],
                            options.albedoDetail * texels.edge[u], &albedo[extraStart[u]]);
    }
    progress.advance(end - begin);
  }, 64);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");

  // The extra rays join each texel's full sets, before its near set: hits = full sets, extra,
  // near set. A near texel's extra hits beyond its near field are flagged like its others.
  std::vector<uint32_t> hitStart(size_t(count) + 1, 0);
  for (uint32_t t = 0; t < count; ++t)
    hitStart[t + 1] = hitStart[t] + (gather.hitStart[t + 1] - gather.hitStart[t]) + extra[t];
  std::vector<uint32_t> hits(hitStart[count]);
  std::vector<uint8_t> hitAlbedo(albedoDetail ? hits.size() : 0, 0);
  parallelFor(count, [&](size_t i) {
    const uint32_t t = uint32_t(i);
    const uint32_t old = gather.hitStart[t], n = gather.hitStart[t + 1] - old;
    const uint32_t full = std::min<uint32_t>(gather.fullRays[t], n);
    uint32_t* out = hits.data() + hitStart[t];
    std::copy_n(gather.hits.begin() + long(old), full, out);
    const bool near = n > full;
    for (uint32_t k = 0; k < extra[t]; ++k) {
      const uint32_t code = codes[extraStart[t] + k];
      out[full + k] = near ? nearFieldCode(texels, options.nearField, t, code) : code;
    }
    std::copy_n(gather.hits.begin() + long(old + full), n - full, out + full + extra[t]);
    if (albedoDetail) {
      uint8_t* a = hitAlbedo.data() + hitStart[t];
      std::copy_n(gather.hitAlbedo.begin() + long(old), full, a);
      std::copy_n(albedo.begin() + long(extraStart[t]), extra[t], a + full);
      std::copy_n(gather.hitAlbedo.begin() + long(old + full), n - full, a + full + extra[t]);
    }
  }, 4096);
  for (uint32_t t = 0; t < count; ++t)
    gather.fullRays[t] = uint16_t(std::min<uint32_t>(65535u, gather.fullRays[t] + extra[t]));
  gather.hits = std::move(hits);
  gather.hitAlbedo = std::move(hitAlbedo);
  gather.hitStart = std::move(hitStart);
  return Status::ok();
}

}  // namespace afterglow::baker
