// The texels' gather rays (transport_precompute.h): cosine-distributed rays from every valid
// texel, recording what each ray reached, the sky it saw and how far it went, and the gather
// points that pool them.
//
// Bounced light is smooth away from other geometry, so a 2×2 block of texels on one surface
// shares one gather point and each of its texels casts a quarter of the rays (the four sets form
// one stratified set, and neighbouring blocks' sets one finer still: sampling::TiledSobol).
// Near other geometry bounced light changes within a texel
// or two: a texel there is a gather point of its own, with a full set of rays plus nearRays more
// that resolve its near field.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/gather.h"
#include "afterglow/baker/stages.h"
#include "afterglow/core/parallel.h"
#include "precompute/gather_batch.h"
#include "precompute/light_visibility.h"
#include "precompute/sight_lines.h"
#include "precompute/texel_lookup.h"
#include "shading/sampling.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::kShCount;

// Groups the valid texels into 2×2 atlas blocks on one surface; texels near other geometry
// (TexelSet::nearGeometry) stay alone. Returns per texel its group, numbered in atlas scan
// order, and the group sizes.
void formBlocks(const TexelSet& texels, std::vector<uint32_t>& groupOf,
                std::vector<uint8_t>& groupSize) {
  groupOf.assign(texels.size(), kNoTexel);
  groupSize.clear();
  for (const runtime::AtlasLayout& layout : texels.atlases)
    for (int by = 0; by < layout.height; by += 2)
      for (int bx = 0; bx < layout.width; bx += 2) {
        uint32_t members[4];
        int count = 0;
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 2; ++i) {
            const int x = bx + i, y = by + j;
            if (x >= layout.width || y >= layout.height) continue;
            const uint32_t t = layout.texelOfPixel[size_t(y) * size_t(layout.width) + size_t(x)];
            if (t != kNoTexel && texels.valid[t]) members[count++] = t;
          }
        // Greedy: each unassigned texel opens a group that takes the later ones it shares a
        // surface with (and which share one with every member so far).
        for (int i = 0; i < count; ++i) {
          const uint32_t a = members[i];
          if (groupOf[a] != kNoTexel) continue;
          const uint32_t g = uint32_t(groupSize.size());
          groupOf[a] = g;
          groupSize.push_back(1);
          if (texels.nearGeometry[a]) continue;
          uint32_t in[4] = {a};
          int size = 1;
          for (int j = i + 1; j < count; ++j) {
            const uint32_t b = members[j];
            if (groupOf[b] != kNoTexel || texels.nearGeometry[b]) continue;
            bool fits = true;
            for (int k = 0; k < size && fits; ++k) fits = sameSurface(texels, in[k], b);
            if (!fits) continue;
            groupOf[b] = g;
            in[size++] = b;
          }
          groupSize.back() = uint8_t(size);
        }
      }
}

// Rays of each texel of a group of `size`: the group casts `rays` in all (three share as four).
uint32_t raysPerMember(uint32_t rays, uint32_t size) {
  return std::max(1u, rays / (size == 3 ? 4u : std::max(1u, size)));
}

// What a texel's rays summed to, for its own decisions and its gather point's pooled values.
struct TexelRays {
  double sky[kShCount] = {};
  double inverseDistance = 0.0;
  uint32_t count = 0;
};

// Whether an emitter that shines on texel t covers its whole footprint within one texel edge:
// a ray along the normal from each of the footprint's four corners hits, nearer than the edge,
// emissive geometry whose side facing the texel emits (the back of a double-sided lamp panel
// just below a ceiling).
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

}  // namespace

Result<TexelGather> gatherTexels(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                 TexelSet& texels, const LinkOptions& options,
                                 Progress& progress) {
  if (options.texelRays <= 0 || options.texelRays > 16384)
    return Status::error("gatherTexels: texelRays must be between 1 and 16384");
  const uint32_t count = texels.size();
  if (count > TexelGather::kTexelMask)
    return Status::error(format("gatherTexels: %u texels is more than a bake can index", count));
  TexelGather g;
  const uint32_t rays = uint32_t(options.texelRays);
  g.raysPerTexel = rays;

  std::vector<uint32_t> groupOf;
  std::vector<uint8_t> groupSize;
  formBlocks(texels, groupOf, groupSize);
  const uint32_t groups = uint32_t(groupSize.size());
  std::vector<uint32_t> groupStart(size_t(groups) + 1, 0), groupTexels;
  for (uint32_t g2 = 0; g2 < groups; ++g2) groupStart[g2 + 1] = groupStart[g2] + groupSize[g2];
  groupTexels.resize(groupStart[groups]);
  {
    std::vector<uint32_t> fill(groupStart.begin(), groupStart.end() - 1);
    for (uint32_t t = 0; t < count; ++t)
      if (groupOf[t] != kNoTexel) groupTexels[fill[groupOf[t]]++] = t;
  }
  // A full block's four texels share one stratified set.
  auto quartered = [&](uint32_t t) { return groupSize[groupOf[t]] == 4; };

  // The first pass: every valid texel its share of its group's rays.
  std::vector<uint32_t> firstCount(count, 0), firstStart(size_t(count) + 1, 0);
  for (uint32_t t = 0; t < count; ++t) {
    if (texels.valid[t]) firstCount[t] = raysPerMember(rays, groupSize[groupOf[t]]);
    firstStart[t + 1] = firstStart[t] + firstCount[t];
  }
  std::vector<uint32_t> first(firstStart[count], TexelGather::kNoHit);
  // The albedo at close hits on textured surfaces (TexelGather::hitAlbedo), as `first`.
  const bool albedoDetail = options.albedoDetail > 0.0f;
  auto albedoReach = [&](size_t t) { return options.albedoDetail * texels.edge[t]; };
  std::vector<uint8_t> firstAlbedo(albedoDetail ? first.size() : 0, 0);
  std::vector<TexelRays> sums(count);
  // Texels found inside walls are collected apart and invalidated after the pass: hits read
  // texels.valid, so changing it during the pass would race and depend on thread timing.
  std::vector<uint8_t> buried(count, 0);
  // The lights each texel's sample sees, for the close hits' check (TexelOfHit::lightMatch).
  const LightVisibility lights(scene);
  std::vector<uint32_t> reached =
      options.lightMatch ? lights.texels(tracer, texels) : std::vector<uint32_t>();
  TexelLookup lookup(texels);
  if (options.lightMatch) lookup.setLights(&lights, &reached);
  // Texel t's points of one set of rays: `set` 0 for the first pass of a full block's texels,
  // whose four texels' points make one stratified set, 1 for any other texel's full set (its
  // first pass or its top-up), 2 for the near set; `n` the rays of that set. Neighbours casting
  // the same kind of set take their points from one sequence (sampling::TiledSobol), so their
  // errors cancel instead of adding up into blotches.
  auto tileSequence = [&](uint32_t t, uint32_t n, uint64_t set) {
    return sampling::TiledSobol(
        sampling::Rng::itemSeed(sampling::Stream::TexelLinks, texels.atlas[t]) ^
            sampling::mix64((set << 32) | n),
        texels.pixel[t].x, texels.pixel[t].y, n);
  };
  // The points of a set in the order they are traced (sampling::coherentOrder).
  auto setPoints = [&](uint32_t t, uint32_t n, uint64_t set, std::vector<glm::vec2>& out) {
    const sampling::TiledSobol sequence = tileSequence(t, n, set);
    out.resize(n);
    for (uint32_t s = 0; s < n; ++s) out[s] = sequence.point(s);
    sampling::coherentOrder(out);
  };
  // Texel t's first-pass samples, sample(s, u) for s = 0 .. firstCount[t] (a pure function of
  // the texel, so a ray can be cast again alike).
  auto firstSamples = [&](uint32_t t, auto&& sample) {
    thread_local std::vector<glm::vec2> points;
    setPoints(t, firstCount[t], quartered(t) ? 0 : 1, points);
    for (uint32_t s = 0; s < points.size(); ++s) sample(s, points[s]);
  };
  auto accumulate = [&](TexelRays& s, const GatherBatch::Summary& sum, uint32_t n) {
    for (int k = 0; k < kShCount; ++k) s.sky[k] += sum.sky[k];
    s.inverseDistance += sum.inverseDistance;
    s.count += n;
  };
  progress.begin(stageName(Stage::Gather), count);
  constexpr size_t kRaysPerBatch = 1024;
  // Small blocks of texels: the work per texel varies tenfold (near texels cast many more
  // rays, and they sit together), and a few big blocks would leave a thread idle at the end.
  constexpr size_t kTexelsPerBlock = 512;
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    std::vector<uint32_t> batchTexels, batchFirst;
    for (size_t t = begin; t < end && !progress.cancelled();) {
      batch.clear();
      batchTexels.clear();
      batchFirst.clear();
      for (; t < end && batch.size() < kRaysPerBatch; ++t) {
        if (!texels.valid[t]) continue;
        batchTexels.push_back(uint32_t(t));
        batchFirst.push_back(uint32_t(batch.size()));
        const sampling::Frame frame(texels.normal[t]);
        firstSamples(uint32_t(t), [&](uint32_t, glm::vec2 u) {
          batch.add(texels.position[t], frame, texels.geometricNormal[t], u);
        });
      }
      if (batchTexels.empty()) break;
      batch.trace(tracer, texels, &lookup);
      for (size_t i = 0; i < batchTexels.size(); ++i) {
        const uint32_t u = batchTexels[i], n = firstCount[u];
        const GatherBatch::Summary sum =
            batch.summarize(tracer, batchFirst[i], batchFirst[i] + n, texels.edge[u]);
        // Inside a wall, or wedged in a gap narrower than the texel (the floor under the rim
        // of a box): light there changes within the texel's footprint, more than one value
        // can hold. No links, no sky; the lightmap fills it from its neighbours. Burying loses
        // only the little light that found its way into the gap, except where an emitter
        // covers the texel (the ceiling above a double-sided lamp panel 1 cm below it, whose
        // back glTF makes emit): there the cavity takes up a first-order share of the lamp's
        // power, and passes some of it on through the gap, so the texel stays.
        if (float(sum.backfaces) > options.maxBackfaceFraction * float(n) ||
            (float(sum.close) >= options.maxEnclosedFraction * float(n) &&
             !litCavity(tracer, texels, u))) {
          buried[u] = 1;
          continue;
        }
        std::copy_n(batch.codes().begin() + long(batchFirst[i]), n, first.begin() + long(firstStart[u]));
        if (albedoDetail)
          batch.albedoCodes(scene, tracer, batchFirst[i], n, albedoReach(u),
                            &firstAlbedo[firstStart[u]]);
        accumulate(sums[u], sum, n);
      }
    }
    progress.advance(end - begin);
  }, kTexelsPerBlock);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  // Buried texels leave now, so that the rays below, and the first-pass rays that landed on
  // one (cast again further down), find the texels that stay: a hit on a buried texel's surface
  // takes the light of a neighbour the hit point sees (TexelLookup, TexelOfHit), never of one
  // behind a wall (a roof that cuts through a cornice: the cornice's texel across the roof's
  // joint is buried, and its neighbour above the roof is in the sun).
  bool anyBuried = false;
  for (uint32_t t = 0; t < count; ++t)
    if (buried[t]) texels.valid[t] = 0, anyBuried = true;
  TexelLookup settled(texels);
  if (options.lightMatch) settled.setLights(&lights, &reached);

  // Where other geometry is close (harmonic distance under blockDistance texel edges) bounced
  // light changes too fast to share: such a texel leaves its block for a gather point of its
  // own with a full set of rays. Nearer still (under nearDistance edges) it casts nearRays more
  // for its near field.
  const uint32_t more = uint32_t(std::max(0, options.nearRays));
  std::vector<uint8_t> alone(count, 0), nearTexel(count, 0), keepFirst(count, 0);
  for (uint32_t t = 0; t < count; ++t) {
    if (!texels.valid[t] || buried[t]) continue;
    keepFirst[t] = 1;
    // harmonic distance < k edges  <=>  count < inverseDistance × k × edge
    const double reach = sums[t].inverseDistance * double(texels.edge[t]);
    nearTexel[t] = more > 0 && double(sums[t].count) < reach * double(options.nearDistance);
    alone[t] = nearTexel[t] || double(sums[t].count) < reach * double(options.blockDistance);
  }
  // The rays that made a texel leave its block, or cast near rays, are not a fair sample of
  // its light (chosen for having met geometry close by, they would overstate the near field):
  // such a texel casts a fresh full set and keeps its first rays for nothing else. In a full
  // block, the first staying texel casts the leaver's quarter of the grid instead (a buried
  // texel's too), so the block's rays still cover every quarter.
  std::vector<uint32_t> topUp(count, 0), adoptStart(size_t(count) + 1, 0), adopted;
  std::vector<uint32_t> adopter(count, kNoTexel);
  for (uint32_t t = 0; t < count; ++t)
    if (nearTexel[t] || (alone[t] && groupSize[groupOf[t]] > 1)) {
      keepFirst[t] = 0;
      sums[t] = TexelRays();
    }
  for (uint32_t g2 = 0; g2 < groups; ++g2) {
    if (groupSize[g2] != 4) continue;
    uint32_t stay = kNoTexel;
    for (uint32_t k = groupStart[g2]; k < groupStart[g2 + 1] && stay == kNoTexel; ++k)
      if (keepFirst[groupTexels[k]] && !alone[groupTexels[k]]) stay = groupTexels[k];
    for (uint32_t k = groupStart[g2]; k < groupStart[g2 + 1]; ++k) {
      const uint32_t t = groupTexels[k];
      if ((alone[t] || buried[t]) && stay != kNoTexel) adopter[t] = stay;
    }
  }
  for (uint32_t t = 0; t < count; ++t)
    if (adopter[t] != kNoTexel) ++adoptStart[adopter[t] + 1];
  for (uint32_t t = 0; t < count; ++t) adoptStart[t + 1] += adoptStart[t];
  adopted.resize(adoptStart[count]);
  {
    std::vector<uint32_t> fill(adoptStart.begin(), adoptStart.end() - 1);
    for (uint32_t t = 0; t < count; ++t)
      if (adopter[t] != kNoTexel) adopted[fill[adopter[t]]++] = t;
  }
  std::vector<uint32_t> extraStart(size_t(count) + 1, 0);
  for (uint32_t t = 0; t < count; ++t) {
    if (alone[t]) topUp[t] = rays - std::min(rays, keepFirst[t] ? firstCount[t] : 0u);
    uint32_t extra = topUp[t] + (nearTexel[t] ? more : 0);
    for (uint32_t k = adoptStart[t]; k < adoptStart[t + 1]; ++k) extra += firstCount[adopted[k]];
    extraStart[t + 1] = extraStart[t] + extra;
  }
  std::vector<uint32_t> second(extraStart[count], TexelGather::kNoHit);
  std::vector<uint8_t> secondAlbedo(albedoDetail ? second.size() : 0, 0);
  progress.begin(stageStep(Stage::Gather, "near geometry"), count);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    std::vector<uint32_t> batchTexels;
    for (size_t t = begin; t < end && !progress.cancelled();) {
      batch.clear();
      batchTexels.clear();
      for (; t < end && batch.size() < kRaysPerBatch; ++t) {
        if (extraStart[t + 1] == extraStart[t]) continue;
        batchTexels.push_back(uint32_t(t));
        const sampling::Frame frame(texels.normal[t]);
        auto cast = [&](uint32_t from, uint32_t n, uint64_t set) {
          thread_local std::vector<glm::vec2> points;
          setPoints(from, n, set, points);
          for (const glm::vec2 u : points)
            batch.add(texels.position[t], frame, texels.geometricNormal[t], u);
        };
        // In the order the hits are kept: the top-up (a full set), the adopted texels' points
        // (their share of their block's set), then the near set.
        cast(uint32_t(t), topUp[t], 1);
        for (uint32_t k = adoptStart[t]; k < adoptStart[t + 1]; ++k)
          cast(adopted[k], firstCount[adopted[k]], 0);
        cast(uint32_t(t), nearTexel[t] ? more : 0u, 2);
      }
      if (batchTexels.empty()) break;
      batch.trace(tracer, texels, &settled);
      size_t at = 0;
      for (const uint32_t u : batchTexels) {
        const uint32_t n = extraStart[u + 1] - extraStart[u];
        const GatherBatch::Summary sum = batch.summarize(tracer, at, at + n);
        std::copy_n(batch.codes().begin() + long(at), n, second.begin() + long(extraStart[u]));
        if (albedoDetail)
          batch.albedoCodes(scene, tracer, at, n, albedoReach(u), &secondAlbedo[extraStart[u]]);
        accumulate(sums[u], sum, n);
        at += n;
      }
    }
    progress.advance(end - begin);
  }, kTexelsPerBlock);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  // Which hits of a near texel lie beyond its near field (nearField texel edges): measured to
  // the sample of the texel hit, which sits within that texel of the hit point.
  auto farCode = [&](uint32_t from, uint32_t code) {
    return nearFieldCode(texels, options.nearField, from, code);
  };

  // Gather points: the blocks without the texels that left them, numbered in the blocks'
  // order, each leaver a point of its own; then the pooled sky and distance of each point (over
  // all its rays) for its texels.
  std::vector<uint32_t> pointOfGroup(groups, kNoTexel);
  g.pointOfTexel.assign(count, TexelGather::kNoHit);
  uint32_t points = 0;
  for (uint32_t g2 = 0; g2 < groups; ++g2)
    for (uint32_t k = groupStart[g2]; k < groupStart[g2 + 1]; ++k) {
      const uint32_t t = groupTexels[k];
      if (!texels.valid[t] || buried[t]) continue;
      if (alone[t]) {
        g.pointOfTexel[t] = points++;
      } else {
        if (pointOfGroup[g2] == kNoTexel) pointOfGroup[g2] = points++;
        g.pointOfTexel[t] = pointOfGroup[g2];
      }
    }
  {
    std::vector<uint32_t> size(points, 0);
    for (uint32_t t = 0; t < count; ++t)
      if (g.pointOfTexel[t] != TexelGather::kNoHit) ++size[g.pointOfTexel[t]];
    g.pointStart.assign(size_t(points) + 1, 0);
    for (uint32_t p = 0; p < points; ++p) g.pointStart[p + 1] = g.pointStart[p] + size[p];
    g.pointTexels.resize(g.pointStart[points]);
    std::vector<uint32_t> fill(g.pointStart.begin(), g.pointStart.end() - 1);
    for (uint32_t t = 0; t < count; ++t)
      if (g.pointOfTexel[t] != TexelGather::kNoHit) g.pointTexels[fill[g.pointOfTexel[t]]++] = t;
  }
  g.sky.assign(size_t(count) * kShCount, 0.0f);
  g.harmonicDistance.assign(count, std::numeric_limits<float>::infinity());
  for (uint32_t p = 0; p < points; ++p) {
    TexelRays pooled;
    for (uint32_t k = g.pointStart[p]; k < g.pointStart[p + 1]; ++k) {
      const TexelRays& s = sums[g.pointTexels[k]];
      for (int i = 0; i < kShCount; ++i) pooled.sky[i] += s.sky[i];
      pooled.inverseDistance += s.inverseDistance;
      pooled.count += s.count;
    }
    for (uint32_t k = g.pointStart[p]; k < g.pointStart[p + 1]; ++k) {
      const uint32_t t = g.pointTexels[k];
      for (int i = 0; i < kShCount; ++i)
        g.sky[size_t(t) * kShCount + size_t(i)] =
            pooled.count > 0 ? float(pooled.sky[i] / double(pooled.count)) : 0.0f;
      if (pooled.inverseDistance > 0.0)
        g.harmonicDistance[t] = float(double(pooled.count) / pooled.inverseDistance);
    }
  }

  // The kept first-pass rays that landed on a buried texel, cast again and resolved against
  // the texels that stay.
  auto onBuried = [&](uint32_t code) {
    return code != TexelGather::kNoHit && buried[code & TexelGather::kTexelMask];
  };
  if (anyBuried)
    parallelForBlocks(count, [&](size_t begin, size_t end, int) {
      GatherBatch batch;
      std::vector<uint32_t> at;  // per queued ray, its index into `first`
      std::vector<float> reach;  // ... and its texel's albedoReach
      std::vector<uint32_t> redo;
      for (size_t t = begin; t < end;) {
        batch.clear();
        at.clear();
        reach.clear();
        for (; t < end && batch.size() < kRaysPerBatch; ++t) {
          if (!keepFirst[t]) continue;
          redo.clear();
          for (uint32_t s = 0; s < firstCount[t]; ++s)
            if (onBuried(first[firstStart[t] + s])) redo.push_back(s);
          if (redo.empty()) continue;
          const sampling::Frame frame(texels.normal[t]);
          size_t next = 0;
          firstSamples(uint32_t(t), [&](uint32_t s, glm::vec2 u) {
            if (next == redo.size() || redo[next] != s) return;
            ++next;
            batch.add(texels.position[t], frame, texels.geometricNormal[t], u);
            at.push_back(firstStart[t] + s);
            reach.push_back(albedoReach(t));
          });
        }
        if (at.empty()) continue;
        batch.trace(tracer, texels, &settled);
        for (size_t k = 0; k < at.size(); ++k) {
          first[at[k]] = batch.codes()[k];
          if (albedoDetail) batch.albedoCodes(scene, tracer, k, 1, reach[k], &firstAlbedo[at[k]]);
        }
      }
    }, kTexelsPerBlock);

  // Every texel's rays in one list: its first pass (unless it left a full block), then its
  // top-up, adopted and near sets; all but the near set are full sets.
  g.hitStart.assign(size_t(count) + 1, 0);
  g.fullRays.assign(count, 0);
  for (uint32_t t = 0; t < count; ++t) {
    const uint32_t kept = keepFirst[t] ? firstCount[t] : 0;
    const uint32_t extra = extraStart[t + 1] - extraStart[t];
    const bool valid = texels.valid[t] && !buried[t];
    g.hitStart[t + 1] = g.hitStart[t] + (valid ? kept + extra : 0);
    if (valid) g.fullRays[t] = uint16_t(kept + extra - (nearTexel[t] ? more : 0));
  }
  g.hits.resize(g.hitStart[count]);
  g.hitAlbedo.assign(albedoDetail ? g.hits.size() : 0, 0);
  parallelFor(count, [&](size_t i) {
    const uint32_t t = uint32_t(i);
    if (g.hitStart[t + 1] == g.hitStart[t]) return;
    uint32_t* out = &g.hits[g.hitStart[t]];
    const uint32_t kept = keepFirst[t] ? firstCount[t] : 0;
    std::copy_n(first.begin() + long(firstStart[t]), kept, out);
    std::copy_n(second.begin() + long(extraStart[t]), extraStart[t + 1] - extraStart[t], out + kept);
    if (albedoDetail) {
      uint8_t* albedo = &g.hitAlbedo[g.hitStart[t]];
      std::copy_n(firstAlbedo.begin() + long(firstStart[t]), kept, albedo);
      std::copy_n(secondAlbedo.begin() + long(extraStart[t]), extraStart[t + 1] - extraStart[t],
                  albedo + kept);
    }
    if (nearTexel[t])
      for (uint32_t k = 0; k < g.hitStart[t + 1] - g.hitStart[t]; ++k) out[k] = farCode(t, out[k]);
  });
  std::vector<uint32_t>().swap(first);
  std::vector<uint32_t>().swap(second);
  std::vector<uint8_t>().swap(firstAlbedo);
  std::vector<uint8_t>().swap(secondAlbedo);

  // The backs some ray reached, and how far their own rays go (for their clusters).
  g.backSeen.assign(count, 0);
  g.backHarmonicDistance.assign(count, std::numeric_limits<float>::infinity());
  for (uint32_t code : g.hits)
    if (code != TexelGather::kNoHit && (code & TexelGather::kBackSide))
      g.backSeen[code & TexelGather::kTexelMask] = 1;
  const uint32_t backRays = std::max(4u, rays / 8);
  progress.begin(stageStep(Stage::Gather, "backs"), count);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    // Several texels' back rays per trace, as in the passes above.
    GatherBatch back;
    std::vector<uint32_t> batchTexels;
    const sampling::Stratified strata(backRays);
    for (size_t t = begin; t < end && !progress.cancelled();) {
      back.clear();
      batchTexels.clear();
      for (; t < end && back.size() < kRaysPerBatch; ++t) {
        if (!g.backSeen[t] || !texels.valid[t]) continue;
        batchTexels.push_back(uint32_t(t));
        const sampling::Frame frame(-texels.normal[t]);
        const sampling::Rng::ItemSeed seed{
            sampling::Rng::itemSeed(sampling::Stream::BackDistance, t)};
        for (uint32_t s = 0; s < backRays; ++s) {
          sampling::Rng rng(seed, s);
          back.add(texels.backPosition(uint32_t(t)), frame, -texels.geometricNormal[t],
                   strata.point(rng, s));
        }
      }
      if (batchTexels.empty()) break;
      back.trace(tracer, texels, nullptr);
      for (size_t i = 0; i < batchTexels.size(); ++i) {
        const GatherBatch::Summary seen = back.summarize(tracer, i * backRays, (i + 1) * backRays);
        if (seen.inverseDistance > 0.0)
          g.backHarmonicDistance[batchTexels[i]] = float(double(backRays) / seen.inverseDistance);
      }
    }
    progress.advance(end - begin);
  }, kTexelsPerBlock);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  g.lightsReached = std::move(reached);
  return g;
}

}  // namespace afterglow::baker
