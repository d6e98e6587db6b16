// Clusters: valid texels grouped by instance and material, then by a world grid of clusterSize
// cells centred on the group, then by normal cones.
#include "afterglow/baker/clusters.h"

#include "afterglow/baker/raytracer.h"
#include "afterglow/core/parallel.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace afterglow::baker {
namespace {

using runtime::kNoTexel;

constexpr float kPi = 3.14159265358979323846f;

glm::vec3 textureRgb(const scenes::Scene& scene, const scenes::TextureRef& ref, glm::vec2 uv0) {
  if (!ref.valid() || size_t(ref.texture) >= scene.textures.size()) return glm::vec3(1.0f);
  const scenes::Texture& texture = scene.textures[size_t(ref.texture)];
  if (!texture.loaded()) return glm::vec3(1.0f);
  // Texels carry only TEXCOORD_0; a texture asking for another set reads set 0 instead.
  return glm::vec3(texture.sample(ref.transform(uv0)));
}


}  // namespace

glm::vec3 diffuseAlbedo(const scenes::Scene& scene, int material, glm::vec2 uv0) {
  const scenes::Material& m = scene.material(material);
  const glm::vec3 base = glm::vec3(m.baseColorFactor) * textureRgb(scene, m.baseColorTexture, uv0);
  const glm::vec3 mr = textureRgb(scene, m.metallicRoughnessTexture, uv0);
  const float metallic = glm::clamp(m.metallicFactor * mr.b, 0.0f, 1.0f);
  const float perceptualRoughness = glm::clamp(m.roughnessFactor * mr.g, 0.0f, 1.0f);
  // Unity's meta pass (UnityLightmappingAlbedo): roughness there is SmoothnessToRoughness, the
  // square of the perceptual roughness glTF stores.
  const float roughness = perceptualRoughness * perceptualRoughness;
  const glm::vec3 specColor = glm::mix(glm::vec3(0.04f), base, metallic);
  return base * (1.0f - metallic) + specColor * roughness * 0.5f;
}

glm::vec3 emittedRadiance(const scenes::Scene& scene, int material, glm::vec2 uv0) {
  const scenes::Material& m = scene.material(material);
  if (!m.emissive()) return glm::vec3(0.0f);
  return m.emission() * textureRgb(scene, m.emissiveTexture, uv0);
}

namespace {

// Splits one group's texels (one instance and material) into clusters: a k-d subdivision until
// every node is small enough (clusterSize, adaptiveScale × median ray distance) and uniform
// enough in ray distance, then normal cones within each leaf.
class GroupClusterer {
 public:
  GroupClusterer(const TexelSet& texels, const RayTracer* tracer, bool backs,
                 const std::vector<float>& distance, const ClusterOptions& options)
      : texels_(texels), tracer_(tracer), backs_(backs), distance_(distance), options_(options) {
    const float angle = glm::clamp(options.maxNormalAngleDeg, 0.0f, 180.0f) * kPi / 180.0f;
    // Every texel within half the cone of its seed keeps the whole cluster within the cone of
    // the cluster's mean normal (the mean of unit vectors in a cone stays in that cone).
    seedCos_ = std::cos(0.5f * angle);
  }

  // Appends the clusters of `group` (texel indices, ascending) to `out`, each sorted.
  void run(std::vector<uint32_t> group, std::vector<std::vector<uint32_t>>& out) {
    std::vector<std::vector<uint32_t>> stack;
    stack.push_back(std::move(group));
    std::vector<std::vector<uint32_t>> leaves;
    while (!stack.empty()) {
      std::vector<uint32_t> node = std::move(stack.back());
      stack.pop_back();
      std::vector<uint32_t> a, b;
      if (split(node, a, b)) {
        // Second half first on the stack so the first half is finished first: the order of
        // the clusters follows the subdivision, whatever the thread count.
        stack.push_back(std::move(b));
        stack.push_back(std::move(a));
      } else {
        leaves.push_back(std::move(node));
      }
    }
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
    std::vector<uint32_t> kept;
    for (uint32_t t : leaf) {
      if (t == seed || sees(seed, t)) kept.push_back(t);
      else hidden.push_back(t);
    }
    leaf.swap(kept);
    return hidden;
  }

  bool sees(uint32_t a, uint32_t b) const {
    const float lift = 0.25f * glm::length(positionOf(b) - positionOf(a));
    const glm::vec3 from = positionOf(a) + normalOf(a) * lift;
    const glm::vec3 to = positionOf(b) + normalOf(b) * lift;
    const glm::vec3 d = to - from;
    const float length = glm::length(d);
    if (!(length > 0.0f)) return true;
    Ray ray;
    ray.origin = from;
    ray.direction = d / length;
    ray.tfar = length;
    return !tracer_->occluded(ray);
  }

  float distanceOf(uint32_t t) const {
    if (distance_.empty()) return std::numeric_limits<float>::infinity();
    return distance_[t];
  }

  bool split(const std::vector<uint32_t>& node, std::vector<uint32_t>& a,
             std::vector<uint32_t>& b) const {
    const size_t minTexels = size_t(std::max(1, options_.minTexels));
    if (node.size() < 2 * minTexels) return false;
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-lo);
    for (uint32_t t : node) {
      lo = glm::min(lo, texels_.position[t]);
      hi = glm::max(hi, texels_.position[t]);
    }
    const glm::vec3 extent = hi - lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    // Ray distances: the median bounds the size, the spread separates regions apart.
    std::vector<float> d;
    d.reserve(node.size());
    for (uint32_t t : node) d.push_back(distanceOf(t));
    const auto [minIt, maxIt] = std::minmax_element(d.begin(), d.end());
    const float low = *minIt, high = *maxIt;
    std::nth_element(d.begin(), d.begin() + long(d.size() / 2), d.end());
    const float median = d[d.size() / 2];
    if (options_.maxDistanceRatio > 1.0f && std::isfinite(low) && low > 0.0f &&
        high > options_.maxDistanceRatio * low) {
      // Apart by ray distance, at the geometric mean of the two percentiles.
      const float cut = std::isfinite(high) ? std::sqrt(low * high) : low * options_.maxDistanceRatio;
      for (uint32_t t : node) (distanceOf(t) < cut ? a : b).push_back(t);
      if (a.size() >= minTexels && b.size() >= minTexels) return true;
      a.clear();
      b.clear();
    }
    float limit = options_.clusterSize > 0.0f ? options_.clusterSize : std::numeric_limits<float>::infinity();
    if (options_.clusterTexels > 0.0f) {
      float edge = 0.0f;
      for (uint32_t t : node) edge += texels_.edge[t];
      limit = std::min(limit, options_.clusterTexels * edge / float(node.size()));
    }
    if (options_.adaptiveScale > 0.0f && std::isfinite(median))
      limit = std::min(limit, options_.adaptiveScale * median);
    if (!(extent[axis] > limit)) return false;
    // At the middle of the box, moved into the 25th..75th percentile of the texels along the
    // axis so neither half comes out tiny.
    std::vector<float> coords;
    coords.reserve(node.size());
    for (uint32_t t : node) coords.push_back(texels_.position[t][axis]);
    const long q1 = long(coords.size() / 4), q3 = long((coords.size() * 3) / 4);
    std::nth_element(coords.begin(), coords.begin() + q1, coords.end());
    const float first = coords[size_t(q1)];
    std::nth_element(coords.begin() + q1, coords.begin() + q3, coords.end());
    const float third = coords[size_t(q3)];
    const float cut = std::clamp(0.5f * (lo[axis] + hi[axis]), first, third);
    for (uint32_t t : node) (texels_.position[t][axis] < cut ? a : b).push_back(t);
    if (a.size() < minTexels || b.size() < minTexels) {
      // Many texels on the cut (a flat surface seen edge-on): halve by index instead.
      a.assign(node.begin(), node.begin() + long(node.size() / 2));
      b.assign(node.begin() + long(node.size() / 2), node.end());
    }
    return true;
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
  const RayTracer* tracer_;
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

Clusters computeClusters(const scenes::Scene& scene, const RayTracer* tracer,
                         const TexelSet& texels, const TexelGather* gather,
                         const ClusterOptions& options) {
  Clusters clusters;
  const uint32_t count = texels.size();
  clusters.texelCluster.assign(count, kNoTexel);
  clusters.texelBackCluster.assign(count, kNoTexel);
  clusters.firstTexel.push_back(0);

  // Valid texels sorted by (instance, material, index).
  std::vector<uint32_t> order;
  std::vector<uint32_t> material(count, 0);
  for (uint32_t t = 0; t < count; ++t) {
    if (!texels.valid[t]) continue;
    order.push_back(t);
    material[t] = uint32_t(texelMaterial(scene, texels, t));
  }
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    if (texels.instance[a] != texels.instance[b]) return texels.instance[a] < texels.instance[b];
    if (material[a] != material[b]) return material[a] < material[b];
    return a < b;
  });

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
  auto partition = [&](const std::vector<float>& distance, bool backs) {
    GroupClusterer clusterer(texels, tracer, backs, distance.size() == count ? distance : none,
                             options);
    std::vector<std::vector<std::vector<uint32_t>>> perGroup(groups.size());
    const bool seenOnly = gather && gather->backSeen.size() == count;
    parallelFor(groups.size(), [&](size_t g) {
      const auto [begin, end] = groups[g];
      std::vector<uint32_t> members(order.begin() + long(begin), order.begin() + long(end));
      if (backs) {
        if (!scene.material(int(int32_t(material[order[begin]]))).doubleSided) return;
        if (seenOnly)
          members.erase(std::remove_if(members.begin(), members.end(),
                                       [&](uint32_t t) { return !gather->backSeen[t]; }),
                        members.end());
      }
      if (!members.empty()) clusterer.run(std::move(members), perGroup[g]);
    }, 1);
    std::vector<std::vector<uint32_t>> found;
    for (auto& list : perGroup)
      for (auto& cluster : list) found.push_back(std::move(cluster));
    return found;
  };
  const std::vector<std::vector<uint32_t>> fronts =
      partition(gather ? gather->harmonicDistance : none, false);
  const std::vector<std::vector<uint32_t>> backs =
      partition(gather ? gather->backHarmonicDistance : none, true);

  auto emit = [&](const std::vector<uint32_t>& members, bool back) {
    const uint32_t c = clusters.size();
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
      albedo += a * glm::dvec3(diffuseAlbedo(scene, mat, texels.uv0[t]));
      emission += a * glm::dvec3(emittedRadiance(scene, mat, texels.uv0[t]));
      (back ? clusters.texelBackCluster : clusters.texelCluster)[t] = c;
      clusters.memberTexels.push_back(t);
    }
    const double n = double(members.size());
    const bool weighted = area > 0.0;
    clusters.position.push_back(glm::vec3(weighted ? position / area : plainPosition / n));
    if (!(glm::length(normal) > 0.0)) normal = plainNormal;
    const double length = glm::length(normal);
    glm::vec3 unit = length > 0.0 ? glm::vec3(normal / length) : texels.normal[members.front()];
    clusters.normal.push_back(back ? -unit : unit);
    clusters.area.push_back(float(area));
    clusters.material.push_back(material[members.front()]);
    if (weighted) {
      clusters.albedo.push_back(glm::vec3(albedo / area));
      clusters.emission.push_back(glm::vec3(emission / area));
    } else {
      clusters.albedo.push_back(diffuseAlbedo(scene, mat, texels.uv0[members.front()]));
      clusters.emission.push_back(emittedRadiance(scene, mat, texels.uv0[members.front()]));
    }
    clusters.back.push_back(back ? 1 : 0);
    clusters.firstTexel.push_back(uint32_t(clusters.memberTexels.size()));
  };
  for (const std::vector<uint32_t>& members : fronts) emit(members, false);
  for (const std::vector<uint32_t>& members : backs) emit(members, true);
  return clusters;
}

}  // namespace afterglow::baker
