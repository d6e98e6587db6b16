// Clusters: valid texels grouped by instance and material, then by a world grid of clusterSize
// cells centred on the group, then by normal cones.
#include "afterglow/baker/clusters.h"

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

uint32_t texelMaterial(const scenes::Scene& scene, const TexelSet& texels, uint32_t t) {
  const scenes::Instance& inst = scene.instances[texels.instance[t]];
  return uint32_t(scene.meshes[size_t(inst.mesh)].primitives[texels.primitive[t]].material);
}

// A cluster while the group is being partitioned.
struct Provisional {
  uint64_t cell = 0;
  std::vector<uint32_t> members;
  glm::dvec3 normalSum{0.0};  // area-weighted
  glm::dvec3 plainSum{0.0};   // for clusters of zero area
  bool alive = true;

  void add(const TexelSet& texels, uint32_t t) {
    members.push_back(t);
    normalSum += double(texels.area[t]) * glm::dvec3(texels.normal[t]);
    plainSum += glm::dvec3(texels.normal[t]);
  }
  void merge(const Provisional& other) {
    members.insert(members.end(), other.members.begin(), other.members.end());
    normalSum += other.normalSum;
    plainSum += other.plainSum;
  }
  glm::vec3 normal() const {
    const glm::dvec3 n = glm::length(normalSum) > 0.0 ? normalSum : plainSum;
    return glm::length(n) > 0.0 ? glm::vec3(glm::normalize(n)) : glm::vec3(0.0f);
  }
};

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

Clusters computeClusters(const scenes::Scene& scene, const TexelSet& texels,
                         const ClusterOptions& options) {
  Clusters clusters;
  const uint32_t count = texels.size();
  clusters.texelCluster.assign(count, kNoTexel);
  clusters.firstTexel.push_back(0);

  // Valid texels sorted by (instance, material, index).
  std::vector<uint32_t> order;
  std::vector<uint32_t> material(count, 0);
  for (uint32_t t = 0; t < count; ++t) {
    if (!texels.valid[t]) continue;
    order.push_back(t);
    material[t] = texelMaterial(scene, texels, t);
  }
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    if (texels.instance[a] != texels.instance[b]) return texels.instance[a] < texels.instance[b];
    if (material[a] != material[b]) return material[a] < material[b];
    return a < b;
  });

  const float cellSize = options.clusterSize > 0.0f ? options.clusterSize : 1e30f;
  // Every texel within half the cone of its seed keeps the whole cluster within the cone of the
  // cluster's mean normal (the mean of unit vectors in a cone stays in that cone).
  const float seedCos = std::cos(0.5f * glm::clamp(options.maxNormalAngleDeg, 0.0f, 180.0f) *
                                 kPi / 180.0f);

  const float coneCos =
      std::cos(glm::clamp(options.maxNormalAngleDeg, 0.0f, 180.0f) * kPi / 180.0f);

  std::vector<uint64_t> cell;
  std::vector<uint32_t> groupTexels;
  std::vector<uint8_t> taken;
  auto emitCluster = [&](const std::vector<uint32_t>& members) {
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
      clusters.texelCluster[t] = c;
      clusters.memberTexels.push_back(t);
    }
    const double n = double(members.size());
    const bool weighted = area > 0.0;
    clusters.position.push_back(glm::vec3(weighted ? position / area : plainPosition / n));
    if (!(glm::length(normal) > 0.0)) normal = plainNormal;
    const double length = glm::length(normal);
    clusters.normal.push_back(length > 0.0 ? glm::vec3(normal / length)
                                           : texels.normal[members.front()]);
    clusters.area.push_back(float(area));
    clusters.material.push_back(material[members.front()]);
    if (weighted) {
      clusters.albedo.push_back(glm::vec3(albedo / area));
      clusters.emission.push_back(glm::vec3(emission / area));
    } else {
      clusters.albedo.push_back(diffuseAlbedo(scene, mat, texels.uv0[members.front()]));
      clusters.emission.push_back(emittedRadiance(scene, mat, texels.uv0[members.front()]));
    }
    clusters.firstTexel.push_back(uint32_t(clusters.memberTexels.size()));
  };

  std::vector<Provisional> provisional;
  for (size_t begin = 0; begin < order.size();) {
    size_t end = begin + 1;
    const uint32_t first = order[begin];
    while (end < order.size() && texels.instance[order[end]] == texels.instance[first] &&
           material[order[end]] == material[first])
      ++end;

    // A grid centred on the group, so a surface that fits one cell is not cut by the grid.
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    for (size_t i = begin; i < end; ++i) {
      lo = glm::min(lo, texels.position[order[i]]);
      hi = glm::max(hi, texels.position[order[i]]);
    }
    glm::ivec3 cells;
    glm::vec3 origin;
    for (int a = 0; a < 3; ++a) {
      const float extent = hi[a] - lo[a];
      cells[a] = std::max(1, int(std::min(1e6f, std::ceil(extent / cellSize - 1e-4f))));
      origin[a] = 0.5f * (lo[a] + hi[a]) - 0.5f * float(cells[a]) * cellSize;
    }
    groupTexels.assign(order.begin() + long(begin), order.begin() + long(end));
    cell.resize(count);
    for (uint32_t t : groupTexels) {
      glm::ivec3 c;
      for (int a = 0; a < 3; ++a)
        c[a] = std::clamp(int(std::floor((texels.position[t][a] - origin[a]) / cellSize)), 0,
                          cells[a] - 1);
      cell[t] = (uint64_t(c.z) * uint64_t(cells.y) + uint64_t(c.y)) * uint64_t(cells.x) +
                uint64_t(c.x);
    }
    std::sort(groupTexels.begin(), groupTexels.end(), [&](uint32_t a, uint32_t b) {
      return cell[a] != cell[b] ? cell[a] < cell[b] : a < b;
    });

    // Within a cell, greedy normal cones seeded by the lowest remaining texel index.
    provisional.clear();
    for (size_t cb = 0; cb < groupTexels.size();) {
      size_t ce = cb + 1;
      while (ce < groupTexels.size() && cell[groupTexels[ce]] == cell[groupTexels[cb]]) ++ce;
      taken.assign(ce - cb, 0);
      for (size_t s = cb; s < ce; ++s) {
        if (taken[s - cb]) continue;
        const glm::vec3 seed = texels.normal[groupTexels[s]];
        Provisional pc;
        pc.cell = cell[groupTexels[s]];
        for (size_t i = s; i < ce; ++i) {
          if (taken[i - cb] || glm::dot(texels.normal[groupTexels[i]], seed) < seedCos) continue;
          taken[i - cb] = 1;
          pc.add(texels, groupTexels[i]);
        }
        provisional.push_back(std::move(pc));
      }
      cb = ce;
    }

    // Tiny clusters (grid cells clipping a surface's edge) join the neighbouring cluster whose
    // normal agrees best, when every texel of both stays within the cone of the merged normal.
    const auto cellCoord = [&](uint64_t id) {
      return glm::ivec3(int(id % uint64_t(cells.x)), int((id / uint64_t(cells.x)) % uint64_t(cells.y)),
                        int(id / (uint64_t(cells.x) * uint64_t(cells.y))));
    };
    const auto cellId = [&](const glm::ivec3& c) {
      return (uint64_t(c.z) * uint64_t(cells.y) + uint64_t(c.y)) * uint64_t(cells.x) + uint64_t(c.x);
    };
    // Provisional clusters come out in cell order, so a cell's clusters are one sorted range.
    const auto cellRange = [&](uint64_t id) {
      const auto lo = std::lower_bound(provisional.begin(), provisional.end(), id,
                                       [](const Provisional& pc, uint64_t v) { return pc.cell < v; });
      const auto hi = std::upper_bound(provisional.begin(), provisional.end(), id,
                                       [](uint64_t v, const Provisional& pc) { return v < pc.cell; });
      return std::make_pair(size_t(lo - provisional.begin()), size_t(hi - provisional.begin()));
    };
    const auto fitsCone = [&](const Provisional& a, const Provisional& b) {
      glm::dvec3 n = a.normalSum + b.normalSum;
      if (!(glm::length(n) > 0.0)) n = a.plainSum + b.plainSum;
      if (!(glm::length(n) > 0.0)) return false;
      const glm::vec3 unit(glm::normalize(n));
      for (const Provisional* pc : {&a, &b})
        for (uint32_t t : pc->members)
          if (glm::dot(texels.normal[t], unit) < coneCos) return false;
      return true;
    };
    for (size_t i = 0; i < provisional.size() && options.minTexels > 1; ++i) {
      Provisional& small = provisional[i];
      if (!small.alive || small.members.size() >= size_t(options.minTexels)) continue;
      const glm::ivec3 c = cellCoord(small.cell);
      const glm::vec3 ni = small.normal();
      size_t best = provisional.size();
      float bestDot = -2.0f;
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const glm::ivec3 nc = c + glm::ivec3(dx, dy, dz);
            if (glm::any(glm::lessThan(nc, glm::ivec3(0))) ||
                glm::any(glm::greaterThanEqual(nc, cells)))
              continue;
            const auto [lo, hi] = cellRange(cellId(nc));
            for (size_t j = lo; j < hi; ++j) {
              if (j == i || !provisional[j].alive) continue;
              const float d = glm::dot(ni, provisional[j].normal());
              if (d > bestDot || (d == bestDot && j < best)) {
                if (!fitsCone(small, provisional[j])) continue;
                bestDot = d;
                best = j;
              }
            }
          }
      if (best == provisional.size()) continue;
      provisional[best].merge(small);
      small.alive = false;
    }
    for (Provisional& pc : provisional) {
      if (!pc.alive) continue;
      std::sort(pc.members.begin(), pc.members.end());
      emitCluster(pc.members);
    }
    begin = end;
  }
  return clusters;
}

}  // namespace afterglow::baker
