// The texels' gather rays (transport_precompute.h): one pass of cosine-distributed rays per
// valid texel, recording what each ray reached, the sky it saw and how far it went.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "afterglow/baker/raytracer.h"
#include "afterglow/baker/transport_precompute.h"
#include "afterglow/core/parallel.h"
#include "gather_rays.h"
#include "sampling.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::kShCount;

// A valid texel of the same instance next to t in its atlas (the nearest by pixel distance,
// first in scan order on ties), or kNoTexel.
uint32_t validNeighbour(const TexelSet& texels, uint32_t t) {
  const runtime::AtlasLayout& layout = texels.atlases[texels.atlas[t]];
  const int x = texels.pixel[t].x, y = texels.pixel[t].y;
  uint32_t best = kNoTexel;
  int bestDist = std::numeric_limits<int>::max();
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx) {
      const int nx = x + dx, ny = y + dy;
      if (nx < 0 || ny < 0 || nx >= layout.width || ny >= layout.height) continue;
      const uint32_t n = layout.texelOfPixel[size_t(ny) * size_t(layout.width) + size_t(nx)];
      if (n == kNoTexel || !texels.valid[n] || texels.instance[n] != texels.instance[t]) continue;
      const int dist = dx * dx + dy * dy;
      if (dist < bestDist) {
        bestDist = dist;
        best = n;
      }
    }
  return best;
}

}  // namespace

Result<TexelGather> gatherTexels(const scenes::Scene& scene, const RayTracer& tracer,
                                 TexelSet& texels, const LinkOptions& options,
                                 Progress& progress) {
  if (options.texelRays <= 0) return Status::error("gatherTexels: texelRays must be positive");
  const uint32_t count = texels.size();
  if (count >= TexelGather::kBackSide)
    return Status::error(format("gatherTexels: %u texels is more than a bake can index", count));
  TexelGather g;
  const uint32_t rays = uint32_t(options.texelRays);
  g.raysPerTexel = rays;
  std::vector<uint32_t> first(size_t(count) * rays, TexelGather::kNoHit);  // the first pass's hits
  std::vector<double> inverseDistance(count, 0.0);  // Σ 1/t over the texel's rays so far
  g.sky.assign(size_t(count) * kShCount, 0.0f);
  g.harmonicDistance.assign(count, std::numeric_limits<float>::infinity());
  g.backHarmonicDistance.assign(count, std::numeric_limits<float>::infinity());
  // Texels found inside walls are collected apart and invalidated after the pass: hits read
  // texels.valid, so changing it during the pass would race and depend on thread timing.
  std::vector<uint8_t> buried(count, 0);
  const TexelLookup lookup(texels);
  progress.begin("gather rays", count);
  // Texels go in groups of 16 per batch (1024 rays by default).
  constexpr size_t kTexelsPerBatch = 16;
  const sampling::InterleavedGrid grid(rays);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    std::vector<uint32_t> batchTexels;
    for (size_t group = begin; group < end && !progress.cancelled(); group += kTexelsPerBatch) {
      batch.clear();
      batchTexels.clear();
      for (size_t t = group; t < std::min(end, group + kTexelsPerBatch); ++t) {
        if (!texels.valid[t]) continue;
        batchTexels.push_back(uint32_t(t));
        const sampling::Frame frame(texels.normal[t]);
        sampling::Rng rng(sampling::Stream::TexelLinks, t, 0);  // one sequence per texel
        for (uint32_t s = 0; s < rays; ++s)
          batch.add(texels.position[t], frame, texels.geometricNormal[t],
                    grid.point(rng, s, texels.pixel[t].x, texels.pixel[t].y));
      }
      batch.trace(tracer, texels, &lookup);
      for (size_t i = 0; i < batchTexels.size(); ++i) {
        const uint32_t t = batchTexels[i];
        const GatherBatch::Summary sum =
            batch.summarize(tracer, i * rays, (i + 1) * rays, texels.edge[t]);
        // Inside a wall, or wedged in a gap narrower than the texel (the 1 cm between a lamp
        // and the ceiling): light there changes within the texel's footprint, more than one
        // value can hold. No links, no sky; the lightmap fills it from its neighbours.
        if (float(sum.backfaces) > options.maxBackfaceFraction * float(rays) ||
            float(sum.close) >= options.maxEnclosedFraction * float(rays)) {
          buried[t] = 1;
          continue;
        }
        std::copy_n(batch.codes().begin() + long(i * rays), rays, first.begin() + long(size_t(t) * rays));
        for (int k = 0; k < kShCount; ++k) g.sky[size_t(t) * kShCount + size_t(k)] = float(sum.sky[k]);
        inverseDistance[t] = sum.inverseDistance;
      }
    }
    progress.advance(end - begin);
  }, 4096);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");

  // A second pass for texels near other geometry (the first pass's harmonic distance under
  // nearDistance texel edges), with a stratified set of its own.
  const uint32_t more = uint32_t(std::max(0, options.nearRays));
  std::vector<uint32_t> extra(count, 0);
  for (uint32_t t = 0; t < count; ++t)
    if (texels.valid[t] && !buried[t] && more > 0 &&
        double(rays) < inverseDistance[t] * double(options.nearDistance * texels.edge[t]))
      extra[t] = more;
  std::vector<uint32_t> extraStart(size_t(count) + 1, 0);
  for (uint32_t t = 0; t < count; ++t) extraStart[t + 1] = extraStart[t] + extra[t];
  std::vector<uint32_t> second(extraStart[count], TexelGather::kNoHit);
  progress.begin("gather rays (near geometry)", count);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    std::vector<uint32_t> batchTexels;
    const size_t perBatch = std::max<size_t>(1, 1024 / std::max<uint32_t>(1, more));
    for (size_t t = begin; t < end && !progress.cancelled();) {
      batch.clear();
      batchTexels.clear();
      for (; t < end && batchTexels.size() < perBatch; ++t) {
        if (!extra[t]) continue;
        batchTexels.push_back(uint32_t(t));
        const sampling::Frame frame(texels.normal[t]);
        sampling::Rng rng(sampling::Stream::TexelLinks, t, 1);
        for (uint32_t s = 0; s < more; ++s)
          batch.add(texels.position[t], frame, texels.geometricNormal[t],
                    sampling::stratified2(rng, s, more));
      }
      if (batchTexels.empty()) break;
      batch.trace(tracer, texels, &lookup);
      for (size_t i = 0; i < batchTexels.size(); ++i) {
        const uint32_t u = batchTexels[i];
        const GatherBatch::Summary sum = batch.summarize(tracer, i * more, (i + 1) * more);
        std::copy_n(batch.codes().begin() + long(i * more), more,
                    second.begin() + long(extraStart[u]));
        for (int k = 0; k < kShCount; ++k) g.sky[size_t(u) * kShCount + size_t(k)] += float(sum.sky[k]);
        inverseDistance[u] += sum.inverseDistance;
      }
    }
    progress.advance(end - begin);
  }, 4096);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");

  // Every texel's rays in one list; sky and distance as means over all of them.
  g.hitStart.assign(size_t(count) + 1, 0);
  for (uint32_t t = 0; t < count; ++t)
    g.hitStart[t + 1] = g.hitStart[t] + (buried[t] || !texels.valid[t] ? 0 : rays + extra[t]);
  g.hits.resize(g.hitStart[count]);
  for (uint32_t t = 0; t < count; ++t) {
    if (g.hitStart[t + 1] == g.hitStart[t]) {
      std::fill_n(&g.sky[size_t(t) * kShCount], kShCount, 0.0f);
      continue;
    }
    std::copy_n(first.begin() + long(size_t(t) * rays), rays, g.hits.begin() + long(g.hitStart[t]));
    std::copy_n(second.begin() + long(extraStart[t]), extra[t],
                g.hits.begin() + long(g.hitStart[t] + rays));
    const float n = float(rays + extra[t]);
    for (int k = 0; k < kShCount; ++k) g.sky[size_t(t) * kShCount + size_t(k)] /= n;
    if (inverseDistance[t] > 0.0) g.harmonicDistance[t] = float(double(n) / inverseDistance[t]);
  }
  std::vector<uint32_t>().swap(first);
  std::vector<uint32_t>().swap(second);

  // Invalidate buried texels; rays that landed on one stand on a valid neighbour instead (or
  // are absorbed when none is near).
  std::vector<uint32_t> standIn(count, kNoTexel);
  bool anyBuried = false;
  for (uint32_t t = 0; t < count; ++t)
    if (buried[t]) texels.valid[t] = 0, anyBuried = true;
  if (anyBuried) {
    for (uint32_t t = 0; t < count; ++t)
      if (buried[t]) standIn[t] = validNeighbour(texels, t);
    for (uint32_t& code : g.hits) {
      if (code == TexelGather::kNoHit) continue;
      const uint32_t t = code & ~TexelGather::kBackSide;
      if (!buried[t]) continue;
      const uint32_t s = standIn[t];
      code = s == kNoTexel ? TexelGather::kNoHit : (s | (code & TexelGather::kBackSide));
    }
  }
  // The backs some ray reached, and how far their own rays go (for their clusters).
  g.backSeen.assign(count, 0);
  for (uint32_t code : g.hits)
    if (code != TexelGather::kNoHit && (code & TexelGather::kBackSide))
      g.backSeen[code & ~TexelGather::kBackSide] = 1;
  const uint32_t backRays = std::max(4u, rays / 8);
  progress.begin("gather rays (backs)", count);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    GatherBatch back;
    for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
      if (!g.backSeen[t] || !texels.valid[t]) continue;
      back.clear();
      const sampling::Frame frame(-texels.normal[t]);
      for (uint32_t s = 0; s < backRays; ++s) {
        sampling::Rng rng(sampling::Stream::BackDistance, t, s);
        back.add(texels.backPosition(uint32_t(t)), frame, -texels.geometricNormal[t],
                 sampling::stratified2(rng, s, backRays));
      }
      back.trace(tracer, texels, nullptr);
      const GatherBatch::Summary seen = back.summarize(tracer, 0, backRays);
      if (seen.inverseDistance > 0.0)
        g.backHarmonicDistance[t] = float(double(backRays) / seen.inverseDistance);
    }
    progress.advance(end - begin);
  }, 4096);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  return g;
}

}  // namespace afterglow::baker
