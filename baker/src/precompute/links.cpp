// Stage 3 of the precompute: form factors gather point -> cluster and back-side cluster ->
// cluster, how clusters and texels read the gather points, and sky transfer, from the texels'
// gather rays (and the back-side clusters' own rays).
#include <algorithm>
#include <limits>
#include <memory>
#include <mutex>
#include <cmath>
#include <utility>
#include <vector>

#include "afterglow/baker/clusters.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/links.h"
#include "afterglow/core/stages.h"
#include "afterglow/core/parallel.h"
#include "afterglow/scenes/material_eval.h"
#include "precompute/far_targets.h"
#include "precompute/gather_batch.h"
#include "precompute/sight_lines.h"
#include "precompute/texel_lookup.h"
#include "shading/sampling.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::kShCount;

struct Link {
  uint32_t cluster;
  float weight;
};

// Leaves out a row's links below minWeight; the dropped weight goes to the kept ones in
// proportion, so the row keeps its sum (its energy) and the dropped light is stood in for by
// the row's own average.
void dropWeakLinks(float minWeight, std::vector<Link>& row) {
  if (!(minWeight > 0.0f)) return;
  double total = 0.0, kept = 0.0;
  size_t out = 0;
  for (const Link& l : row) {
    total += l.weight;
    if (l.weight < minWeight) continue;
    kept += l.weight;
    row[out++] = l;
  }
  row.resize(out);
  if (kept > 0.0 && kept < total)
    for (Link& l : row) l.weight = float(double(l.weight) * total / kept);
}

// Sums a row's weights per target cluster in a dense array (one per block of rows: a row of a
// big cluster gathers tens of thousands of rays), then emits the targets in ascending order,
// leaving out links below minWeight. The targets touched are kept as bits, one per cluster, and
// read back in order a 64-bit word at a time, visiting only the words touched (a short list to
// sort): cheaper than sorting every target (a row touches a few hundred of ten thousand
// clusters), and independent of how many clusters the level has.
class RowBuilder {
 public:
  explicit RowBuilder(uint32_t clusters)
      : sum_(clusters, 0.0), touched_((size_t(clusters) + 63) / 64, 0),
        words_(touched_.size() + 1) {}  // + 1: add() writes one past the words counted

  void add(uint32_t cluster, double weight) {
    // The word's index is always written and only counted when the word was empty: no branch
    // (whether a hit is a row's first on its word is a coin toss).
    uint64_t& word = touched_[cluster >> 6];
    words_[wordCount_] = cluster >> 6;
    wordCount_ += word == 0 ? 1 : 0;
    word |= uint64_t(1) << (cluster & 63);
    sum_[cluster] += weight;
  }

  void finish(float minWeight, std::vector<Link>& row) {
    row.clear();
    std::sort(words_.begin(), words_.begin() + wordCount_);
    for (size_t i = 0; i < wordCount_; ++i) {
      const uint32_t w = words_[i];
      for (uint64_t bits = touched_[w]; bits != 0; bits &= bits - 1) {
        const uint32_t c = w * 64 + uint32_t(__builtin_ctzll(bits));
        row.push_back({c, float(sum_[c])});
        sum_[c] = 0.0;
      }
      touched_[w] = 0;
    }
    wordCount_ = 0;
    dropWeakLinks(minWeight, row);
  }

 private:
  std::vector<double> sum_;
  std::vector<uint64_t> touched_;  // bit c of word c / 64: cluster c was added to
  std::vector<uint32_t> words_;    // the first wordCount_: the words of touched_ not zero
  size_t wordCount_ = 0;
};

// Builds a sparse matrix row by row in parallel: fill(row, state, links) writes a row's links
// sorted by cluster, with per-thread scratch `state` from makeState() (a dense array over the
// targets: made once a thread, not once a block; fill leaves it as it found it); each block of rows
// collects its own, and the blocks are joined in row order (so the result does not depend on
// the thread count, nor the memory on hundreds of thousands of small vectors).
template <class MakeState, class Fill>
void buildRows(size_t rows, uint32_t targets, Progress& progress, MakeState&& makeState,
               Fill&& fill, runtime::SparseLinks& out, size_t grain) {
  // A block's rows, already quantised (SparseLinks of its own, joined below).
  struct Block {
    size_t begin = 0;
    runtime::SparseLinks links;
  };
  std::vector<Block> blocks;
  std::mutex mutex;
  using State = decltype(makeState());
  std::vector<std::unique_ptr<State>> states(size_t(std::max(1, threadCount())));
  parallelForBlocks(rows, [&](size_t begin, size_t end, int thread) {
    Block block;
    block.begin = begin;
    block.links = runtime::SparseLinks(targets);
    block.links.rowScale.reserve(end - begin);
    std::unique_ptr<State>& state = states[size_t(thread)];
    if (!state) state = std::make_unique<State>(makeState());
    std::vector<Link> row;
    std::vector<uint32_t> columns;
    std::vector<float> weights;
    for (size_t r = begin; r < end; ++r) {
      row.clear();
      if (!progress.cancelled()) fill(r, *state, row);
      columns.clear();
      weights.clear();
      for (const Link& l : row) {
        columns.push_back(l.cluster);
        weights.push_back(l.weight);
      }
      block.links.appendRow(columns.data(), weights.data(), row.size());
    }
    progress.advance(end - begin);
    std::lock_guard<std::mutex> lock(mutex);
    blocks.push_back(std::move(block));
  }, grain);
  std::sort(blocks.begin(), blocks.end(),
            [](const Block& a, const Block& b) { return a.begin < b.begin; });
  out = runtime::SparseLinks(targets);
  size_t total = 0;
  for (const Block& b : blocks) total += b.links.size();
  out.rowStart.reserve(rows + 1);
  out.rowScale.reserve(rows);
  out.link.reserve(total);
  for (Block& b : blocks) {
    const uint32_t base = uint32_t(out.link.size());
    out.link.insert(out.link.end(), b.links.link.begin(), b.links.link.end());
    out.rowScale.insert(out.rowScale.end(), b.links.rowScale.begin(), b.links.rowScale.end());
    for (size_t r = 1; r < b.links.rowStart.size(); ++r)
      out.rowStart.push_back(base + b.links.rowStart[r]);
    b.links = runtime::SparseLinks();
  }
}

// The material's albedo with every texture read as 1 (baker::diffuseAlbedoFactor, the same
// formula as baker::diffuseAlbedo). A cluster's albedo is this factor × its texture ratio
// (its mean textured albedo / this factor), so setAlbedo on a material scales its textured
// clusters by the same ratios.
glm::vec3 albedoFactor(const scenes::Material& m) { return diffuseAlbedoFactor(m); }

glm::vec3 safeRatio(glm::vec3 value, glm::vec3 factor) {
  glm::vec3 r(1.0f);
  for (int i = 0; i < 3; ++i)
    if (factor[i] > 0.0f) r[i] = value[i] / factor[i];
  return r;
}

// Materials and the per-cluster texture modulation the Solver reads. A cluster whose material
// index is outside Scene::materials (the glTF default material) gets an appended entry.
void fillMaterials(const scenes::Scene& scene, const Clusters& clusters,
                   runtime::TransportData& transport) {
  transport.materials.clear();
  for (const scenes::Material& m : scene.materials)
    transport.materials.push_back({m.name, albedoFactor(m), m.emission()});
  const uint32_t defaultIndex = uint32_t(scene.materials.size());
  bool needDefault = false;
  const uint32_t n = clusters.size();
  transport.clusterMaterial.resize(n);
  transport.clusterAlbedoTexture.resize(n);
  transport.clusterEmissionTexture.resize(n);
  for (uint32_t c = 0; c < n; ++c) {
    uint32_t mi = clusters.material[c];
    if (mi >= defaultIndex) mi = defaultIndex, needDefault = true;
    const scenes::Material& m = scene.material(mi == defaultIndex ? -1 : int(mi));
    transport.clusterMaterial[c] = mi;
    transport.clusterAlbedoTexture[c] = safeRatio(clusters.albedo[c], albedoFactor(m));
    transport.clusterEmissionTexture[c] = safeRatio(clusters.emission[c], m.emission());
  }
  if (needDefault) {
    const scenes::Material& m = scene.material(-1);
    transport.materials.push_back({"default", albedoFactor(m), m.emission()});
  }
}

// The lifted sight line between the samples of texels a and b on one surface, traced from the
// lower index so that it is symmetric.
bool sightLine(const TexelSet& texels, uint32_t a, uint32_t b, trace::Ray& sight) {
  const uint32_t from = std::min(a, b), to = std::max(a, b);
  return liftedSightLine(texels.position[from], texels.normal[from], texels.position[to],
                         texels.normal[to], sight);
}

// Marks, per texel, the atlas neighbours whose bounced light may smooth its own: valid, same
// instance, same plane (normals within 30°, no step between them), closer than filterReach ×
// the harmonic ray distance of both, and in sight of each other (a wall standing on the floor
// between two texels must not let the lit one brighten the one under the box). The test is
// symmetric (the sight line runs from the lower texel index), so the marks are too: bit k for
// the neighbour at runtime::kNeighbourOffsets[k].
std::vector<uint8_t> markFilterNeighbours(const trace::RayTracer& tracer, const TexelSet& texels,
                                          const TexelGather& gather, const LinkOptions& options) {
  std::vector<uint8_t> marks(texels.size(), 0);
  const float cosMaxAngle = std::cos(glm::radians(options.filterMaxAngleDeg));
  // Whether a and b may smooth each other: kNo, kYes, or kInSight when the sight line `sight`
  // between them is clear.
  enum Compatible { kNo, kYes, kInSight };
  auto compatible = [&](uint32_t a, uint32_t b, trace::Ray& sight) {
    if (!texels.valid[b] || !sameSurface(texels, a, b)) return kNo;
    if (glm::dot(texels.normal[a], texels.normal[b]) < cosMaxAngle) return kNo;
    const float distance = glm::length(texels.position[b] - texels.position[a]);
    const float reach = options.filterReach *
                        std::min(gather.harmonicDistance[a], gather.harmonicDistance[b]);
    if (!(distance < reach)) return kNo;
    return sightLine(texels, a, b, sight) ? kInSight : kYes;
  };
  // A block's sight lines are traced together (a coherent stream, RayTracer::occluded).
  parallelForBlocks(texels.size(), [&](size_t begin, size_t end, int) {
    std::vector<trace::Ray> sights;
    std::vector<std::pair<uint32_t, uint8_t>> markOf;  // per sight line: texel, its bit
    sights.reserve((end - begin) * 8);
    markOf.reserve((end - begin) * 8);
    for (size_t i = begin; i < end; ++i) {
      const uint32_t t = uint32_t(i);
      if (!texels.valid[t]) continue;
      const runtime::AtlasLayout& layout = texels.atlases[texels.atlas[t]];
      for (int k = 0; k < 8; ++k) {
        const int x = texels.pixel[t].x + runtime::kNeighbourOffsets[k][0];
        const int y = texels.pixel[t].y + runtime::kNeighbourOffsets[k][1];
        if (x < 0 || y < 0 || x >= layout.width || y >= layout.height) continue;
        const uint32_t n = layout.texelOfPixel[size_t(y) * size_t(layout.width) + size_t(x)];
        if (n == kNoTexel) continue;
        trace::Ray sight;
        const Compatible c = compatible(t, n, sight);
        if (c == kYes) marks[t] |= uint8_t(1u << k);
        if (c != kInSight) continue;
        sights.push_back(sight);
        markOf.push_back({t, uint8_t(1u << k)});
      }
    }
    std::unique_ptr<bool[]> blocked(new bool[sights.size()]);
    tracer.occluded(sights.data(), blocked.get(), sights.size());
    for (size_t j = 0; j < sights.size(); ++j)
      if (!blocked[j]) marks[markOf[j].first] |= markOf[j].second;
  }, 1024);
  return marks;
}

// Gather point p's first texel, and whether it is its only one (a point of a texel near other
// geometry, not of a 2×2 block).
uint32_t firstTexelOf(const TexelGather& gather, uint32_t p) {
  return gather.pointTexels[gather.pointStart[p]];
}
bool lonePoint(const TexelGather& gather, uint32_t p) {
  return gather.pointStart[p + 1] - gather.pointStart[p] == 1;
}

// Two points may share a far field when their far hits receive alike light in every channel
// (LinkOptions::sharedFarLightRatio); farLight per point and channel (farLightOfPoints), empty:
// no check.
class FarLitAlike {
 public:
  FarLitAlike(const std::vector<float>& farLight, const ClusterLight& light, float ratio)
      : farLight_(farLight), light_(light), ratio_(ratio) {}
  bool operator()(uint32_t a, uint32_t b) const {
    if (farLight_.empty()) return true;
    const size_t channels = light_.channels.size();
    for (size_t ch = 0; ch < channels; ++ch) {
      const float x = farLight_[a * channels + ch], y = farLight_[b * channels + ch];
      if (std::max(x, y) > ratio_ * std::min(x, y) + kSharedFloor * light_.floors[ch])
        return false;
    }
    return true;
  }

 private:
  // A fifth of ClusterLight's floor (a hundredth of the channel's mean): a point whose far hits
  // are all in shade must not take a far field with some sun in it. Between shaded far fields
  // the difference is their bounced light, which this check cannot see, and on Sponza-sun at 8
  // texels/m a point under a ledge took its neighbours' far field, 20 times its own.
  static constexpr float kSharedFloor = 0.2f;
  const std::vector<float>& farLight_;
  const ClusterLight& light_;
  float ratio_;
};

// Gather points that share a far field (LinkOptions::sharedFarSpan): points of one kind (of one
// texel, or 2×2 blocks: a texel near other geometry sees a far field unlike its block
// neighbours') in one span × span square of an atlas, on one surface and in sight of each
// other. In rounds: in every square the first point without a group anchors one, and the
// square's other points without one join it when they share its surface and see it (the sight
// lines of a round traced together); the rest try again next round. Per point its group,
// numbered in the order of their anchors, or kNoTexel for a point alone in its group (its row
// keeps its far links: sharing would only add one). Deterministic: the rounds do not depend on
// threads.
struct FarGroups {
  std::vector<uint32_t> ofPoint;
  std::vector<uint32_t> start{0};  // group g's points: points[start[g] .. start[g+1])
  std::vector<uint32_t> points;
  uint32_t size() const { return uint32_t(start.size() - 1); }
};

// (square, point) for every point (its first texel's square), sorted: each square's points in
// a run.
std::vector<std::pair<uint64_t, uint32_t>> pointsBySquare(const TexelSet& texels,
                                                          const TexelGather& gather, int span) {
  std::vector<std::pair<uint64_t, uint32_t>> order;
  for (uint32_t p = 0; p < gather.points(); ++p) {
    const uint32_t t = firstTexelOf(gather, p);
    const runtime::AtlasLayout& layout = texels.atlases[texels.atlas[t]];
    const uint64_t columns = uint64_t(layout.width + span - 1) / uint64_t(span);
    const uint64_t square = uint64_t(texels.pixel[t].y / span) * columns +
                            uint64_t(texels.pixel[t].x / span);
    order.push_back({(uint64_t(texels.atlas[t]) << 40) | square, p});
  }
  std::sort(order.begin(), order.end());
  return order;
}

// The rounds of shareFarFields over the points in square order: per point, its group's anchor
// point (kNoTexel: none).
std::vector<uint32_t> anchorPoints(const trace::RayTracer& tracer, const TexelSet& texels,
                                   const TexelGather& gather,
                                   const std::vector<std::pair<uint64_t, uint32_t>>& order,
                                   const FarLitAlike& alike) {
  auto firstTexel = [&](uint32_t p) { return firstTexelOf(gather, p); };
  std::vector<uint32_t> anchor(gather.points(), kNoTexel);
  std::vector<trace::Ray> sights;
  std::vector<std::pair<uint32_t, uint32_t>> joins;  // per sight line: point, anchor
  for (bool open = true; open;) {
    open = false;
    sights.clear();
    joins.clear();
    for (size_t i = 0, j; i < order.size(); i = j) {
      for (j = i + 1; j < order.size() && order[j].first == order[i].first;) ++j;
      uint32_t a = kNoTexel;
      for (size_t k = i; k < j; ++k) {
        const uint32_t p = order[k].second;
        if (anchor[p] != kNoTexel) continue;
        if (a == kNoTexel) {
          anchor[p] = a = p;
          open = true;
          continue;
        }
        if (lonePoint(gather, a) != lonePoint(gather, p) ||
            !sameSurface(texels, firstTexel(a), firstTexel(p)) || !alike(a, p))
          continue;
        if (!sightLine(texels, firstTexel(a), firstTexel(p), sights.emplace_back())) {
          sights.pop_back();
          anchor[p] = a;
          continue;
        }
        joins.push_back({p, a});
      }
    }
    std::unique_ptr<bool[]> blocked(new bool[sights.size()]);
    tracer.occluded(sights.data(), blocked.get(), sights.size());
    for (size_t k = 0; k < joins.size(); ++k)
      if (!blocked[k]) anchor[joins[k].first] = joins[k].second;
  }
  return anchor;
}

FarGroups shareFarFields(const trace::RayTracer& tracer, const TexelSet& texels,
                         const TexelGather& gather, int span, const FarLitAlike& alike) {
  const uint32_t points = gather.points();
  FarGroups out;
  out.ofPoint.assign(points, kNoTexel);
  if (span <= 1) return out;
  const std::vector<uint32_t> anchor =
      anchorPoints(tracer, texels, gather, pointsBySquare(texels, gather, span), alike);
  // The groups of more than one point, numbered in their anchors' order.
  std::vector<uint32_t> members(points, 0);
  for (uint32_t p = 0; p < points; ++p)
    if (anchor[p] != kNoTexel) ++members[anchor[p]];
  std::vector<uint32_t> groupOfAnchor(points, kNoTexel);
  for (uint32_t p = 0; p < points; ++p)
    if (anchor[p] == p && members[p] > 1) {
      groupOfAnchor[p] = out.size();
      out.start.push_back(out.start.back() + members[p]);
    }
  out.points.resize(out.start.back());
  std::vector<uint32_t> fill(out.start.begin(), out.start.end() - 1);
  for (uint32_t p = 0; p < points; ++p) {
    if (anchor[p] == kNoTexel) continue;
    const uint32_t g = groupOfAnchor[anchor[p]];
    out.ofPoint[p] = g;
    if (g != kNoTexel) out.points[fill[g]++] = p;
  }
  return out;
}

// Checks that the options are usable and that the gather, the clusters and the far levels
// match the texel set.
Status checkLinkInputs(const TexelSet& texels, const TexelGather& gather, const Clusters& clusters,
                       const LinkOptions& options, const std::vector<Clusters>& farLevels) {
  if (options.clusterRays <= 0) return Status::error("computeLinks: clusterRays must be positive");
  const uint32_t texelCount = texels.size();
  const uint32_t clusterCount = clusters.size();
  if (clusters.texelCluster.size() != texelCount)
    return Status::error(format("computeLinks: clusters cover %zu texels, the texel set has %u",
                                clusters.texelCluster.size(), texelCount));
  if (gather.hitStart.size() != size_t(texelCount) + 1 ||
      gather.sky.size() != size_t(texelCount) * kShCount ||
      gather.pointOfTexel.size() != texelCount || gather.fullRays.size() != texelCount)
    return Status::error("computeLinks: the gather does not match the texel set");
  if (clusterCount > 0 && clusters.firstTexel.size() != size_t(clusterCount) + 1)
    return Status::error("computeLinks: Clusters::firstTexel needs one entry per cluster plus one");
  for (const Clusters& far : farLevels)
    if (far.texelCluster.size() != texelCount)
      return Status::error("computeLinks: the far clusters do not match the texel set");
  return Status::ok();
}

// The area of cluster c's texels, and texel t's share of it (of `members` texels: an even
// share when they have no area): how a cluster averages its texels.
double memberArea(const TexelSet& texels, const Clusters& clusters, size_t c) {
  double area = 0.0;
  for (uint32_t k = clusters.firstTexel[c]; k < clusters.firstTexel[c + 1]; ++k)
    area += double(texels.area[clusters.memberTexels[k]]);
  return area;
}
double shareOf(const TexelSet& texels, uint32_t t, double area, uint32_t members) {
  return area > 0.0 ? double(texels.area[t]) / area : 1.0 / double(members);
}

// The front clusters' sky transfer, the area-weighted mean of their texels' (the back
// clusters' comes with their rays, traceBackRays); before the far targets, whose light check
// reads it.
void frontClusterSky(const TexelSet& texels, const TexelGather& gather, const Clusters& clusters,
                     runtime::TransportData& transport) {
  transport.clusterSky.assign(size_t(clusters.size()) * kShCount, 0);
  parallelFor(clusters.size(), [&](size_t c) {
    if (clusters.back[c]) return;
    const uint32_t first = clusters.firstTexel[c], last = clusters.firstTexel[c + 1];
    const double area = memberArea(texels, clusters, c);
    double sky[kShCount] = {};
    for (uint32_t k = first; k < last; ++k) {
      const uint32_t t = clusters.memberTexels[k];
      if (gather.pointOfTexel[t] == TexelGather::kNoHit) continue;
      const double share = shareOf(texels, t, area, last - first);
      for (int i = 0; i < kShCount; ++i)
        sky[i] += share * double(gather.sky[size_t(t) * kShCount + size_t(i)]);
    }
    for (int i = 0; i < kShCount; ++i)
      transport.clusterSky[c * kShCount + size_t(i)] = runtime::floatToHalf(float(sky[i]));
  }, 1024);
}

// What the gather points' rays link to, and with what weight (visit).
class PointHits {
 public:
  // Flags a target as far (targetOf): the far field a group of points may share.
  static constexpr uint32_t kFarHit = 0x80000000u;
  static_assert(runtime::kMaxLinkTargets <= kFarHit, "the flag is above every target");

  PointHits(const TexelSet& texels, const TexelGather& gather, const Clusters& clusters,
            const FarTargets& far, const runtime::TransportData& transport)
      : texels_(texels), gather_(gather), clusters_(clusters), far_(far),
        albedoRatios_(gather.hitAlbedo.size() == gather.hits.size() && !gather.hits.empty()) {
    if (albedoRatios_)
      for (const glm::vec3& a : transport.clusterAlbedoTexture)
        clusterGrey_.push_back((a.x + a.y + a.z) / 3.0f);
  }

  // What a gather point's ray from texel `from` links to: the coarsest far cluster of a front
  // hit seen from far enough (flagged kFarHit), else the hit's cluster.
  uint32_t targetOf(uint32_t code, uint32_t from) const {
    if (far_.empty() || code == TexelGather::kNoHit || (code & TexelGather::kBackSide))
      return clusterOfHit(clusters_, code);
    const uint32_t t = code & TexelGather::kTexelMask;
    const glm::vec3 d = texels_.position[t] - texels_.position[from];
    bool seenFar = false;
    const uint32_t f = far_.of(t, glm::dot(d, d), &seenFar);
    if (f != kNoTexel) return f | kFarHit;
    // Seen from far, but in a far cluster lit unevenly: its own cluster, still far (sharable).
    const uint32_t c = clusterOfHit(clusters_, code);
    return c != kNoTexel && seenFar ? (c | kFarHit) : c;
  }

  // A hit close by (within albedoDetail texel edges) on the front of a textured surface sees
  // the texture there, not its cluster's mean: the link to its cluster carries the albedo at
  // the hit point over the cluster's (TexelGather::hitAlbedo over clusterAlbedoTexture). On
  // Sponza-sun walls a few cm from roof tiles and column mouldings whose texture differs 2x
  // from their cluster's mean were 50% too bright or dark (issue 16). A ratio of texture
  // modulations, as the transport's own, so a relight of the albedo factors leaves it be
  // (untextured materials: no code, exactly 1).
  double albedoDetail(uint32_t hitIndex, uint32_t code, uint32_t target) const {
    if (!albedoRatios_ || gather_.hitAlbedo[hitIndex] == 0) return 1.0;
    if (target != clusters_.texelCluster[code & TexelGather::kTexelMask]) return 1.0;
    const float grey = clusterGrey_[target];
    return grey > 0.0f ? double(TexelGather::albedoOfCode(gather_.hitAlbedo[hitIndex]) / grey)
                       : 1.0;
  }

  // A gather point's rays pooled, visit(target, weight, ray index, far hit) per hit. Hits in
  // the near field count over all the point's rays; hits beyond it were kept from the full
  // sets only, and share what the near hits and the misses leave (a ratio estimate), so every
  // row plus its misses sums to exactly 1 and a closed room neither gains nor loses light.
  template <class Visit>
  void visit(uint32_t p, Visit&& visit) const {
    const TexelGather& gather = gather_;
    uint32_t all = 0, near = 0, misses = 0, farFull = 0;
    for (uint32_t k = gather.pointStart[p]; k < gather.pointStart[p + 1]; ++k) {
      const uint32_t t = gather.pointTexels[k];
      const uint32_t firstHit = gather.hitStart[t], n = gather.hitStart[t + 1] - firstHit;
      all += n;
      for (uint32_t i = 0; i < n; ++i) {
        const uint32_t code = gather.hits[firstHit + i];
        if (code == TexelGather::kNoHit) ++misses;
        else if (!(code & TexelGather::kFar)) ++near;
        else if (i < gather.fullRays[t]) ++farFull;
      }
    }
    if (all == 0) return;
    const double farMass = double(all - near - misses) / double(all);
    // No full ray went far although others did: their share stays with the near hits.
    const double nearWeight = farFull > 0 || near == 0 ? 1.0 / double(all)
                                                       : (1.0 - double(misses) / all) / near;
    const double farWeight = farFull > 0 ? farMass / double(farFull) : 0.0;
    for (uint32_t k = gather.pointStart[p]; k < gather.pointStart[p + 1]; ++k) {
      const uint32_t t = gather.pointTexels[k];
      const uint32_t firstHit = gather.hitStart[t], n = gather.hitStart[t + 1] - firstHit;
      for (uint32_t i = 0; i < n; ++i) {
        const uint32_t code = gather.hits[firstHit + i];
        const bool inNearField = !(code & TexelGather::kFar);
        if (!inNearField && i >= gather.fullRays[t]) continue;  // counted by the full rays
        const uint32_t c = targetOf(code, t);
        if (c == kNoTexel) continue;
        const double w = (inNearField ? nearWeight : farWeight) *
                         albedoDetail(firstHit + i, code, c & ~kFarHit);
        visit(c & ~kFarHit, w, i, c >= kFarHit);
      }
    }
  }

 private:
  const TexelSet& texels_;
  const TexelGather& gather_;
  const Clusters& clusters_;
  const FarTargets& far_;
  const bool albedoRatios_;
  std::vector<float> clusterGrey_;  // per cluster, its texture's grey modulation
};

// Per gather point and light channel, the mean light its far hits' targets receive directly
// (a far cluster: its clusters' area-weighted mean), for the far fields' sharing (FarLitAlike);
// empty when there is nothing to share or no light to compare.
std::vector<float> farLightOfPoints(const PointHits& hits, uint32_t points, const ClusterLight& light,
                                    const FarTargets& far, const runtime::TransportData& transport,
                                    const LinkOptions& options) {
  const size_t channels = light.channels.size();
  std::vector<float> farLight;
  if (!(channels > 0 && !far.empty() && options.sharedFarSpan > 1 &&
        options.sharedFarLightRatio > 1.0f))
    return farLight;
  const uint32_t clusterCount = transport.clusterCount;
  const runtime::SparseMatrix& mix = transport.farClusters;
  std::vector<float> targetLight(size_t(clusterCount + mix.rows()) * channels, 0.0f);
  for (size_t ch = 0; ch < channels; ++ch) {
    for (uint32_t c = 0; c < clusterCount; ++c)
      targetLight[c * channels + ch] = light.channels[ch][c];
    for (size_t f = 0; f < mix.rows(); ++f) {
      double sum = 0.0;
      for (uint32_t k = mix.rowStart[f]; k < mix.rowStart[f + 1]; ++k)
        sum += double(mix.weight[k]) * double(light.channels[ch][mix.column[k]]);
      targetLight[(clusterCount + f) * channels + ch] = float(sum);
    }
  }
  farLight.assign(size_t(points) * channels, 0.0f);
  parallelFor(points, [&](size_t p) {
    std::vector<double> sum(channels, 0.0);
    double weight = 0.0;
    hits.visit(uint32_t(p), [&](uint32_t c, double w, uint32_t, bool farHit) {
      if (!farHit) return;
      weight += w;
      for (size_t ch = 0; ch < channels; ++ch)
        sum[ch] += w * double(targetLight[c * channels + ch]);
    });
    if (weight > 0.0)
      for (size_t ch = 0; ch < channels; ++ch)
        farLight[p * channels + ch] = float(sum[ch] / weight);
  }, 1024);
  return farLight;
}

// The back clusters' rays: a back cluster gathers with rays of its own from behind its texels,
// as many as they would cast from the front (up to clusterRays), round robin, each texel
// stratifying its share.
struct BackRays {
  std::vector<uint32_t> clusters;  // the back clusters with texels, their rows in this order
  std::vector<uint32_t> start;     // cluster i's rays: codes[start[i] .. start[i + 1])
  std::vector<uint32_t> codes;     // per ray, its TexelGather hit code
};

// How many rays back cluster c casts: `rays` per texel, up to clusterRays.
uint32_t backRayCount(const Clusters& clusters, uint32_t rays, uint32_t clusterRays, uint32_t c) {
  const uint64_t m = clusters.firstTexel[c + 1] - clusters.firstTexel[c];
  return uint32_t(std::min<uint64_t>(clusterRays, uint64_t(rays) * m));
}

BackRays planBackRays(const Clusters& clusters, uint32_t rays, uint32_t clusterRays) {
  BackRays out;
  for (uint32_t c = 0; c < clusters.size(); ++c)
    if (clusters.back[c] && clusters.firstTexel[c] < clusters.firstTexel[c + 1])
      out.clusters.push_back(c);
  out.start.assign(out.clusters.size() + 1, 0);
  for (size_t i = 0; i < out.clusters.size(); ++i)
    out.start[i + 1] = out.start[i] + backRayCount(clusters, rays, clusterRays, out.clusters[i]);
  out.codes.resize(out.start.back());
  return out;
}

// Queues back cluster c's `count` rays. Ray s belongs to member s % m as its (s / m)-th:
// queued member by member (one frame and one stratification each; the members' shares differ
// by one at most).
void queueBackRays(const TexelSet& texels, const Clusters& clusters, uint32_t c, uint32_t count,
                   GatherBatch& batch) {
  const uint32_t first = clusters.firstTexel[c], m = clusters.firstTexel[c + 1] - first;
  const sampling::Rng::ItemSeed seed{sampling::Rng::itemSeed(sampling::Stream::ClusterLinks, c)};
  const uint32_t share = count / m, extra = count % m;
  const sampling::Stratified more(share + 1), fewer(std::max(share, 1u));
  for (uint32_t i = 0; i < std::min(m, count); ++i) {
    const uint32_t t = clusters.memberTexels[first + i];
    const uint32_t localCount = share + (i < extra ? 1 : 0);
    const sampling::Stratified& strata = i < extra ? more : fewer;
    const sampling::Frame frame(-texels.normal[t]);
    const glm::vec3 origin = texels.backPosition(t), geometricNormal = -texels.geometricNormal[t];
    for (uint32_t local = 0; local < localCount; ++local) {
      sampling::Rng rng(seed, local * m + i);
      batch.add(origin, frame, geometricNormal, strata.point(rng, local));
    }
  }
}

// Traces the back clusters' rays, several clusters to a batch (a cluster casts a few hundred
// rays; Embree's coherent streams and the hit lookup's prefetching do better on a thousand or
// more), keeping their hit codes for the rows and storing their sky transfer.
void traceBackRays(const trace::RayTracer& tracer, const TexelSet& texels,
                   const Clusters& clusters, BackRays& back, runtime::TransportData& transport,
                   Progress& progress) {
  const TexelLookup lookup(texels);
  parallelForBlocks(back.clusters.size(), [&](size_t begin, size_t end, int) {
    constexpr size_t kRaysPerBatch = 1024;
    GatherBatch batch;  // its per-geometry cache is valid for this bake's tracer only
    for (size_t i = begin; i < end && !progress.cancelled();) {
      batch.clear();
      const size_t firstCluster = i;
      for (; i < end && batch.size() < kRaysPerBatch; ++i)
        queueBackRays(texels, clusters, back.clusters[i], back.start[i + 1] - back.start[i], batch);
      batch.trace(tracer, texels, &lookup);
      std::copy(batch.codes().begin(), batch.codes().end(),
                back.codes.begin() + back.start[firstCluster]);
      for (size_t j = firstCluster; j < i; ++j) {
        const uint32_t from = back.start[j] - back.start[firstCluster];
        const uint32_t count = back.start[j + 1] - back.start[j];
        const GatherBatch::Summary seen = batch.summarize(tracer, from, from + count);
        for (int k = 0; k < kShCount; ++k)
          transport.clusterSky[size_t(back.clusters[j]) * kShCount + size_t(k)] =
              runtime::floatToHalf(float(seen.sky[k] * (1.0 / double(count))));
      }
    }
    progress.advance(end - begin);
  }, 16);
}

// The rows of the links' matrices (RowBuilder): the gather points', the shared far fields' and
// the back clusters'.
class LinkRows {
 public:
  LinkRows(const TexelGather& gather, const Clusters& clusters, const PointHits& hits,
           const FarGroups& groups, const BackRays& back, uint32_t sharedBase,
           const LinkOptions& options)
      : gather_(gather), clusters_(clusters), hits_(hits), groups_(groups), back_(back),
        sharedBase_(sharedBase), minWeight_(options.minWeight),
        sharedRays_(uint64_t(std::max(1.0f, options.sharedFarPoints * float(gather.raysPerTexel)))),
        blockRays_(4 * uint64_t(gather.raysPerTexel)) {}

  // The shared far fields' rows (shared()), each normalised to sum to 1.
  void buildShared(Progress& progress, runtime::SparseLinks& out) const {
    buildRows(
        groups_.size(), sharedBase_, progress, [&] { return RowBuilder(sharedBase_); },
        [&](size_t r, RowBuilder& row, std::vector<Link>& links) {
          shared(uint32_t(r), row);
          row.finish(minWeight_, links);
          double sum = 0.0;
          for (const Link& l : links) sum += double(l.weight);
          for (Link& l : links) l.weight = float(double(l.weight) / sum);
        },
        out, 64);
  }

  // The links' rows over `targets` targets: the gather points' (point()), then the back
  // clusters' (back()).
  void buildLinks(uint32_t targets, Progress& progress, runtime::SparseLinks& out) const {
    const uint32_t points = gather_.points();
    buildRows(
        size_t(points) + back_.clusters.size(), targets, progress,
        [&] { return RowBuilder(targets); },
        [&](size_t r, RowBuilder& row, std::vector<Link>& links) {
          if (r < points) point(uint32_t(r), row);
          else back(r - points, row);
          row.finish(minWeight_, links);
        },
        out, 256);
  }

  // A point's row: its hits, except that a point sharing a far field links that field with
  // the weight of its own hits on far clusters instead of linking them one by one.
  void point(uint32_t p, RowBuilder& row) const {
    const uint32_t group = groups_.ofPoint[p];
    double shared = 0.0;
    hits_.visit(p, [&](uint32_t c, double w, uint32_t, bool farHit) {
      if (group != kNoTexel && farHit) shared += w;
      else row.add(c, w);
    });
    if (shared > 0.0) row.add(sharedBase_ + group, shared);
  }

  // A shared far field: its points' hits on far clusters, as they weigh in their own rows
  // (each point's rays count alike). A pool of texels near other geometry (up to
  // sharedFarSpan² points) is thinned to about sharedFarPoints × texelRays rays: the group's
  // rays interleaved (ray i of the group's k-th point is ray i × m + k of the group) and an
  // even share of them kept; as every point casts texelRays full rays, that keeps whole
  // points' sets, each a stratified set of its own. A fraction, not every n-th:
  // sharedFarPoints then sets the links' count smoothly. A pool of 2×2 blocks keeps four
  // points' rays, every ray of a square of four full blocks, whose rays together are one
  // stratified set of their tile's sequence (sampling::TiledSobol), while three blocks' worth
  // left the field that the square's points share erring alike over the square, a blotch (the
  // Cornell box's ceiling: 1.0% band-passed against 0.8%, for 3% more links on Sponza).
  // Normalised where it is built.
  void shared(uint32_t g, RowBuilder& row) const {
    const uint32_t first = groups_.start[g], m = groups_.start[g + 1] - first;
    uint64_t pooled = 0;
    for (uint32_t k = first; k < first + m; ++k) {
      const uint32_t p = groups_.points[k];
      for (uint32_t i = gather_.pointStart[p]; i < gather_.pointStart[p + 1]; ++i)
        pooled += gather_.fullRays[gather_.pointTexels[i]];
    }
    const uint32_t anchor = groups_.points[first];
    const bool blocks = gather_.pointStart[anchor + 1] - gather_.pointStart[anchor] > 1;
    const uint64_t keep = std::min(blocks ? blockRays_ : sharedRays_, pooled);
    for (uint32_t k = first; k < first + m; ++k) {
      hits_.visit(groups_.points[k], [&](uint32_t c, double w, uint32_t ray, bool farHit) {
        const uint64_t i = uint64_t(ray) * m + (k - first);
        if (farHit && (i + 1) * keep / pooled > i * keep / pooled) row.add(c, w);
      });
    }
  }

  // Back cluster i's row: its own rays' hits, each weighing alike.
  void back(size_t i, RowBuilder& row) const {
    const double weight = 1.0 / double(back_.start[i + 1] - back_.start[i]);
    for (uint32_t k = back_.start[i]; k < back_.start[i + 1]; ++k) {
      const uint32_t target = clusterOfHit(clusters_, back_.codes[k]);
      if (target != kNoTexel) row.add(target, weight);
    }
  }

 private:
  const TexelGather& gather_;
  const Clusters& clusters_;
  const PointHits& hits_;
  const FarGroups& groups_;
  const BackRays& back_;
  const uint32_t sharedBase_;
  const float minWeight_;
  const uint64_t sharedRays_, blockRays_;
};

// Sky transfer per texel: its gather point's, as half floats.
void storeTexelSky(const TexelSet& texels, const TexelGather& gather,
                   runtime::TransportData& transport) {
  transport.texelSky.assign(size_t(texels.size()) * kShCount, 0);
  parallelFor(texels.size(), [&](size_t t) {
    if (texels.valid[t])
      for (int i = 0; i < kShCount; ++i)
        transport.texelSky[t * kShCount + size_t(i)] =
            runtime::floatToHalf(gather.sky[t * kShCount + size_t(i)]);
  }, 4096);
}

// Where the clusters and gather points lie (TransportData::clusterPosition, ...): a point at
// its texels' area-weighted centre, facing their mean normal.
void storeDirections(const TexelSet& texels, const TexelGather& gather, const Clusters& clusters,
                     runtime::TransportData& transport) {
  transport.clusterPosition = clusters.position;
  const uint32_t points = gather.points();
  transport.pointPosition.assign(points, glm::vec3(0.0f));
  transport.pointNormal.assign(points, glm::vec3(0.0f, 0.0f, 1.0f));
  parallelFor(points, [&](size_t p) {
    glm::dvec3 position(0.0), normal(0.0);
    double area = 0.0;
    for (uint32_t k = gather.pointStart[p]; k < gather.pointStart[p + 1]; ++k) {
      const uint32_t t = gather.pointTexels[k];
      const double a = std::max(double(texels.area[t]), 1e-12);
      position += a * glm::dvec3(texels.position[t]);
      normal += a * glm::dvec3(texels.normal[t]);
      area += a;
    }
    if (area <= 0.0) return;
    transport.pointPosition[p] = glm::vec3(position / area);
    if (glm::length(normal) > 0.0) transport.pointNormal[p] = glm::vec3(glm::normalize(normal));
  }, 4096);
}

// What each cluster gathers: its texels' gather points, area-weighted (a back cluster: its own
// row, after the points').
runtime::SparseMatrix clusterGather(const TexelSet& texels, const TexelGather& gather,
                                    const Clusters& clusters, const BackRays& back) {
  std::vector<uint32_t> backRowOf(clusters.size(), kNoTexel);
  for (size_t i = 0; i < back.clusters.size(); ++i)
    backRowOf[back.clusters[i]] = gather.points() + uint32_t(i);
  return runtime::normalisedRows(clusters.size(), [&](size_t c, auto& entries) {
    const uint32_t first = clusters.firstTexel[c], last = clusters.firstTexel[c + 1];
    if (clusters.back[c]) {
      if (backRowOf[c] != kNoTexel) entries.emplace_back(backRowOf[c], 1.0f);
      return;
    }
    const double area = memberArea(texels, clusters, c);
    for (uint32_t k = first; k < last; ++k) {
      const uint32_t t = clusters.memberTexels[k];
      if (gather.pointOfTexel[t] == TexelGather::kNoHit) continue;
      entries.emplace_back(gather.pointOfTexel[t], float(shareOf(texels, t, area, last - first)));
    }
  }, blockRanges());
}

}  // namespace

ClusterLight clusterLight(const runtime::TransportData& transport, float maxRatio) {
  ClusterLight out;
  if (!(maxRatio > 1.0f)) return out;
  out.maxRatio = maxRatio;
  const size_t clusters = transport.clusterCount;
  auto add = [&](std::vector<float> values) {
    double mean = 0.0;
    for (float v : values) mean += double(v);
    mean /= double(std::max<size_t>(values.size(), 1));
    if (!(mean > 0.0)) return;  // a source that lights nothing cannot tell clusters apart
    out.channels.push_back(std::move(values));
    out.floors.push_back(float(0.05 * mean));
  };
  const size_t sources = std::min<size_t>(transport.sources.size(), 32);
  for (size_t s = 0; s < sources; ++s)
    if (transport.sources[s].kind == runtime::SourceKind::Light &&
        transport.sources[s].clusterTransfer.size() == clusters)
      add(transport.sources[s].clusterTransfer);
  if (transport.clusterSky.size() == clusters * kShCount) {
    std::vector<float> sky(clusters);
    for (size_t c = 0; c < clusters; ++c)
      sky[c] = runtime::halfToFloat(transport.clusterSky[c * kShCount]);
    add(std::move(sky));
  }
  return out;
}

// Numbers the front far clusters level by level, fills farClusters (each the
// area-weighted mix of the clusters its texels belong to, for those of several clusters) and
// the targets. A far cluster's radius is the farthest of its texels' corners from its centre.
FarTargets farTargets(const TexelSet& texels, const Clusters& clusters,
                      const std::vector<Clusters>& levels, float farDistance,
                      runtime::SparseMatrix* farClusters, const ClusterLight& light) {
  FarTargets out;
  if (farClusters) *farClusters = runtime::SparseMatrix();
  if (!(farDistance > 0.0f)) return out;
  std::vector<std::pair<uint32_t, float>> entries;
  for (const Clusters& far : levels) {
    std::vector<uint32_t>& ofTexel = out.ofTexel.emplace_back(texels.size(), kNoTexel);
    for (uint32_t c = 0; c < far.size(); ++c) {
      if (far.back[c] || far.firstTexel[c] == far.firstTexel[c + 1]) continue;
      const uint32_t f = uint32_t(out.reach2.size());
      entries.clear();
      float radius = 0.0f;
      bool single = true;
      for (uint32_t k = far.firstTexel[c]; k < far.firstTexel[c + 1]; ++k) {
        const uint32_t t = far.memberTexels[k];
        if (clusters.texelCluster[t] == kNoTexel) continue;  // (every valid texel has one)
        ofTexel[t] = f;
        single = single && (entries.empty() || entries[0].first == clusters.texelCluster[t]);
        entries.emplace_back(clusters.texelCluster[t], texels.area[t]);
        radius = std::max(radius, glm::length(texels.position[t] - far.position[c]) +
                                      0.7072f * texels.edge[t]);
      }
      const float reach = farDistance * radius;
      out.reach2.push_back(reach * reach);
      out.unlike.push_back(0);
      if (single && !entries.empty()) {
        out.target.push_back(entries[0].first);
        continue;
      }
      out.target.push_back(clusters.size() + out.rows++);
      // A far cluster whose clusters are lit unlike each other is left to its finer levels.
      bool alike = true;
      for (size_t ch = 0; ch < light.channels.size() && alike; ++ch) {
        const std::vector<float>& values = light.channels[ch];
        float lo = std::numeric_limits<float>::infinity(), hi = 0.0f;
        for (const auto& [member, a] : entries) {
          lo = std::min(lo, values[member]);
          hi = std::max(hi, values[member]);
        }
        alike = hi <= light.maxRatio * lo + light.floors[ch];
      }
      out.unlike.back() = alike ? 0 : 1;
      if (farClusters) farClusters->appendNormalisedRow(entries);
    }
  }
  return out;
}

Status computeLinks(const scenes::Scene& scene, const trace::RayTracer& tracer, const TexelSet& texels,
                    const TexelGather& gather, const Clusters& clusters,
                    const LinkOptions& options, runtime::TransportData& transport,
                    Progress& progress, const std::vector<Clusters>& farLevels) {
  if (Status st = checkLinkInputs(texels, gather, clusters, options, farLevels); !st) return st;
  const uint32_t points = gather.points();
  transport.texelCount = texels.size();
  transport.clusterCount = clusters.size();
  transport.gatherPointCount = points;
  transport.atlases = texels.atlases;
  fillMaterials(scene, clusters, transport);
  frontClusterSky(texels, gather, clusters, transport);

  // The link targets: clusters, far clusters, and the far fields that points share.
  const ClusterLight light = clusterLight(transport, options.farLightRatio);
  const FarTargets far = farTargets(texels, clusters, farLevels, options.farDistance,
                                    &transport.farClusters, light);
  const PointHits hits(texels, gather, clusters, far, transport);
  const std::vector<float> farLight =
      farLightOfPoints(hits, points, light, far, transport, options);
  // (Without far clusters there is no far field to share.)
  const FarGroups groups =
      shareFarFields(tracer, texels, gather, far.empty() ? 0 : options.sharedFarSpan,
                     FarLitAlike(farLight, light, options.sharedFarLightRatio));
  const uint32_t sharedBase = transport.sharedFarBase();
  const uint64_t targetCount = uint64_t(sharedBase) + groups.size();
  if (targetCount > runtime::kMaxLinkTargets)
    return Status::error(format(
        "%llu clusters, far clusters and shared far fields, more than the transport's links can "
        "address (%u): raise --cluster-size or --cluster-texels, or lower --texels-per-unit",
        (unsigned long long)targetCount, runtime::kMaxLinkTargets));

  // The rows: the back clusters' rays first, then the shared far fields, then the points' and
  // the back clusters' rows.
  BackRays back = planBackRays(clusters, gather.raysPerTexel, uint32_t(options.clusterRays));
  const size_t rowCount = size_t(points) + back.clusters.size();  // the links' rows
  progress.begin(stageName(Stage::Links), back.clusters.size() + groups.size() + rowCount);
  traceBackRays(tracer, texels, clusters, back, transport, progress);
  const LinkRows rows(gather, clusters, hits, groups, back, sharedBase, options);
  rows.buildShared(progress, transport.sharedFar);
  rows.buildLinks(uint32_t(targetCount), progress, transport.links);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");

  storeTexelSky(texels, gather, transport);
  storeDirections(texels, gather, clusters, transport);
  transport.clusterGather = clusterGather(texels, gather, clusters, back);
  // How texels read the gather points and how the points smooth each other, built by the
  // runtime from what the transport file stores (so a loaded file has the very same maps).
  transport.filterPasses = std::max(0, options.filterPasses);
  static_assert(TexelGather::kNoHit == kNoTexel, "invalid texels read no gather point");
  transport.texelPoint = gather.pointOfTexel;
  transport.texelNeighbours = markFilterNeighbours(tracer, texels, gather, options);
  runtime::buildGatherMaps(transport, blockRanges());
  return Status::ok();
}

}  // namespace afterglow::baker
