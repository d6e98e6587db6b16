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
  g.hits.assign(size_t(count) * rays, TexelGather::kNoHit);
  g.sky.assign(size_t(count) * kShCount, 0.0f);
  g.harmonicDistance.assign(count, std::numeric_limits<float>::infinity());
  g.backHarmonicDistance.assign(count, std::numeric_limits<float>::infinity());
  const uint32_t backRays = std::max(4u, rays / 4);
  // Texels found inside walls are collected apart and invalidated after the pass: hits read
  // texels.valid, so changing it during the pass would race and depend on thread timing.
  std::vector<uint8_t> buried(count, 0);
  progress.begin("gather rays", count);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
      if (!texels.valid[t]) continue;
      batch.clear();
      const sampling::Frame frame(texels.normal[t]);
      for (uint32_t s = 0; s < rays; ++s) {
        sampling::Rng rng(sampling::Stream::TexelLinks, t, s);
        batch.add(texels.position[t], frame, texels.geometricNormal[t],
                  sampling::stratified2(rng, s, rays));
      }
      batch.trace(scene, tracer, texels);
      if (float(batch.backfaces) > options.maxBackfaceFraction * float(rays)) {
        buried[t] = 1;  // inside a wall: no links, no sky; filled from neighbours later
        continue;
      }
      std::copy(batch.codes.begin(), batch.codes.end(), g.hits.begin() + long(t * rays));
      for (int i = 0; i < kShCount; ++i) g.sky[t * kShCount + size_t(i)] = float(batch.sky[i] / rays);
      if (batch.inverseDistance > 0.0) g.harmonicDistance[t] = float(double(rays) / batch.inverseDistance);
      if (!texelDoubleSided(scene, texels, uint32_t(t))) continue;
      batch.clear();
      const sampling::Frame back(-texels.normal[t]);
      for (uint32_t s = 0; s < backRays; ++s) {
        sampling::Rng rng(sampling::Stream::BackDistance, t, s);
        batch.add(texels.backPosition(uint32_t(t)), back, -texels.geometricNormal[t],
                  sampling::stratified2(rng, s, backRays));
      }
      batch.trace(scene, tracer, texels);
      if (batch.inverseDistance > 0.0)
        g.backHarmonicDistance[t] = float(double(backRays) / batch.inverseDistance);
    }
    progress.advance(end - begin);
  });
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");

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
    for (uint32_t t = 0; t < count; ++t)
      if (buried[t]) std::fill_n(g.hits.begin() + long(size_t(t) * rays), rays, TexelGather::kNoHit);
  }
  return g;
}

}  // namespace afterglow::baker
