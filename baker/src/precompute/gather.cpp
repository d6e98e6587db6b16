// The texels' gather rays (transport_precompute.h): cosine-distributed rays from every valid
// texel, recording what each ray reached, the sky it saw and how far it went, and the gather
// points that pool them.
//
// Bounced light is smooth away from other geometry, so a 2×2 block of texels on one surface
// shares one gather point and each of its texels casts a quarter of the rays (the four sets form
// one stratified set, and neighbouring blocks' sets one finer still: sampling::TiledSobol).
// Near other geometry bounced light changes within a texel or two: a texel there is a gather
// point of its own, with a full set of rays plus nearRays more that resolve its near field.
#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/gather.h"
#include "afterglow/core/stages.h"
#include "afterglow/core/parallel.h"
#include "precompute/burial.h"
#include "precompute/gather_batch.h"
#include "precompute/glass_sky.h"
#include "precompute/light_visibility.h"
#include "precompute/sight_lines.h"
#include "precompute/texel_lookup.h"
#include "shading/sampling.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::kShCount;

static_assert(TexelGather::kNoHit == kNoTexel, "texels without a gather point hold kNoTexel");

// What every step of the gather reads.
struct GatherInputs {
  const scenes::Scene& scene;
  const trace::RayTracer& tracer;
  const TexelSet& texels;
  const LinkOptions& options;
  Progress& progress;
  const GlassSky* glassSky;  // the sky through glass, estimated apart; null: by the rays
  // The albedo at close hits on textured surfaces (TexelGather::hitAlbedo), within
  // albedoReach(t) of texel t.
  bool albedoDetail() const { return options.albedoDetail > 0.0f; }
  float albedoReach(uint32_t t) const { return options.albedoDetail * texels.edge[t]; }
  uint32_t glassSamples() const { return uint32_t(std::max(0, options.glassSkySamples)); }
  // How texel t's rays through glass weigh against its points on glass (GlassSky): as its
  // `rays` first-pass rays, whichever of its passes cast them (any fixed count keeps the
  // weights a split of each direction, and the first pass's is the count most texels keep).
  GatherBatch::GlassWeights glassWeights(uint32_t t, uint32_t rays) const {
    return {texels.normal[t], rays, glassSamples()};
  }
};

// Lists items by key: key k's items are items[start[k] .. start[k + 1]), in index order; an
// item keyed kNoTexel is left out. (The blocks' texels, the adopted texels, the points' texels.)
void listByKey(const std::vector<uint32_t>& keyOf, uint32_t keys, std::vector<uint32_t>& start,
               std::vector<uint32_t>& items) {
  start.assign(size_t(keys) + 1, 0);
  for (const uint32_t k : keyOf)
    if (k != kNoTexel) ++start[k + 1];
  for (uint32_t k = 0; k < keys; ++k) start[k + 1] += start[k];
  items.resize(start[keys]);
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  for (uint32_t i = 0; i < uint32_t(keyOf.size()); ++i)
    if (keyOf[i] != kNoTexel) items[fill[keyOf[i]]++] = i;
}

// The valid texels in groups: 2×2 atlas blocks on one surface, or alone.
struct Groups {
  std::vector<uint32_t> of;             // per texel, its group (kNoTexel: invalid)
  std::vector<uint8_t> size;            // per group, its texels
  std::vector<uint32_t> start, texels;  // group g's texels: texels[start[g] .. start[g + 1])
  uint32_t count() const { return uint32_t(size.size()); }
};

// Groups the valid texels into 2×2 atlas blocks on one surface; texels near other geometry
// (TexelSet::nearGeometry) stay alone. Groups are numbered in atlas scan order.
Groups formBlocks(const TexelSet& texels) {
  Groups out;
  out.of.assign(texels.size(), kNoTexel);
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
          if (out.of[a] != kNoTexel) continue;
          const uint32_t g = out.count();
          out.of[a] = g;
          out.size.push_back(1);
          if (texels.nearGeometry[a]) continue;
          uint32_t in[4] = {a};
          int size = 1;
          for (int j = i + 1; j < count; ++j) {
            const uint32_t b = members[j];
            if (out.of[b] != kNoTexel || texels.nearGeometry[b]) continue;
            bool fits = true;
            for (int k = 0; k < size && fits; ++k) fits = sameSurface(texels, in[k], b);
            if (!fits) continue;
            out.of[b] = g;
            in[size++] = b;
          }
          out.size.back() = uint8_t(size);
        }
      }
  listByKey(out.of, out.count(), out.start, out.texels);
  return out;
}

// Rays of each texel of a group of `size`: the group casts `rays` in all (three share as four).
uint32_t raysPerMember(uint32_t rays, uint32_t size) {
  return std::max(1u, rays / (size == 3 ? 4u : std::max(1u, size)));
}

// The kinds of a texel's sets of rays (RaySets): the first pass of a full block's texels, whose
// four texels' points make one stratified set; any other texel's full set (its first pass or
// its top-up); the near set.
constexpr uint64_t kBlockSet = 0, kFullSet = 1, kNearSet = 2;

// The points of the texels' sets of rays. Neighbours casting the same kind of set take their
// points from one sequence (sampling::TiledSobol), so their errors cancel instead of adding up
// into blotches.
class RaySets {
 public:
  RaySets(const TexelSet& texels, const Groups& groups, uint32_t rays)
      : texels_(texels), groups_(groups), firstCount_(texels.size(), 0) {
    for (uint32_t t = 0; t < texels.size(); ++t)
      if (texels.valid[t]) firstCount_[t] = raysPerMember(rays, groups.size[groups.of[t]]);
  }

  // Texel t's rays in the first pass: its share of its group's.
  uint32_t firstCount(uint32_t t) const { return firstCount_[t]; }
  const std::vector<uint32_t>& firstCounts() const { return firstCount_; }

  // Texel t's points of one set of `n` rays, in the order they are traced
  // (sampling::coherentOrder).
  void setPoints(uint32_t t, uint32_t n, uint64_t set, std::vector<glm::vec2>& out) const {
    const sampling::TiledSobol sequence(
        sampling::Rng::itemSeed(sampling::Stream::TexelLinks, texels_.atlas[t]) ^
            sampling::mix64((set << 32) | n),
        texels_.pixel[t].x, texels_.pixel[t].y, n);
    out.resize(n);
    for (uint32_t s = 0; s < n; ++s) out[s] = sequence.point(s);
    sampling::coherentOrder(out);
  }

  // Texel t's first-pass samples, sample(s, u) for s = 0 .. firstCount(t) (a pure function of
  // the texel, so a ray can be cast again alike).
  template <class Sample>
  void firstSamples(uint32_t t, Sample&& sample) const {
    thread_local std::vector<glm::vec2> points;
    const bool quartered = groups_.size[groups_.of[t]] == 4;  // a full block
    setPoints(t, firstCount_[t], quartered ? kBlockSet : kFullSet, points);
    for (uint32_t s = 0; s < points.size(); ++s) sample(s, points[s]);
  }

 private:
  const TexelSet& texels_;
  const Groups& groups_;
  std::vector<uint32_t> firstCount_;
};

// What a texel's rays summed to, for its own decisions and its gather point's pooled values.
struct TexelRays {
  double sky[kShCount] = {};
  double inverseDistance = 0.0;
  uint32_t count = 0;
  void add(const double (&moreSky)[kShCount], double moreInverseDistance, uint32_t rays) {
    for (int k = 0; k < kShCount; ++k) sky[k] += moreSky[k];
    inverseDistance += moreInverseDistance;
    count += rays;
  }
};

// Per texel, the hit codes of one pass's rays and their albedo codes (empty without
// albedoDetail): texel t's are codes[start[t] .. start[t + 1]), as in TexelGather.
struct HitLists {
  std::vector<uint32_t> start, codes;
  std::vector<uint8_t> albedo;

  HitLists() = default;
  // Room for counts[t] rays of each texel t, every one a miss.
  HitLists(const std::vector<uint32_t>& counts, bool albedoDetail) : start(counts.size() + 1, 0) {
    for (size_t t = 0; t < counts.size(); ++t) start[t + 1] = start[t] + counts[t];
    codes.assign(start.back(), TexelGather::kNoHit);
    albedo.assign(albedoDetail ? codes.size() : 0, 0);
  }
  uint32_t count(uint32_t t) const { return start[t + 1] - start[t]; }

  // Takes texel t's codes from a traced batch, its rays from `firstRay` on.
  void take(const GatherInputs& in, GatherBatch& batch, uint32_t t, size_t firstRay) {
    const uint32_t n = count(t);
    std::copy_n(batch.codes().begin() + long(firstRay), n, codes.begin() + long(start[t]));
    if (in.albedoDetail())
      batch.albedoCodes(in.scene, in.tracer, firstRay, n, in.albedoReach(t), &albedo[start[t]]);
  }
};

// A texel whose rays a batch holds, from its ray firstRay on.
struct Queued {
  uint32_t texel, firstRay;
};

// Casts the texels' rays in parallel, over small blocks of texels (the work per texel varies
// tenfold: near texels cast many more rays, and they sit together, so a few big blocks would
// leave a thread idle at the end), several texels to a batch (Embree's coherent streams and
// the hit lookup's prefetching do better on a thousand rays than on one texel's).
// queue(t, batch) adds texel t's rays, false when it has none; read(batch, queued) reads a
// traced batch. With `progress`, it stops when cancelled and counts the texels done.
template <class Queue, class Read>
void castInBatches(const GatherInputs& in, const TexelLookup* lookup, Progress* progress,
                   Queue&& queue, Read&& read) {
  constexpr size_t kRaysPerBatch = 1024, kTexelsPerBlock = 512;
  parallelForBlocks(in.texels.size(), [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    batch.setGlassSky(in.glassSky);
    std::vector<Queued> queued;
    for (size_t t = begin; t < end && !(progress && progress->cancelled());) {
      batch.clear();
      queued.clear();
      for (; t < end && batch.size() < kRaysPerBatch; ++t) {
        const uint32_t firstRay = uint32_t(batch.size());
        if (queue(uint32_t(t), batch)) queued.push_back({uint32_t(t), firstRay});
      }
      if (queued.empty()) break;
      batch.trace(in.tracer, in.texels, lookup);
      read(batch, queued);
    }
    if (progress) progress->advance(end - begin);
  }, kTexelsPerBlock);
}

// The texels' lookup as they stand, its hits light-matched when the options say so.
TexelLookup lookupOf(const GatherInputs& in, const LightVisibility& lights,
                     const std::vector<uint32_t>& reached) {
  TexelLookup lookup(in.texels);
  if (in.options.lightMatch) lookup.setLights(&lights, &reached);
  return lookup;
}

// Whether texel t, its first-pass rays summed to `sum`, is buried: inside a wall, or wedged in
// a gap narrower than the texel (the floor under the rim of a box), where light changes within
// the texel's footprint, more than one value can hold. No links, no sky; the lightmap fills it
// from its neighbours. Burying loses only the little light that found its way into the gap,
// except where an emitter covers the texel (the ceiling above a double-sided lamp panel 1 cm
// below it, whose back glTF makes emit): there the cavity takes up a first-order share of the
// lamp's power, and passes some of it on through the gap, so the texel stays.
bool isBuried(const GatherInputs& in, uint32_t t, const GatherBatch::Summary& sum, uint32_t n) {
  return insideAWall(sum.backfaces, int(n), in.options) ||
         (wedgedInAGap(sum.close, int(n), in.options) && !litCavity(in.tracer, in.texels, t));
}

// What the first pass found per texel.
struct FirstPass {
  HitLists hits;
  std::vector<uint8_t> buried;  // inside a wall (see isBuried)
};

// The first pass: every valid texel its share of its group's rays. Texels found buried are
// only marked: hits read texels.valid, so changing it during the pass would race and depend on
// thread timing. False when cancelled.
bool castFirstPass(const GatherInputs& in, const RaySets& sets, const TexelLookup& lookup,
                   FirstPass& first, std::vector<TexelRays>& sums) {
  const TexelSet& texels = in.texels;
  first.hits = HitLists(sets.firstCounts(), in.albedoDetail());
  first.buried.assign(texels.size(), 0);
  in.progress.begin(stageName(Stage::Gather), texels.size());
  castInBatches(
      in, &lookup, &in.progress,
      [&](uint32_t t, GatherBatch& batch) {
        if (!texels.valid[t]) return false;
        const sampling::Frame frame(texels.normal[t]);
        sets.firstSamples(t, [&](uint32_t, glm::vec2 u) {
          batch.add(texels.position[t], frame, texels.geometricNormal[t], u);
        });
        return true;
      },
      [&](GatherBatch& batch, const std::vector<Queued>& queued) {
        for (const auto& [t, firstRay] : queued) {
          const uint32_t n = sets.firstCount(t);
          const GatherBatch::GlassWeights glass = in.glassWeights(t, n);
          const GatherBatch::Summary sum = batch.summarize(in.tracer, firstRay, firstRay + n,
                                                           texels.edge[t], &glass);
          if (isBuried(in, t, sum, n)) {
            first.buried[t] = 1;
            continue;
          }
          first.hits.take(in, batch, t, firstRay);
          sums[t].add(sum.sky, sum.inverseDistance, n);
        }
      });
  in.progress.end();
  return !in.progress.cancelled();
}

// Buried texels leave now, so that the rays below, and the first-pass rays that landed on one
// (cast again in recastBuriedHits), find the texels that stay: a hit on a buried texel's
// surface takes the light of a neighbour the hit point sees (TexelLookup, TexelOfHit), never of
// one behind a wall (a roof that cuts through a cornice: the cornice's texel across the roof's
// joint is buried, and its neighbour above the roof is in the sun). Whether any was.
bool buryTexels(TexelSet& texels, const std::vector<uint8_t>& buried) {
  bool anyBuried = false;
  for (uint32_t t = 0; t < texels.size(); ++t)
    if (buried[t]) texels.valid[t] = 0, anyBuried = true;
  return anyBuried;
}

// Per texel, what the first pass made of it.
struct Roles {
  uint32_t nearRays = 0;           // LinkOptions::nearRays: a near texel's near set
  std::vector<uint8_t> alone;      // a gather point of its own
  std::vector<uint8_t> nearTexel;  // ... that casts nearRays more for its near field
  std::vector<uint8_t> keepFirst;  // its first-pass rays count
};

// Where other geometry is close (harmonic distance under blockDistance texel edges) bounced
// light changes too fast to share: such a texel leaves its block for a gather point of its
// own with a full set of rays. Nearer still (under nearDistance edges) it casts nearRays more
// for its near field.
Roles chooseRoles(const GatherInputs& in, const std::vector<uint8_t>& buried,
                  const std::vector<TexelRays>& sums) {
  const TexelSet& texels = in.texels;
  const uint32_t count = texels.size();
  Roles out;
  out.nearRays = uint32_t(std::max(0, in.options.nearRays));
  out.alone.assign(count, 0);
  out.nearTexel.assign(count, 0);
  out.keepFirst.assign(count, 0);
  for (uint32_t t = 0; t < count; ++t) {
    if (!texels.valid[t] || buried[t]) continue;
    out.keepFirst[t] = 1;
    // harmonic distance < k edges  <=>  count < inverseDistance × k × edge
    const double reach = sums[t].inverseDistance * double(texels.edge[t]);
    out.nearTexel[t] =
        out.nearRays > 0 && double(sums[t].count) < reach * double(in.options.nearDistance);
    out.alone[t] =
        out.nearTexel[t] || double(sums[t].count) < reach * double(in.options.blockDistance);
  }
  return out;
}

// The rays that made a texel leave its block, or cast near rays, are not a fair sample of its
// light (chosen for having met geometry close by, they would overstate the near field): such a
// texel keeps its first rays for nothing else, and casts a fresh full set instead.
void dropLeaversFirstRays(const Groups& groups, Roles& roles, std::vector<TexelRays>& sums) {
  for (uint32_t t = 0; t < uint32_t(sums.size()); ++t)
    if (roles.nearTexel[t] || (roles.alone[t] && groups.size[groups.of[t]] > 1)) {
      roles.keepFirst[t] = 0;
      sums[t] = TexelRays();
    }
}

// The second pass's rays per texel, in the order its hits are kept: a fresh full set (its
// top-up), the points of the texels it adopted (their share of their block's set), then its
// near set.
struct SecondPass {
  std::vector<uint32_t> topUp;
  // The texels whose quarters texel t casts: adopted[adoptStart[t] .. adoptStart[t + 1]).
  std::vector<uint32_t> adoptStart, adopted;
  HitLists hits;
};

// Plans the second pass. A texel alone tops its rays up to a full set. In a full block, the
// first staying texel adopts the leavers (and the buried texels): it casts their quarters of
// the block's set, so the block's rays still cover every quarter.
SecondPass planSecondPass(const GatherInputs& in, const Groups& groups, const RaySets& sets,
                          const Roles& roles, const std::vector<uint8_t>& buried, uint32_t rays) {
  const uint32_t count = in.texels.size();
  SecondPass out;
  std::vector<uint32_t> adopter(count, kNoTexel);
  for (uint32_t g = 0; g < groups.count(); ++g) {
    if (groups.size[g] != 4) continue;
    uint32_t stay = kNoTexel;
    for (uint32_t k = groups.start[g]; k < groups.start[g + 1] && stay == kNoTexel; ++k) {
      const uint32_t t = groups.texels[k];
      if (roles.keepFirst[t] && !roles.alone[t]) stay = t;
    }
    for (uint32_t k = groups.start[g]; k < groups.start[g + 1]; ++k) {
      const uint32_t t = groups.texels[k];
      if ((roles.alone[t] || buried[t]) && stay != kNoTexel) adopter[t] = stay;
    }
  }
  listByKey(adopter, count, out.adoptStart, out.adopted);
  out.topUp.assign(count, 0);
  std::vector<uint32_t> extra(count, 0);
  for (uint32_t t = 0; t < count; ++t) {
    if (roles.alone[t])
      out.topUp[t] = rays - std::min(rays, roles.keepFirst[t] ? sets.firstCount(t) : 0u);
    extra[t] = out.topUp[t] + (roles.nearTexel[t] ? roles.nearRays : 0);
    for (uint32_t k = out.adoptStart[t]; k < out.adoptStart[t + 1]; ++k)
      extra[t] += sets.firstCount(out.adopted[k]);
  }
  out.hits = HitLists(extra, in.albedoDetail());
  return out;
}

// The second pass: the rays planned, against the texels that stay (`settled`). False when
// cancelled.
bool castSecondPass(const GatherInputs& in, const RaySets& sets, const TexelLookup& settled,
                    const Roles& roles, SecondPass& second, std::vector<TexelRays>& sums) {
  const TexelSet& texels = in.texels;
  in.progress.begin(stageStep(Stage::Gather, "near geometry"), texels.size());
  castInBatches(
      in, &settled, &in.progress,
      [&](uint32_t t, GatherBatch& batch) {
        if (second.hits.count(t) == 0) return false;
        const sampling::Frame frame(texels.normal[t]);
        auto cast = [&](uint32_t from, uint32_t n, uint64_t set) {
          thread_local std::vector<glm::vec2> points;
          sets.setPoints(from, n, set, points);
          for (const glm::vec2 u : points)
            batch.add(texels.position[t], frame, texels.geometricNormal[t], u);
        };
        cast(t, second.topUp[t], kFullSet);
        for (uint32_t k = second.adoptStart[t]; k < second.adoptStart[t + 1]; ++k)
          cast(second.adopted[k], sets.firstCount(second.adopted[k]), kBlockSet);
        cast(t, roles.nearTexel[t] ? roles.nearRays : 0u, kNearSet);
        return true;
      },
      [&](GatherBatch& batch, const std::vector<Queued>& queued) {
        for (const auto& [t, firstRay] : queued) {
          const uint32_t n = second.hits.count(t);
          const GatherBatch::GlassWeights glass = in.glassWeights(t, sets.firstCount(t));
          const GatherBatch::Summary sum =
              batch.summarize(in.tracer, firstRay, firstRay + n, 0.0f, &glass);
          second.hits.take(in, batch, t, firstRay);
          sums[t].add(sum.sky, sum.inverseDistance, n);
        }
      });
  in.progress.end();
  return !in.progress.cancelled();
}

// The glass samples' share of the sky each texel sees through glass (GlassSky), added to its
// rays' sky as each of its rays would have brought it (the rays brought the rest). False when
// cancelled.
constexpr double kY00 = 0.28209479177387814;  // the SH basis's constant term

bool addGlassSky(const GatherInputs& in, const RaySets& sets, std::vector<TexelRays>& sums) {
  const TexelSet& texels = in.texels;
  in.progress.begin(stageStep(Stage::Gather, "sky through glass"), texels.size());
  parallelForBlocks(texels.size(), [&](size_t begin, size_t end, int) {
    for (size_t t = begin; t < end && !in.progress.cancelled(); ++t) {
      if (sums[t].count == 0) continue;
      double sky[kShCount] = {};
      // The sky its rays saw, as a share of a white sky's: the open sky, and the rays' share
      // of the sky through glass.
      const float open = float(sums[t].sky[0] / (double(sums[t].count) * kY00));
      in.glassSky->addTo(in.tracer, texels.position[t], texels.normal[t],
                         texels.geometricNormal[t], t, in.glassSamples(),
                         sets.firstCount(uint32_t(t)), open, sky);
      for (int i = 0; i < kShCount; ++i) sums[t].sky[i] += double(sums[t].count) * sky[i];
    }
    in.progress.advance(end - begin);
  }, 256);
  in.progress.end();
  return !in.progress.cancelled();
}

// Gather points: the blocks without the texels that left them, numbered in the blocks' order,
// each leaver a point of its own.
void formGatherPoints(const TexelSet& texels, const Groups& groups, const Roles& roles,
                      const std::vector<uint8_t>& buried, TexelGather& g) {
  std::vector<uint32_t> pointOfGroup(groups.count(), kNoTexel);
  g.pointOfTexel.assign(texels.size(), TexelGather::kNoHit);
  uint32_t points = 0;
  for (uint32_t group = 0; group < groups.count(); ++group)
    for (uint32_t k = groups.start[group]; k < groups.start[group + 1]; ++k) {
      const uint32_t t = groups.texels[k];
      if (!texels.valid[t] || buried[t]) continue;
      if (roles.alone[t]) {
        g.pointOfTexel[t] = points++;
      } else {
        if (pointOfGroup[group] == kNoTexel) pointOfGroup[group] = points++;
        g.pointOfTexel[t] = pointOfGroup[group];
      }
    }
  listByKey(g.pointOfTexel, points, g.pointStart, g.pointTexels);
}

// The pooled sky and distance of each gather point (over all its rays), for its texels.
void poolGatherPoints(const std::vector<TexelRays>& sums, TexelGather& g) {
  const size_t count = sums.size();
  g.sky.assign(count * kShCount, 0.0f);
  g.harmonicDistance.assign(count, std::numeric_limits<float>::infinity());
  for (uint32_t p = 0; p < g.points(); ++p) {
    TexelRays pooled;
    for (uint32_t k = g.pointStart[p]; k < g.pointStart[p + 1]; ++k) {
      const TexelRays& s = sums[g.pointTexels[k]];
      pooled.add(s.sky, s.inverseDistance, s.count);
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
}

// The kept first-pass rays that landed on a buried texel, cast again (the same rays:
// RaySets::firstSamples) and resolved against the texels that stay.
void recastBuriedHits(const GatherInputs& in, const RaySets& sets, const TexelLookup& settled,
                      const Roles& roles, FirstPass& first) {
  const TexelSet& texels = in.texels;
  HitLists& hits = first.hits;
  auto onBuried = [&](uint32_t code) {
    return code != TexelGather::kNoHit && first.buried[code & TexelGather::kTexelMask];
  };
  castInBatches(
      in, &settled, nullptr,
      [&](uint32_t t, GatherBatch& batch) {
        if (!roles.keepFirst[t]) return false;
        const uint32_t* codes = hits.codes.data() + hits.start[t];
        if (std::none_of(codes, codes + hits.count(t), onBuried)) return false;
        const sampling::Frame frame(texels.normal[t]);
        sets.firstSamples(t, [&](uint32_t s, glm::vec2 u) {
          if (onBuried(codes[s]))
            batch.add(texels.position[t], frame, texels.geometricNormal[t], u);
        });
        return true;
      },
      [&](GatherBatch& batch, const std::vector<Queued>& queued) {
        size_t k = 0;  // the batch's ray
        for (const Queued& q : queued)
          for (uint32_t at = hits.start[q.texel]; at < hits.start[q.texel + 1]; ++at) {
            if (!onBuried(hits.codes[at])) continue;
            hits.codes[at] = batch.codes()[k];
            if (in.albedoDetail()) {
              const float reach = in.albedoReach(q.texel);
              batch.albedoCodes(in.scene, in.tracer, k, 1, reach, &hits.albedo[at]);
            }
            ++k;
          }
      });
}

// Every texel's rays in one list: its first pass (unless it left a full block), then its
// top-up, adopted and near sets; all but the near set are full sets. A near texel's hits beyond
// its near field are flagged kFar. The passes' lists are moved in and freed when done.
void joinHits(const GatherInputs& in, const Roles& roles, const std::vector<uint8_t>& buried,
              HitLists first, HitLists second, TexelGather& g) {
  const TexelSet& texels = in.texels;
  const uint32_t count = texels.size();
  g.hitStart.assign(size_t(count) + 1, 0);
  g.fullRays.assign(count, 0);
  for (uint32_t t = 0; t < count; ++t) {
    const uint32_t kept = roles.keepFirst[t] ? first.count(t) : 0;
    const uint32_t extra = second.count(t);
    const bool valid = texels.valid[t] && !buried[t];
    g.hitStart[t + 1] = g.hitStart[t] + (valid ? kept + extra : 0);
    if (valid) g.fullRays[t] = uint16_t(kept + extra - (roles.nearTexel[t] ? roles.nearRays : 0));
  }
  g.hits.resize(g.hitStart[count]);
  g.hitAlbedo.assign(in.albedoDetail() ? g.hits.size() : 0, 0);
  parallelFor(count, [&](size_t i) {
    const uint32_t t = uint32_t(i);
    if (g.hitStart[t + 1] == g.hitStart[t]) return;
    uint32_t* out = &g.hits[g.hitStart[t]];
    const uint32_t kept = roles.keepFirst[t] ? first.count(t) : 0;
    std::copy_n(first.codes.begin() + long(first.start[t]), kept, out);
    std::copy_n(second.codes.begin() + long(second.start[t]), second.count(t), out + kept);
    if (in.albedoDetail()) {
      uint8_t* albedo = &g.hitAlbedo[g.hitStart[t]];
      std::copy_n(first.albedo.begin() + long(first.start[t]), kept, albedo);
      std::copy_n(second.albedo.begin() + long(second.start[t]), second.count(t), albedo + kept);
    }
    if (roles.nearTexel[t])
      for (uint32_t k = 0; k < g.hitStart[t + 1] - g.hitStart[t]; ++k)
        out[k] = nearFieldCode(texels, in.options.nearField, t, out[k]);
  });
}

// The backs some ray reached, and how far their own rays go (for their clusters). False when
// cancelled.
bool castBackRays(const GatherInputs& in, uint32_t rays, TexelGather& g) {
  const TexelSet& texels = in.texels;
  g.backSeen.assign(texels.size(), 0);
  g.backHarmonicDistance.assign(texels.size(), std::numeric_limits<float>::infinity());
  for (uint32_t code : g.hits)
    if (code != TexelGather::kNoHit && (code & TexelGather::kBackSide))
      g.backSeen[code & TexelGather::kTexelMask] = 1;
  const uint32_t backRays = std::max(4u, rays / 8);
  const sampling::Stratified strata(backRays);
  in.progress.begin(stageStep(Stage::Gather, "backs"), texels.size());
  castInBatches(
      in, nullptr, &in.progress,
      [&](uint32_t t, GatherBatch& back) {
        if (!g.backSeen[t] || !texels.valid[t]) return false;
        const sampling::Frame frame(-texels.normal[t]);
        const sampling::Rng::ItemSeed seed{
            sampling::Rng::itemSeed(sampling::Stream::BackDistance, t)};
        for (uint32_t s = 0; s < backRays; ++s) {
          sampling::Rng rng(seed, s);
          back.add(texels.backPosition(t), frame, -texels.geometricNormal[t], strata.point(rng, s));
        }
        return true;
      },
      [&](GatherBatch& back, const std::vector<Queued>& queued) {
        for (const auto& [t, firstRay] : queued) {
          const GatherBatch::Summary seen =
              back.summarize(in.tracer, firstRay, firstRay + backRays);
          if (seen.inverseDistance > 0.0)
            g.backHarmonicDistance[t] = float(double(backRays) / seen.inverseDistance);
        }
      });
  in.progress.end();
  return !in.progress.cancelled();
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
  const uint32_t rays = uint32_t(options.texelRays);
  GlassSky glass;
  if (options.glassSkySamples > 0 && tracer.hasGlass()) glass = GlassSky(scene);
  const GatherInputs in{scene, tracer, texels, options, progress,
                        glass.empty() ? nullptr : &glass};
  const Groups groups = formBlocks(texels);
  const RaySets sets(texels, groups, rays);
  // The lights each texel's sample sees, for the close hits' check (TexelOfHit's light match).
  const LightVisibility lights(scene);
  std::vector<uint32_t> reached =
      options.lightMatch ? lights.texels(tracer, texels) : std::vector<uint32_t>();

  std::vector<TexelRays> sums(count);
  FirstPass first;
  if (!castFirstPass(in, sets, lookupOf(in, lights, reached), first, sums))
    return Status::error("cancelled");
  const bool anyBuried = buryTexels(texels, first.buried);
  const TexelLookup settled = lookupOf(in, lights, reached);
  Roles roles = chooseRoles(in, first.buried, sums);
  dropLeaversFirstRays(groups, roles, sums);
  SecondPass second = planSecondPass(in, groups, sets, roles, first.buried, rays);
  if (!castSecondPass(in, sets, settled, roles, second, sums)) return Status::error("cancelled");
  if (in.glassSky && !addGlassSky(in, sets, sums)) return Status::error("cancelled");

  TexelGather g;
  g.raysPerTexel = rays;
  formGatherPoints(texels, groups, roles, first.buried, g);
  poolGatherPoints(sums, g);
  if (anyBuried) recastBuriedHits(in, sets, settled, roles, first);
  joinHits(in, roles, first.buried, std::move(first.hits), std::move(second.hits), g);
  if (!castBackRays(in, rays, g)) return Status::error("cancelled");
  g.lightsReached = std::move(reached);
  return g;
}

}  // namespace afterglow::baker
