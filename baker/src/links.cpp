// Stage 3 of the precompute: form factors texel -> cluster and cluster -> cluster and sky
// transfer, from the texels' gather rays (and the back-side clusters' own rays).
#include <algorithm>
#include <cmath>
#include <utility>
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
using sampling::kPi;

struct Link {
  uint32_t cluster;
  float weight;
};

// Sorts a row's (cluster, weight) entries and merges duplicates. Links below minWeight are then
// folded into the row's strongest link so the row keeps its sum (energy) while the matrix stays
// sparse.
void finishRow(std::vector<Link>& row, float minWeight) {
  std::sort(row.begin(), row.end(),
            [](const Link& a, const Link& b) { return a.cluster < b.cluster; });
  size_t out = 0;
  for (size_t k = 0; k < row.size();) {
    Link merged = row[k];
    size_t e = k + 1;
    while (e < row.size() && row[e].cluster == merged.cluster) merged.weight += row[e++].weight;
    row[out++] = merged;
    k = e;
  }
  row.resize(out);
  if (row.size() < 2) return;
  size_t strongest = 0;
  for (size_t k = 1; k < row.size(); ++k)
    if (row[k].weight > row[strongest].weight) strongest = k;
  float folded = 0.0f;
  size_t kept = 0;
  for (size_t k = 0; k < row.size(); ++k) {
    if (k != strongest && row[k].weight < minWeight) {
      folded += row[k].weight;
      continue;
    }
    if (k == strongest) strongest = kept;
    row[kept++] = row[k];
  }
  row.resize(kept);
  row[strongest].weight += folded;
}

void concatenate(const std::vector<std::vector<Link>>& rows, runtime::SparseLinks& links) {
  links = runtime::SparseLinks();
  size_t total = 0;
  for (const auto& r : rows) total += r.size();
  links.rowStart.reserve(rows.size() + 1);
  links.target.reserve(total);
  links.weight.reserve(total);
  for (const auto& r : rows) {
    for (const Link& l : r) {
      links.target.push_back(l.cluster);
      links.weight.push_back(l.weight);
    }
    links.rowStart.push_back(uint32_t(links.target.size()));
  }
}

// The material's diffuse albedo factor without textures (DESIGN.md: baseColor × (1 − metallic)
// plus Unity's meta-pass specular share specColor × roughness × 0.5, specColor = lerp(0.04,
// baseColor, metallic), roughness = perceptual roughness², as baker::diffuseAlbedo does).
glm::vec3 albedoFactor(const scenes::Material& m) {
  const glm::vec3 base(m.baseColorFactor);
  const float metallic = std::clamp(m.metallicFactor, 0.0f, 1.0f);
  const float perceptual = std::clamp(m.roughnessFactor, 0.0f, 1.0f);
  const float roughness = perceptual * perceptual;
  const glm::vec3 spec = glm::mix(glm::vec3(0.04f), base, metallic);
  return base * (1.0f - metallic) + spec * roughness * 0.5f;
}

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

// Marks, per texel, the atlas neighbours whose bounced light may smooth its own: valid, same
// instance, same plane (normals within 30°, no step between them) and closer than filterReach ×
// the harmonic ray distance of both. The test is symmetric, so the filter is too.
void markFilterNeighbours(const TexelSet& texels, const TexelGather& gather,
                          const LinkOptions& options, runtime::TransportData& transport) {
  transport.indirectFilterPasses = std::max(0, options.filterPasses);
  transport.texelNeighbours.assign(texels.size(), 0);
  if (transport.indirectFilterPasses == 0) return;
  const float minCos = std::cos(30.0f * kPi / 180.0f);
  auto compatible = [&](uint32_t a, uint32_t b) {
    if (!texels.valid[b] || texels.instance[a] != texels.instance[b]) return false;
    if (glm::dot(texels.normal[a], texels.normal[b]) < minCos) return false;
    const glm::vec3 d = texels.position[b] - texels.position[a];
    const float distance = glm::length(d);
    if (std::abs(glm::dot(texels.geometricNormal[a], d)) > 0.2f * distance ||
        std::abs(glm::dot(texels.geometricNormal[b], d)) > 0.2f * distance)
      return false;
    const float reach = options.filterReach *
                        std::min(gather.harmonicDistance[a], gather.harmonicDistance[b]);
    return distance < reach;
  };
  parallelFor(texels.size(), [&](size_t i) {
    const uint32_t t = uint32_t(i);
    if (!texels.valid[t]) return;
    const runtime::AtlasLayout& layout = texels.atlases[texels.atlas[t]];
    uint8_t mask = 0;
    for (int k = 0; k < 8; ++k) {
      const int x = texels.pixel[t].x + runtime::kNeighbourOffsets[k][0];
      const int y = texels.pixel[t].y + runtime::kNeighbourOffsets[k][1];
      if (x < 0 || y < 0 || x >= layout.width || y >= layout.height) continue;
      const uint32_t n = layout.texelOfPixel[size_t(y) * size_t(layout.width) + size_t(x)];
      if (n != kNoTexel && compatible(t, n)) mask |= uint8_t(1u << k);
    }
    transport.texelNeighbours[t] = mask;
  });
}

}  // namespace

Status computeLinks(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels,
                    const TexelGather& gather, const Clusters& clusters,
                    const LinkOptions& options, runtime::TransportData& transport,
                    Progress& progress) {
  if (options.clusterRays <= 0) return Status::error("computeLinks: clusterRays must be positive");
  const uint32_t texelCount = texels.size();
  const uint32_t clusterCount = clusters.size();
  const uint32_t rays = gather.raysPerTexel;
  if (clusters.texelCluster.size() != texelCount)
    return Status::error(format("computeLinks: clusters cover %zu texels, the texel set has %u",
                                clusters.texelCluster.size(), texelCount));
  if (gather.hits.size() != size_t(texelCount) * rays ||
      gather.sky.size() != size_t(texelCount) * kShCount)
    return Status::error("computeLinks: the gather does not match the texel set");
  if (clusterCount > 0 && clusters.firstTexel.size() != size_t(clusterCount) + 1)
    return Status::error("computeLinks: Clusters::firstTexel needs one entry per cluster plus one");

  transport.texelCount = texelCount;
  transport.clusterCount = clusterCount;
  transport.atlases = texels.atlases;
  fillMaterials(scene, clusters, transport);

  // The cluster a hit code lands in: the texel's front cluster, or its back-side cluster.
  auto clusterOf = [&](uint32_t code) -> uint32_t {
    if (code == TexelGather::kNoHit) return kNoTexel;
    const uint32_t t = code & ~TexelGather::kBackSide;
    return (code & TexelGather::kBackSide) ? clusters.texelBackCluster[t] : clusters.texelCluster[t];
  };
  auto addHits = [&](uint32_t t, float weight, std::vector<Link>& row) {
    const uint32_t* codes = &gather.hits[size_t(t) * rays];
    for (uint32_t k = 0; k < rays; ++k) {
      const uint32_t c = clusterOf(codes[k]);
      if (c != kNoTexel) row.push_back({c, weight});
    }
  };

  // Texel rows: what each texel's own rays reached.
  std::vector<std::vector<Link>> rowsOfTexels(texelCount);
  transport.texelSky.assign(size_t(texelCount) * kShCount, 0.0f);
  progress.begin("form factors (texels)", texelCount);
  parallelForBlocks(texelCount, [&](size_t begin, size_t end, int) {
    for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
      if (!texels.valid[t]) continue;
      std::vector<Link>& row = rowsOfTexels[t];
      addHits(uint32_t(t), rays > 0 ? 1.0f / float(rays) : 0.0f, row);
      finishRow(row, options.minWeight);
      row.shrink_to_fit();
      std::copy_n(&gather.sky[t * kShCount], kShCount, &transport.texelSky[t * kShCount]);
    }
    progress.advance(end - begin);
  });
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  concatenate(rowsOfTexels, transport.texelLinks);
  std::vector<std::vector<Link>>().swap(rowsOfTexels);

  // Cluster rows. A front cluster gathers what its texels gather (area-weighted, all of their
  // rays); a back cluster of a double-sided surface casts clusterRays rays of its own from the
  // back of its texels (round robin, each texel stratifying its share).
  const uint32_t clusterRays = uint32_t(options.clusterRays);
  std::vector<std::vector<Link>> rows(clusterCount);
  transport.clusterSky.assign(size_t(clusterCount) * kShCount, 0.0f);
  progress.begin("form factors (clusters)", clusterCount);
  parallelForBlocks(clusterCount, [&](size_t begin, size_t end, int) {
    GatherBatch batch;
    for (size_t c = begin; c < end && !progress.cancelled(); ++c) {
      std::vector<Link>& row = rows[c];
      float* sky = &transport.clusterSky[c * kShCount];
      const uint32_t first = clusters.firstTexel[c], last = clusters.firstTexel[c + 1];
      if (first == last) continue;
      if (!clusters.back[c]) {
        double area = 0.0;
        for (uint32_t k = first; k < last; ++k) area += double(texels.area[clusters.memberTexels[k]]);
        for (uint32_t k = first; k < last; ++k) {
          const uint32_t t = clusters.memberTexels[k];
          const double share = area > 0.0 ? double(texels.area[t]) / area : 1.0 / double(last - first);
          addHits(t, float(share / double(rays)), row);
          for (int i = 0; i < kShCount; ++i)
            sky[i] += float(share * double(gather.sky[size_t(t) * kShCount + size_t(i)]));
        }
      } else {
        batch.clear();
        const uint32_t m = last - first;
        for (uint32_t s = 0; s < clusterRays; ++s) {
          const uint32_t t = clusters.memberTexels[first + s % m];
          const uint32_t local = s / m;
          const uint32_t localCount = (clusterRays - s % m + m - 1) / m;
          sampling::Rng rng(sampling::Stream::ClusterLinks, c, s);
          const sampling::Frame frame(-texels.normal[t]);
          batch.add(texels.backPosition(t), frame, -texels.geometricNormal[t],
                    sampling::stratified2(rng, local, localCount));
          if (batch.rays.size() == 256) batch.trace(scene, tracer, texels);
        }
        batch.trace(scene, tracer, texels);
        const float weight = 1.0f / float(clusterRays);
        for (uint32_t code : batch.codes) {
          const uint32_t target = clusterOf(code);
          if (target != kNoTexel) row.push_back({target, weight});
        }
        for (int i = 0; i < kShCount; ++i) sky[i] = float(batch.sky[i] * double(weight));
      }
      finishRow(row, options.minWeight);
      row.shrink_to_fit();
    }
    progress.advance(end - begin);
  });
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  concatenate(rows, transport.clusterLinks);
  markFilterNeighbours(texels, gather, options, transport);
  return Status::ok();
}

}  // namespace afterglow::baker
