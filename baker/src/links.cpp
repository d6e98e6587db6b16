// Stage 3 of the precompute: form factors texel -> cluster and cluster -> cluster, sky transfer
// and texel validity, by cosine-distributed gather rays.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "afterglow/baker/raytracer.h"
#include "afterglow/baker/transport_precompute.h"
#include "afterglow/core/parallel.h"
#include "sampling.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::kShCount;

// The texel under a hit: texelAt maps it through TEXCOORD_1 and stands in a valid neighbour
// when the hit lands in a chart's padding or on a buried texel.
uint32_t texelUnderHit(const scenes::Scene& scene, const TexelSet& texels, const Hit& hit) {
  return texelAt(scene, texels, hit.instance, hit.primitive, hit.triangle, hit.barycentric);
}

struct Link {
  uint32_t cluster;
  float weight;
};

// One row of gathered links plus its sky transfer and back-face count. Rays are queued and
// traced as one batch per row (the tracer's batched call has less bookkeeping per ray).
struct Gather {
  std::vector<Ray> queue;
  std::vector<Hit> queueHits;
  std::vector<uint32_t> hits;  // cluster of every ray that reached a lit surface
  double sky[kShCount] = {};   // double: thousands of rays per row
  int backfaces = 0;
  int rays = 0;

  void reset() {
    queue.clear();
    hits.clear();
    for (double& v : sky) v = 0.0;
    backfaces = 0;
    rays = 0;
  }
};

// Queues one cosine-distributed ray from `origin` around the shading normal. Directions below
// the geometric surface are mirrored above it: a shading normal tilted away from the face must
// not send rays into the surface the sample lies on.
void queueGatherRay(glm::vec3 origin, const sampling::Frame& frame, glm::vec3 geometricNormal,
                    glm::vec2 u, Gather& g) {
  glm::vec3 dir = frame.toWorld(sampling::cosineHemisphere(u));
  const float below = glm::dot(dir, geometricNormal);
  if (below < 0.0f) dir = glm::normalize(dir - 2.0f * below * geometricNormal);
  Ray ray;
  ray.origin = origin;
  ray.direction = dir;
  g.queue.push_back(ray);
}

// Traces the queued rays and records what each saw.
void traceQueue(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels,
                const Clusters& clusters, Gather& g) {
  g.queueHits.resize(g.queue.size());
  tracer.intersect(g.queue.data(), g.queueHits.data(), g.queue.size());
  for (size_t k = 0; k < g.queue.size(); ++k) {
    const Hit& hit = g.queueHits[k];
    ++g.rays;
    if (!hit.valid()) {
      float y[kShCount];
      sampling::shBasis(g.queue[k].direction, y);
      for (int i = 0; i < kShCount; ++i) g.sky[i] += double(y[i]);
      continue;
    }
    if (!hit.frontFace && !tracer.material(hit).doubleSided) {
      ++g.backfaces;
      continue;
    }
    // Dynamic instances block the ray but take no part in bounces.
    if (!scene.instances[hit.instance].isStatic) continue;
    const uint32_t texel = texelUnderHit(scene, texels, hit);
    if (texel == kNoTexel) continue;
    const uint32_t cluster = clusters.texelCluster[texel];
    if (cluster == kNoTexel) continue;
    g.hits.push_back(cluster);
  }
  g.queue.clear();
}

// Turns ray counts per cluster into form factors. Links below minWeight are folded into the
// row's strongest link so the row keeps its sum (energy) while the matrix stays sparse.
void finishRow(Gather& g, float minWeight, std::vector<Link>& row, float* sky) {
  row.clear();
  const float inv = g.rays > 0 ? 1.0f / float(g.rays) : 0.0f;
  for (int i = 0; i < kShCount; ++i) sky[i] = float(g.sky[i] * double(inv));
  std::sort(g.hits.begin(), g.hits.end());
  for (size_t k = 0; k < g.hits.size();) {
    size_t e = k;
    while (e < g.hits.size() && g.hits[e] == g.hits[k]) ++e;
    row.push_back({g.hits[k], float(e - k) * inv});
    k = e;
  }
  if (row.size() < 2) return;
  size_t strongest = 0;
  for (size_t k = 1; k < row.size(); ++k)
    if (row[k].weight > row[strongest].weight) strongest = k;
  float folded = 0.0f;
  std::vector<Link> kept;
  kept.reserve(row.size());
  for (size_t k = 0; k < row.size(); ++k) {
    if (k != strongest && row[k].weight < minWeight) {
      folded += row[k].weight;
    } else {
      kept.push_back(row[k]);
    }
  }
  if (folded > 0.0f) {
    for (Link& l : kept)
      if (l.cluster == row[strongest].cluster) l.weight += folded;
  }
  row.swap(kept);
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

}  // namespace

Status computeLinks(const scenes::Scene& scene, const RayTracer& tracer, TexelSet& texels,
                    const Clusters& clusters, const LinkOptions& options,
                    runtime::TransportData& transport, Progress& progress) {
  if (options.texelRays <= 0 || options.clusterRays <= 0)
    return Status::error("computeLinks: texelRays and clusterRays must be positive");
  const uint32_t texelCount = texels.size();
  const uint32_t clusterCount = clusters.size();
  if (clusters.texelCluster.size() != texelCount)
    return Status::error(format("computeLinks: clusters cover %zu texels, the texel set has %u",
                                clusters.texelCluster.size(), texelCount));
  if (clusterCount > 0 && clusters.firstTexel.size() != size_t(clusterCount) + 1)
    return Status::error("computeLinks: Clusters::firstTexel needs one entry per cluster plus one");

  transport.texelCount = texelCount;
  transport.clusterCount = clusterCount;
  transport.atlases = texels.atlases;
  fillMaterials(scene, clusters, transport);

  // Texel rows. Each item writes only its own row, so the result is independent of threads.
  const uint32_t texelRays = uint32_t(options.texelRays);
  std::vector<std::vector<Link>> rows(texelCount);
  // Texels found inside walls are collected apart and invalidated after the pass: texelAt reads
  // texels.valid for every hit, so changing it during the pass would race and make links
  // depend on thread timing.
  std::vector<uint8_t> buried(texelCount, 0);
  transport.texelSky.assign(size_t(texelCount) * kShCount, 0.0f);
  progress.begin("form factors (texels)", texelCount);
  parallelForBlocks(texelCount, [&](size_t begin, size_t end, int) {
    Gather g;
    for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
      if (!texels.valid[t]) continue;
      g.reset();
      const sampling::Frame frame(texels.normal[t]);
      for (uint32_t s = 0; s < texelRays; ++s) {
        sampling::Rng rng(sampling::Stream::TexelLinks, t, s);
        queueGatherRay(texels.position[t], frame, texels.geometricNormal[t],
                       sampling::stratified2(rng, s, texelRays), g);
      }
      traceQueue(scene, tracer, texels, clusters, g);
      if (float(g.backfaces) > options.maxBackfaceFraction * float(g.rays)) {
        buried[t] = 1;  // inside a wall: no links, no sky; filled from neighbours later
        continue;
      }
      finishRow(g, options.minWeight, rows[t], &transport.texelSky[t * kShCount]);
    }
    progress.advance(end - begin);
  });
  progress.end();
  if (progress.cancelled()) return Status::error("computeLinks: cancelled");
  concatenate(rows, transport.texelLinks);
  for (uint32_t t = 0; t < texelCount; ++t)
    if (buried[t]) texels.valid[t] = 0;

  // Cluster rows: clusterRays rays spread round-robin over the cluster's (still) valid texels.
  const uint32_t clusterRays = uint32_t(options.clusterRays);
  rows.assign(clusterCount, {});
  transport.clusterSky.assign(size_t(clusterCount) * kShCount, 0.0f);
  progress.begin("form factors (clusters)", clusterCount);
  parallelForBlocks(clusterCount, [&](size_t begin, size_t end, int) {
    std::vector<uint32_t> members;
    Gather g;
    for (size_t c = begin; c < end && !progress.cancelled(); ++c) {
      members.clear();
      for (uint32_t k = clusters.firstTexel[c]; k < clusters.firstTexel[c + 1]; ++k) {
        const uint32_t t = clusters.memberTexels[k];
        if (texels.valid[t]) members.push_back(t);
      }
      if (members.empty()) continue;
      g.reset();
      for (uint32_t s = 0; s < clusterRays; ++s) {
        // Each texel stratifies its own share of the rays: striding one grid over the texels
        // would tie directions to texel positions and bias the cluster's links.
        const uint32_t m = uint32_t(members.size());
        const uint32_t t = members[s % m];
        const uint32_t local = s / m;
        const uint32_t localCount = (clusterRays - s % m + m - 1) / m;
        sampling::Rng rng(sampling::Stream::ClusterLinks, c, s);
        const sampling::Frame frame(texels.normal[t]);
        queueGatherRay(texels.position[t], frame, texels.geometricNormal[t],
                       sampling::stratified2(rng, local, localCount), g);
        if (g.queue.size() == 256) traceQueue(scene, tracer, texels, clusters, g);
      }
      traceQueue(scene, tracer, texels, clusters, g);
      // Back faces seen from a cluster reduce its reach but do not invalidate it: its texels
      // were judged one by one above.
      finishRow(g, options.minWeight, rows[c], &transport.clusterSky[c * kShCount]);
    }
    progress.advance(end - begin);
  });
  progress.end();
  if (progress.cancelled()) return Status::error("computeLinks: cancelled");
  concatenate(rows, transport.clusterLinks);
  return Status::ok();
}

}  // namespace afterglow::baker
