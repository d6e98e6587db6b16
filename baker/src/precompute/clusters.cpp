// Clusters: valid texels grouped by instance and material, then by a world grid of clusterSize
// cells centred on the group, then by normal cones.
#include "afterglow/baker/clusters.h"

#include "afterglow/baker/gather.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/core/math.h"
#include "afterglow/core/parallel.h"
#include "afterglow/scenes/material_eval.h"
#include "precompute/sight_lines.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace afterglow::baker {
namespace {

using runtime::kNoTexel;

// The diffuse albedo averaged over texel t's footprint: its atlas pixel mapped into the
// material's UVs through the affine map of its triangle (TEXCOORD_1 in pixels to TEXCOORD_0),
// read at 4 × 4 points. A texture's detail finer than a texel (roof tiles and the gaps between
// them, mortar) must reach the bounces as its mean over the texel, as an engine's lightmapping
// meta pass renders albedo at lightmap resolution, not as whatever the sample point lands on:
// on Sponza-sun a roof texel whose sample hit a bright spot lit its neighbours 4 times too
// much (issue 16). Untextured materials, and triangles without both UV sets, read the sample.
glm::vec3 footprintAlbedo(const scenes::Scene& scene, const TexelSet& texels, int material,
                          uint32_t t) {
  if (!albedoTextured(scene.material(material)))
    return diffuseAlbedo(scene, material, texels.uv0[t]);
  const scenes::Instance& inst = scene.instances[texels.instance[t]];
  const scenes::Primitive& prim =
      scene.meshes[size_t(inst.mesh)].primitives[texels.primitive[t]];
  const size_t first = size_t(texels.triangle[t]) * 3;
  const std::vector<glm::vec2>& lightmapUv = scenes::lightmapUvs(prim, texels.uvSet);
  const scenes::LightmapLocation& lm = scenes::lightmapOf(inst, texels.uvSet);
  if (prim.uv0.size() != prim.positions.size() || lightmapUv.size() != prim.positions.size() ||
      first + 2 >= prim.indices.size() || lm.width <= 0)
    return diffuseAlbedo(scene, material, texels.uv0[t]);
  const glm::dvec2 size(lm.width, lm.height);
  glm::dvec2 px[3], uv[3];
  for (int k = 0; k < 3; ++k) {
    px[k] = glm::dvec2(lightmapUv[prim.indices[first + size_t(k)]]) * size;
    uv[k] = glm::dvec2(prim.uv0[prim.indices[first + size_t(k)]]);
  }
  const glm::dmat2 pixels(px[1] - px[0], px[2] - px[0]), uvs(uv[1] - uv[0], uv[2] - uv[0]);
  const double det = glm::determinant(pixels);
  if (!(std::abs(det) > 1e-12)) return diffuseAlbedo(scene, material, texels.uv0[t]);
  const glm::dmat2 perPixel = uvs * glm::inverse(pixels);  // d uv0 / d pixel
  const glm::dvec2 centre = glm::dvec2(texels.pixel[t]) + 0.5;
  const glm::dvec2 base = uv[0] + perPixel * (centre - px[0]);
  glm::dvec3 sum(0.0);
  constexpr int kSide = 4;
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x) {
      const glm::dvec2 d((double(x) + 0.5) / kSide - 0.5, (double(y) + 0.5) / kSide - 0.5);
      sum += glm::dvec3(diffuseAlbedo(scene, material, glm::vec2(base + perPixel * d)));
    }
  return glm::vec3(sum / double(kSide * kSide));
}

// Splits one group's texels (one instance and material) into clusters: a k-d subdivision until
// every node is small enough (clusterSize, adaptiveScale × median ray distance) and uniform
// enough in ray distance, then normal cones within each leaf.
class GroupClusterer {
 public:
  GroupClusterer(const TexelSet& texels, const trace::RayTracer* tracer, bool backs,
                 const std::vector<float>& distance, const ClusterOptions& options)
      : texels_(texels), tracer_(tracer), backs_(backs), distance_(distance), options_(options) {
    const float angle = glm::clamp(options.maxNormalAngleDeg, 0.0f, 180.0f) * kPi / 180.0f;
    // Every texel within half the cone of its seed keeps the whole cluster within the cone of
    // the cluster's mean normal (the mean of unit vectors in a cone stays in that cone).
    seedCos_ = std::cos(0.5f * angle);
  }

  // Appends the clusters of `group` (texel indices, ascending) to `out`, each sorted.
  void run(std::vector<uint32_t> group, std::vector<std::vector<uint32_t>>& out) const {
    // The k-d subdivision works on ranges of `group` in place, each split a stable partition
    // (a node's texels keep their order), so a node costs no allocation of its own.
    struct Range {
      uint32_t begin, end;
    };
    std::vector<Range> stack{{0, uint32_t(group.size())}}, leafRanges;
    Scratch scratch;
    while (!stack.empty()) {
      const Range node = stack.back();
      stack.pop_back();
      const uint32_t mid =
          node.begin + split(group.data() + node.begin, node.end - node.begin, scratch);
      if (mid > node.begin) {
        // Second half first on the stack so the first half is finished first: the order of
        // the clusters follows the subdivision, whatever the thread count.
        stack.push_back({mid, node.end});
        stack.push_back({node.begin, mid});
      } else {
        leafRanges.push_back(node);
      }
    }
    std::vector<std::vector<uint32_t>> leaves;
    leaves.reserve(leafRanges.size());
    for (const Range& r : leafRanges)
      leaves.emplace_back(group.begin() + long(r.begin), group.begin() + long(r.end));
    // Leaves split further where a wall stands between their texels, then by normal cones.
    for (size_t i = 0; i < leaves.size(); ++i) {
      std::vector<uint32_t> hidden = separateHidden(leaves[i]);
      cones(leaves[i], out);
      if (!hidden.empty()) leaves.push_back(std::move(hidden));
    }
  }

 private:
  glm::vec3 positionOf(uint32_t t) const {
    return backs_ ? texels_.backPosition(t) : texels_.position[t];
  }
  glm::vec3 normalOf(uint32_t t) const { return backs_ ? -texels_.normal[t] : texels_.normal[t]; }

  // Moves the texels that cannot see the leaf's central texel out of the leaf and returns them
  // (a floor cluster must not reach under a box or past a wall: its light would leak). The
  // test ray runs above the surface, lifted by a quarter of its length, so curved surfaces
  // within the normal cone do not hide their own texels.
  std::vector<uint32_t> separateHidden(std::vector<uint32_t>& leaf) const {
    std::vector<uint32_t> hidden;
    if (!tracer_ || leaf.size() < 2) return hidden;
    glm::dvec3 centre(0.0);
    for (uint32_t t : leaf) centre += glm::dvec3(positionOf(t));
    centre /= double(leaf.size());
    uint32_t seed = leaf.front();
    double best = std::numeric_limits<double>::infinity();
    for (uint32_t t : leaf) {
      const double d = glm::length(glm::dvec3(positionOf(t)) - centre);
      if (d < best) best = d, seed = t;
    }
    // The sight lines of the leaf traced together (packets: they share an origin).
    std::vector<trace::Ray> lines;
    std::vector<uint32_t> lineOf(leaf.size(), kNoTexel);
    for (size_t i = 0; i < leaf.size(); ++i) {
      trace::Ray line;
      if (leaf[i] == seed || !liftedSightLine(positionOf(seed), normalOf(seed),
                                              positionOf(leaf[i]), normalOf(leaf[i]), line))
        continue;
      lineOf[i] = uint32_t(lines.size());
      lines.push_back(line);
    }
    std::unique_ptr<bool[]> blocked(new bool[lines.size()]);
    tracer_->occluded(lines.data(), blocked.get(), lines.size());
    std::vector<uint32_t> kept;
    for (size_t i = 0; i < leaf.size(); ++i) {
      if (lineOf[i] == kNoTexel || !blocked[lineOf[i]]) kept.push_back(leaf[i]);
      else hidden.push_back(leaf[i]);
    }
    leaf.swap(kept);
    return hidden;
  }

  float distanceOf(uint32_t t) const {
    if (distance_.empty()) return std::numeric_limits<float>::infinity();
    return distance_[t];
  }

  // A split's working buffers, one set per run.
  struct Scratch {
    std::vector<float> values;
    std::vector<uint32_t> moved;
  };

  // Moves the node's texels for which `first` holds to its front, keeping the order on both
  // sides; returns how many there are.
  template <class Pred>
  static uint32_t partition(uint32_t* node, uint32_t n, Scratch& scratch, Pred&& first) {
    scratch.moved.clear();
    uint32_t kept = 0;
    for (uint32_t i = 0; i < n; ++i) {
      if (first(node[i])) node[kept++] = node[i];
      else scratch.moved.push_back(node[i]);
    }
    std::copy(scratch.moved.begin(), scratch.moved.end(), node + kept);
    return kept;
  }

  // Splits the node's n texels into two runs, in place; returns the length of the first, or 0
  // when the node is a leaf.
  uint32_t split(uint32_t* node, uint32_t n, Scratch& scratch) const {
    const uint32_t minTexels = uint32_t(std::max(1, options_.minTexels));
    if (n < 2 * minTexels) return 0;
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-lo);
    float low = std::numeric_limits<float>::infinity(), high = -low, edge = 0.0f;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t t = node[i];
      lo = glm::min(lo, texels_.position[t]);
      hi = glm::max(hi, texels_.position[t]);
      const float d = distanceOf(t);
      low = std::min(low, d);
      high = std::max(high, d);
      edge += texels_.edge[t];
    }
    const glm::vec3 extent = hi - lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    // Ray distances: the spread separates regions apart, the median bounds the size.
    if (options_.maxDistanceRatio > 1.0f && std::isfinite(low) && low > 0.0f &&
        high > options_.maxDistanceRatio * low) {
      // Apart by ray distance, at the geometric mean of the two percentiles.
      const float cut = std::isfinite(high) ? std::sqrt(low * high) : low * options_.maxDistanceRatio;
      uint32_t below = 0;
      for (uint32_t i = 0; i < n; ++i) below += distanceOf(node[i]) < cut ? 1 : 0;
      if (below >= minTexels && n - below >= minTexels)
        return partition(node, n, scratch, [&](uint32_t t) { return distanceOf(t) < cut; });
    }
    float limit = options_.clusterSize > 0.0f ? options_.clusterSize : std::numeric_limits<float>::infinity();
    if (options_.clusterTexels > 0.0f)
      limit = std::min(limit, options_.clusterTexels * edge / float(n));
    // The median only matters when the node is within the other limits (most nodes are not:
    // the subdivision starts from whole instances).
    if (extent[axis] <= limit && options_.adaptiveScale > 0.0f && !distance_.empty()) {
      std::vector<float>& d = scratch.values;
      d.resize(n);
      for (uint32_t i = 0; i < n; ++i) d[i] = distanceOf(node[i]);
      std::nth_element(d.begin(), d.begin() + long(n / 2), d.end());
      const float median = d[n / 2];
      if (std::isfinite(median)) limit = std::min(limit, options_.adaptiveScale * median);
    }
    if (!(extent[axis] > limit)) return 0;
    // At the middle of the box, moved into the 25th..75th percentile of the texels along the
    // axis so neither half comes out tiny. The middle lies below the 25th percentile exactly
    // when at most n/4 texels are at or below it (and above the 75th when more than 3n/4 are
    // below it), so the percentiles are only looked for when the middle is outside them.
    const uint32_t q1 = n / 4, q3 = (n * 3) / 4;
    float cut = 0.5f * (lo[axis] + hi[axis]);
    uint32_t atOrBelow = 0, below = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const float x = texels_.position[node[i]][axis];
      atOrBelow += x <= cut ? 1 : 0;
      below += x < cut ? 1 : 0;
    }
    if (atOrBelow <= q1 || below > q3) {
      std::vector<float>& coords = scratch.values;
      coords.resize(n);
      for (uint32_t i = 0; i < n; ++i) coords[i] = texels_.position[node[i]][axis];
      std::nth_element(coords.begin(), coords.begin() + long(q1), coords.end());
      const float first = coords[q1];
      std::nth_element(coords.begin() + long(q1), coords.begin() + long(q3), coords.end());
      cut = std::clamp(cut, first, coords[q3]);
      below = 0;
      for (uint32_t i = 0; i < n; ++i) below += texels_.position[node[i]][axis] < cut ? 1 : 0;
    }
    // Many texels on the cut (a flat surface seen edge-on): halve by index instead.
    if (below < minTexels || n - below < minTexels) return n / 2;
    return partition(node, n, scratch,
                     [&](uint32_t t) { return texels_.position[t][axis] < cut; });
  }

  // Greedy normal cones seeded by the lowest remaining texel; a cone smaller than minTexels
  // joins the cone whose seed normal is nearest, when that keeps the merged cone within the
  // angle limit.
  void cones(std::vector<uint32_t>& leaf, std::vector<std::vector<uint32_t>>& out) const {
    std::sort(leaf.begin(), leaf.end());
    std::vector<uint8_t> taken(leaf.size(), 0);
    std::vector<std::vector<uint32_t>> found;
    std::vector<glm::vec3> seeds;
    for (size_t s = 0; s < leaf.size(); ++s) {
      if (taken[s]) continue;
      const glm::vec3 seed = texels_.normal[leaf[s]];
      std::vector<uint32_t> members;
      for (size_t i = s; i < leaf.size(); ++i) {
        if (taken[i] || glm::dot(texels_.normal[leaf[i]], seed) < seedCos_) continue;
        taken[i] = 1;
        members.push_back(leaf[i]);
      }
      found.push_back(std::move(members));
      seeds.push_back(seed);
    }
    const size_t minTexels = size_t(std::max(1, options_.minTexels));
    const float coneCos = std::cos(glm::clamp(options_.maxNormalAngleDeg, 0.0f, 180.0f) * kPi / 180.0f);
    for (size_t i = 0; i < found.size(); ++i) {
      if (found[i].empty() || found[i].size() >= minTexels || found.size() == 1) continue;
      size_t best = found.size();
      float bestDot = -2.0f;
      for (size_t j = 0; j < found.size(); ++j) {
        if (j == i || found[j].empty()) continue;
        const float d = glm::dot(seeds[i], seeds[j]);
        if (d > bestDot && fitsCone(found[i], found[j], coneCos)) {
          bestDot = d;
          best = j;
        }
      }
      if (best == found.size()) continue;
      found[best].insert(found[best].end(), found[i].begin(), found[i].end());
      std::sort(found[best].begin(), found[best].end());
      found[i].clear();
    }
    for (std::vector<uint32_t>& f : found)
      if (!f.empty()) out.push_back(std::move(f));
  }

  bool fitsCone(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b,
                float coneCos) const {
    glm::dvec3 sum(0.0);
    for (const auto* list : {&a, &b})
      for (uint32_t t : *list) sum += double(texels_.area[t]) * glm::dvec3(texels_.normal[t]);
    if (!(glm::length(sum) > 0.0)) return false;
    const glm::vec3 n(glm::normalize(sum));
    for (const auto* list : {&a, &b})
      for (uint32_t t : *list)
        if (glm::dot(texels_.normal[t], n) < coneCos) return false;
    return true;
  }

  const TexelSet& texels_;
  const trace::RayTracer* tracer_;
  bool backs_;
  const std::vector<float>& distance_;
  const ClusterOptions& options_;
  float seedCos_ = 0.0f;
};

}  // namespace

ClusterOptions farClusterOptions(const ClusterOptions& options, int level) {
  const float scale = std::pow(options.farScale, float(level));
  ClusterOptions far = options;
  far.clusterSize *= scale;
  far.clusterTexels *= scale;
  far.adaptiveScale *= scale;
  far.farLevels = 0;
  return far;
}

Clusters computeClusters(const scenes::Scene& scene, const trace::RayTracer* tracer,
                         const TexelSet& texels, const TexelGather* gather,
                         const ClusterOptions& options) {
  Clusters clusters;
  const uint32_t count = texels.size();
  clusters.texelCluster.assign(count, kNoTexel);
  clusters.texelBackCluster.assign(count, kNoTexel);
  clusters.firstTexel.push_back(0);

  // Valid texels sorted by (instance, material, index): one key per texel, sorted stably
  // (texels come mostly in order already).
  std::vector<uint32_t> material(count, 0);
  parallelFor(count, [&](size_t t) {
    if (texels.valid[t]) material[t] = uint32_t(texelMaterial(scene, texels, uint32_t(t)));
  }, 4096);
  std::vector<std::pair<uint64_t, uint32_t>> keyed;
  for (uint32_t t = 0; t < count; ++t)
    if (texels.valid[t]) keyed.push_back({(uint64_t(texels.instance[t]) << 32) | material[t], t});
  if (!std::is_sorted(keyed.begin(), keyed.end()))
    std::stable_sort(keyed.begin(), keyed.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<uint32_t> order(keyed.size());
  for (size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  keyed = {};

  // Front sides of every group, then the back sides of the double-sided ones.
  const std::vector<float> none;
  // Groups (one instance and material) as ranges of `order`, clustered in parallel and
  // concatenated in group order, so the result does not depend on the thread count.
  std::vector<std::pair<size_t, size_t>> groups;
  for (size_t begin = 0; begin < order.size();) {
    size_t end = begin + 1;
    const uint32_t first = order[begin];
    while (end < order.size() && texels.instance[order[end]] == texels.instance[first] &&
           material[order[end]] == material[first])
      ++end;
    groups.emplace_back(begin, end);
    begin = end;
  }
  // Every group's front side and, for double-sided groups, its back side, as tasks of one
  // parallel loop (two loops would leave a thread idle at the end of each), largest first.
  const std::vector<float>& frontDistance =
      gather && gather->harmonicDistance.size() == count ? gather->harmonicDistance : none;
  const std::vector<float>& backDistance =
      gather && gather->backHarmonicDistance.size() == count ? gather->backHarmonicDistance : none;
  const GroupClusterer frontClusterer(texels, tracer, false, frontDistance, options);
  const GroupClusterer backClusterer(texels, tracer, true, backDistance, options);
  const bool seenOnly = gather && gather->backSeen.size() == count;
  std::vector<std::vector<std::vector<uint32_t>>> perTask(2 * groups.size());  // fronts, backs
  std::vector<size_t> tasks(perTask.size());
  for (size_t i = 0; i < tasks.size(); ++i) tasks[i] = i;
  auto texelsOf = [&](size_t task) {
    const auto [begin, end] = groups[task % groups.size()];
    return end - begin;
  };
  std::stable_sort(tasks.begin(), tasks.end(),
                   [&](size_t a, size_t b) { return texelsOf(a) > texelsOf(b); });
  parallelFor(tasks.size(), [&](size_t i) {
    const size_t task = tasks[i], g = task % groups.size();
    const bool back = task >= groups.size();
    const auto [begin, end] = groups[g];
    if (back && !scene.material(int(int32_t(material[order[begin]]))).doubleSided) return;
    std::vector<uint32_t> members(order.begin() + long(begin), order.begin() + long(end));
    if (back && seenOnly)
      members.erase(std::remove_if(members.begin(), members.end(),
                                   [&](uint32_t t) { return !gather->backSeen[t]; }),
                    members.end());
    if (members.empty()) return;
    (back ? backClusterer : frontClusterer).run(std::move(members), perTask[task]);
  }, 1);
  // Concatenated in group order, so the result does not depend on the thread count.
  std::vector<std::vector<uint32_t>> fronts, backs;
  for (size_t task = 0; task < perTask.size(); ++task)
    for (auto& cluster : perTask[task])
      (task < groups.size() ? fronts : backs).push_back(std::move(cluster));

  // Numbered fronts then backs, in group order; the per-cluster means in parallel (each
  // cluster summed in its own texel order, so the result does not depend on the thread count).
  const size_t total = fronts.size() + backs.size();
  auto membersOf = [&](size_t c) -> const std::vector<uint32_t>& {
    return c < fronts.size() ? fronts[c] : backs[c - fronts.size()];
  };
  clusters.firstTexel.resize(total + 1);
  for (size_t c = 0; c < total; ++c) {
    const std::vector<uint32_t>& members = membersOf(c);
    const bool back = c >= fronts.size();
    for (uint32_t t : members) {
      (back ? clusters.texelBackCluster : clusters.texelCluster)[t] = uint32_t(c);
      clusters.memberTexels.push_back(t);
    }
    clusters.firstTexel[c + 1] = uint32_t(clusters.memberTexels.size());
  }
  clusters.position.resize(total);
  clusters.normal.resize(total);
  clusters.area.resize(total);
  clusters.material.resize(total);
  clusters.albedo.resize(total);
  clusters.emission.resize(total);
  clusters.back.resize(total);
  parallelFor(total, [&](size_t c) {
    const std::vector<uint32_t>& members = membersOf(c);
    const bool back = c >= fronts.size();
    double area = 0.0;
    glm::dvec3 position(0.0), normal(0.0), albedo(0.0), emission(0.0), plainPosition(0.0),
        plainNormal(0.0);
    const int mat = int(int32_t(material[members.front()]));
    for (uint32_t t : members) {
      const double a = double(texels.area[t]);
      area += a;
      position += a * glm::dvec3(texels.position[t]);
      plainPosition += glm::dvec3(texels.position[t]);
      normal += a * glm::dvec3(texels.normal[t]);
      plainNormal += glm::dvec3(texels.normal[t]);
      albedo += a * glm::dvec3(footprintAlbedo(scene, texels, mat, t));
      emission += a * glm::dvec3(emittedRadiance(scene, mat, texels.uv0[t]));
    }
    const double n = double(members.size());
    const bool weighted = area > 0.0;
    clusters.position[c] = glm::vec3(weighted ? position / area : plainPosition / n);
    if (!(glm::length(normal) > 0.0)) normal = plainNormal;
    const double length = glm::length(normal);
    const glm::vec3 unit =
        length > 0.0 ? glm::vec3(normal / length) : texels.normal[members.front()];
    clusters.normal[c] = back ? -unit : unit;
    clusters.area[c] = float(area);
    clusters.material[c] = material[members.front()];
    if (weighted) {
      clusters.albedo[c] = glm::vec3(albedo / area);
      clusters.emission[c] = glm::vec3(emission / area);
    } else {
      clusters.albedo[c] = footprintAlbedo(scene, texels, mat, members.front());
      clusters.emission[c] = emittedRadiance(scene, mat, texels.uv0[members.front()]);
    }
    // A back-side cluster shows its material's emission only where the back emits.
    if (back && !scene.material(mat).emitsFromBack()) clusters.emission[c] = glm::vec3(0.0f);
    clusters.back[c] = back ? 1 : 0;
  }, 64);
  return clusters;
}

}  // namespace afterglow::baker
