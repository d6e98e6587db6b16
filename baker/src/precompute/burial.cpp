#include "precompute/burial.h"

#include <atomic>
#include <cmath>

#include "afterglow/core/parallel.h"
#include "afterglow/core/stages.h"
#include "afterglow/trace/raytracer.h"
#include "shading/sampling.h"

namespace afterglow::baker {

bool litCavity(const trace::RayTracer& tracer, const TexelSet& texels, uint32_t t) {
  const sampling::Frame frame(texels.normal[t]);
  const float half = 0.5f * texels.edge[t];
  for (const glm::vec2 corner : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1),
                                 glm::vec2(-1, 1)}) {
    trace::Ray ray;
    ray.origin = texels.position[t] + half * (corner.x * frame.t + corner.y * frame.b);
    ray.direction = texels.normal[t];
    ray.tfar = texels.edge[t];
    const trace::Hit hit = tracer.intersect(ray);
    if (!hit.valid()) return false;
    const scenes::Material& m = tracer.material(hit);
    if (!m.emissive() || !m.emitsFrom(hit.frontFace)) return false;
  }
  return true;
}

namespace {

// The gather's rule (gather.cpp, isBuried) on kBurialRays cosine rays of texel t, cast in two
// halves that each cover the hemisphere: most texels tested are plainly buried (the floor under
// a column), or plainly not after half the rays (no back face, few close hits), and stop there.
bool buried(const trace::RayTracer& tracer, const TexelSet& texels, uint32_t t,
            const LinkOptions& options) {
  const sampling::Frame frame(texels.normal[t]);
  const sampling::Rng::ItemSeed seed{sampling::Rng::itemSeed(sampling::Stream::Burial, t)};
  constexpr int kHalf = kBurialRays / 2;
  int backfaces = 0, close = 0;
  for (int half = 0; half < 2; ++half) {
    trace::Ray rays[kHalf];
    trace::Hit hits[kHalf];
    for (int i = 0; i < kHalf; ++i) {
      // The halves interleave over the 4 × 4 strata: each half holds two of the four radii in
      // every azimuth row. Halves of consecutive strata split the azimuth instead (rows 0-1 vs
      // 2-3), so a texel half inside a wall whose first half faced the open side stopped
      // after 8 rays as not buried (Sponza's at 16 texels/m: half their rays on back faces).
      const int index = 2 * i + half;
      sampling::Rng rng(seed, uint64_t(index));
      const glm::vec2 u = sampling::stratified2(rng, uint32_t(index), uint32_t(kBurialRays));
      rays[i].origin = texels.position[t];
      rays[i].direction = frame.toWorld(sampling::cosineHemisphere(u));
    }
    tracer.intersect(rays, hits, size_t(kHalf));
    for (const trace::Hit& hit : hits) {
      if (!hit.valid()) continue;
      if (!hit.frontFace && !tracer.material(hit).doubleSided) ++backfaces;
      if (hit.t < texels.edge[t]) ++close;
    }
    if (insideAWall(backfaces, kBurialRays, options)) return true;
    // Plainly clear: no back face, and not half the close hits the rule asks of all 16.
    if (half == 0 && backfaces == 0 && !wedgedInAGap(2 * close, kBurialRays, options)) return false;
  }
  return wedgedInAGap(close, kBurialRays, options) && !litCavity(tracer, texels, t);
}

}  // namespace

size_t buryLightmapTexels(const trace::RayTracer& tracer, TexelSet& lightmap,
                          const LinkOptions& options, Progress& progress) {
  // Marked apart, then applied: the test reads no validity, but keep the pass's reads and
  // writes apart all the same.
  std::vector<uint8_t> marks(lightmap.size(), 0);
  std::atomic<size_t> count{0};
  progress.begin(stageStep(Stage::Direct, "buried lightmap texels"), lightmap.size());
  parallelForBlocks(lightmap.size(), [&](size_t begin, size_t end, int) {
    size_t local = 0;
    for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
      if (!lightmap.valid[t]) continue;
      if (buried(tracer, lightmap, uint32_t(t), options)) marks[t] = 1, ++local;
    }
    count += local;
    progress.advance(end - begin);
  }, 1024);
  progress.end();
  for (size_t t = 0; t < marks.size(); ++t)
    if (marks[t]) lightmap.valid[t] = 0;
  return count;
}

}  // namespace afterglow::baker
