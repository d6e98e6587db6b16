// afterglow_bench accuracy --breakdown: which texels carry the indirect error (issue 16), and
// how much of it a few changes to the gather would remove.
//
// Per compared texel it casts its own cosine-distributed rays (independent of the bake's) and
// classifies the texel by what it sees: how near other geometry is (harmonic ray distance in
// texel edges), whether it is sunlit, how big its cluster is, how unevenly lit the clusters its
// rays land in are, and its material. Each class's share of the summed squared relative error
// (compareToReference's e_t²) is printed next to its share of texels and of the reference's own
// noise², and its share of the excess (e² − noise², the error beyond the reference's noise), so
// a class whose error is only the reference's noise shows as such.
//
// The same rays also give four one-bounce final gathers of the bake's own solution, each an
// estimate of the texel's bounced light that one change to the precompute would approach:
//   cluster  each hit reads its cluster's reflected light (the solver's R): the transport's
//            model with unlimited rays and no far clusters, 2×2 blocks or smoothing
//   texelD   each hit reads its texel's own direct light (× the albedo at the hit) and its
//            cluster's bounced part: "the hit texel's own direct light", or clusters split by
//            light visibility as finely as the texels
//   nearEx   hits nearer than kNear × their cluster's size read the direct light at the hit
//            point itself (a shadow ray from there, sunAt) and their cluster's bounced part, the
//            others their cluster's light: a per-light near-field transfer
//   exact    that for every hit: the first bounce exact, the later ones through the clusters
// compared with the reference like the bake. The sky is left out (the accuracy bench lights
// with none); emission seen by a ray is direct light, as in the reference.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "afterglow/baker/bake.h"
#include "afterglow/baker/clusters.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/material_eval.h"
#include "bench_accuracy_breakdown.h"
#include "bench_common.h"

namespace afterglow::bench {

namespace {

using runtime::kNoTexel;

// splitmix64: seeded per (texel, ray), so the figures do not depend on the thread count.
double uniform(uint64_t& state) {
  uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return double((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
}

// Ray k of `count` over the hemisphere around n: stratified cosine-distributed directions,
// mirrored above the geometric surface when the shading normal tilts them below it (as the
// gather and the reference do).
glm::vec3 gatherDirection(glm::vec3 n, glm::vec3 ng, int k, int count, uint64_t& rng) {
  const int side = std::max(1, int(std::sqrt(double(count))));
  const double u = ((k % side) + uniform(rng)) / side, v = (((k / side) % side) + uniform(rng)) / side;
  const double r = std::sqrt(u), phi = 2.0 * 3.14159265358979 * v;
  const glm::vec3 a = std::abs(n.x) > 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 t = glm::normalize(glm::cross(a, n)), b = glm::cross(n, t);
  glm::vec3 d = float(r * std::cos(phi)) * t + float(r * std::sin(phi)) * b +
                float(std::sqrt(std::max(0.0, 1.0 - u))) * n;
  const float below = glm::dot(d, ng);
  if (below < 0.0f) d = glm::normalize(d - 2.0f * below * ng);
  return d;
}

// nearDirect's "near": a hit closer than this many × the √area of the cluster it lands in, where
// the cluster spans more than ~15° as seen from the texel.
constexpr double kNear = 4.0;

const char* const kGatherNames[4] = {"cluster", "texelD", "nearEx", "exact"};

// E/π of the directional lights at a hit (unit albedo, bounceIntensity applied), with one hard
// shadow ray each: what the reference's next-event estimate gives there on average, short of
// the sun's soft edge. Other lights are left out (Sponza-sun has the sun alone).
glm::dvec3 sunAt(const scenes::Scene& scene, const trace::RayTracer& tracer, const trace::Hit& hit) {
  const glm::vec3 ng = hit.frontFace ? hit.geometricNormal : -hit.geometricNormal;
  glm::vec3 n = tracer.shadingNormal(hit) * (hit.frontFace ? 1.0f : -1.0f);
  if (glm::dot(n, ng) <= 0.0f) n = ng;
  glm::vec3 p = tracer.position(hit);
  p += ng * (2e-5f * std::max({1.0f, std::abs(p.x), std::abs(p.y), std::abs(p.z)}));
  glm::dvec3 sum(0.0);
  for (const scenes::Light& light : scene.lights) {
    if (light.type != scenes::LightType::Directional) continue;
    const glm::vec3 toLight = -glm::normalize(light.direction);
    const float cosTheta = glm::dot(n, toLight);
    if (cosTheta <= 0.0f || glm::dot(ng, toLight) <= 0.0f) continue;
    trace::Ray shadow;
    shadow.origin = p;
    shadow.direction = toLight;
    shadow.mask = trace::kMaskShadowCasters;
    if (tracer.occluded(shadow)) continue;
    sum += glm::dvec3(light.color) *
           double(light.intensity * light.bounceIntensity * cosTheta / 3.14159265f);
  }
  return sum;
}

// What one texel's rays saw.
struct Probe {
  double harmonic = 0.0;       // harmonic mean ray distance, texel edges (∞ for all misses)
  double unevenness = 0.0;     // mean over rays of albedo × |hit texel's direct − its
                               //   cluster's mean direct|, E/π (relative later)
  glm::dvec3 gathers[4] = {};  // the final gathers, in kGatherNames' order
};

struct ClassSum {
  size_t texels = 0;
  double e2 = 0.0, noise2 = 0.0, signedSum = 0.0;
  double alt2[4] = {0.0, 0.0, 0.0, 0.0};  // e² of the four final gathers
};

}  // namespace

void printIndirectBreakdown(const scenes::Scene& scene, const trace::RayTracer& tracer,
                            const baker::BakeResult& b, const baker::ReferenceTexels& ref,
                            int rays) {
  const baker::TexelSet& texels = b.texels;
  const baker::Clusters& clusters = b.clusters;
  // The solver's reflected light per cluster, as the bake's last pass left it.
  runtime::Solver solver(b.transport);
  solver.setParallelFor(blockRanges());
  solver.solve();
  const std::vector<glm::vec3>& reflected = solver.clusterReflected();
  // Per front cluster: area-weighted mean direct and bounced light of its texels.
  std::vector<glm::dvec3> clusterDirect(clusters.size(), glm::dvec3(0.0)),
      clusterIndirect(clusters.size(), glm::dvec3(0.0));
  std::vector<double> clusterArea(clusters.size(), 0.0);
  for (uint32_t t = 0; t < texels.size(); ++t) {
    const uint32_t c = clusters.texelCluster[t];
    if (c == kNoTexel || !texels.valid[t]) continue;
    clusterDirect[c] += double(texels.area[t]) * glm::dvec3(b.texelDirect[t]);
    clusterIndirect[c] += double(texels.area[t]) * glm::dvec3(b.texelIndirect[t]);
    clusterArea[c] += double(texels.area[t]);
  }
  for (uint32_t c = 0; c < clusters.size(); ++c)
    if (clusterArea[c] > 0.0) clusterDirect[c] /= clusterArea[c], clusterIndirect[c] /= clusterArea[c];

  const size_t n = ref.texels.size();
  std::vector<Probe> probes(n);
  parallelFor(n, [&](size_t i) {
    const uint32_t t = ref.texels[i];
    Probe& p = probes[i];
    uint64_t rng = 0x5eed0000ull ^ (uint64_t(t) << 20);
    double inverse = 0.0;
    for (int k = 0; k < rays; ++k) {
      trace::Ray ray;
      ray.origin = texels.position[t];
      ray.direction = gatherDirection(texels.normal[t], texels.geometricNormal[t], k, rays, rng);
      const trace::Hit hit = tracer.intersect(ray);
      if (!hit.valid()) continue;
      inverse += 1.0 / std::max(double(hit.t), 1e-6);
      const scenes::Instance& inst = scene.instances[hit.instance];
      const int material = scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
      const bool doubleSided = scene.material(material).doubleSided;
      if (!inst.isStatic || (!hit.frontFace && !doubleSided)) continue;  // absorbs
      const uint32_t h = baker::texelAtUv(scene, texels, hit.instance, tracer.uv(hit, 1));
      if (h == kNoTexel) continue;
      if (!hit.frontFace) {  // the back of a double-sided surface: only its cluster's light
        const uint32_t c = clusters.texelBackCluster[h];
        if (c == kNoTexel) continue;
        for (glm::dvec3& g : p.gathers) g += glm::dvec3(reflected[c]);
        continue;
      }
      const uint32_t c = clusters.texelCluster[h];
      const glm::dvec3 albedo(scenes::diffuseAlbedo(scene, material, tracer.uv(hit, 0)));
      const glm::dvec3 direct(b.texelDirect[h]);
      const glm::dvec3 bounced = glm::dvec3(clusters.albedo[c]) * clusterIndirect[c];
      const bool near = double(hit.t) < kNear * std::sqrt(clusterArea[c]);
      const glm::dvec3 exact = albedo * sunAt(scene, tracer, hit) + bounced;
      p.gathers[0] += glm::dvec3(reflected[c]);
      p.gathers[1] += albedo * direct + bounced;
      p.gathers[2] += near ? exact : glm::dvec3(reflected[c]);
      p.gathers[3] += exact;
      const glm::dvec3 uneven = albedo * glm::abs(direct - clusterDirect[c]);
      p.unevenness += (uneven.x + uneven.y + uneven.z) / 3.0;
    }
    p.harmonic = inverse > 0.0 ? double(rays) / inverse / double(texels.edge[t]) : 1e30;
    for (glm::dvec3& g : p.gathers) g /= double(rays);
    p.unevenness /= double(rays);
  }, 16);

  // compareToReference's per-texel errors, for the bake and the four gathers.
  double meanNorm = 0.0, meanSum = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 r(ref.indirect[i]);
    meanNorm += glm::length(r);
    meanSum += r.x + r.y + r.z;
  }
  meanNorm /= double(std::max<size_t>(1, n));
  meanSum /= double(std::max<size_t>(1, n));
  // Sunlit: direct light above a tenth of the 90th percentile of the compared texels' (the sun
  // is one directional light, so a texel is in sun, in shade or in a thin penumbra).
  std::vector<double> directs;
  for (size_t i = 0; i < n; ++i) directs.push_back(glm::length(glm::dvec3(b.texelDirect[ref.texels[i]])));
  std::vector<double> sorted = directs;
  std::sort(sorted.begin(), sorted.end());
  const double sunny = sorted.empty() ? 0.0 : 0.1 * sorted[sorted.size() * 9 / 10];

  std::map<std::string, ClassSum> classes;
  // How many texels share each gather point (1: the texel gathers alone).
  std::vector<uint32_t> pointTexels(b.transport.gatherPointCount + 1, 0);
  for (uint32_t p : b.transport.texelPoint)
    ++pointTexels[p == runtime::kNoTexel ? b.transport.gatherPointCount : p];
  ClassSum all, capped;  // capped: each texel's e² at most 1, so a few texels 5-20× off (the
                        //   relative RMSE's outliers) weigh no more than any texel 100% off
  // The bake's own error rank, to show how concentrated the error is.
  std::vector<double> e2s(n);
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 r(ref.indirect[i]);
    const glm::dvec3 d = glm::dvec3(b.texelIndirect[ref.texels[i]]) - r;
    e2s[i] = glm::dot(d, d) / std::pow(std::max(glm::length(r), 0.1 * meanNorm), 2.0);
  }
  std::vector<double> e2sorted = e2s;
  std::sort(e2sorted.begin(), e2sorted.end(), std::greater<double>());
  const double top1 = e2sorted[std::min(n - 1, n / 100)], top10 = e2sorted[std::min(n - 1, n / 10)];
  std::vector<uint32_t> members(clusters.size(), 0);
  for (uint32_t t = 0; t < texels.size(); ++t)
    if (clusters.texelCluster[t] != kNoTexel) ++members[clusters.texelCluster[t]];
  for (size_t i = 0; i < n; ++i) {
    const uint32_t t = ref.texels[i];
    const glm::dvec3 r(ref.indirect[i]), v(ref.indirectVariance[i]);
    const double scale = std::max(glm::length(r), 0.1 * meanNorm);
    const glm::dvec3 d = glm::dvec3(b.texelIndirect[t]) - r;
    ClassSum one;
    one.texels = 1;
    one.e2 = glm::dot(d, d) / (scale * scale);
    one.noise2 = (v.x + v.y + v.z) / (scale * scale);
    one.signedSum = (d.x + d.y + d.z) / std::max(r.x + r.y + r.z, 0.1 * meanSum);
    for (int a = 0; a < 4; ++a) {
      const glm::dvec3 e = probes[i].gathers[a] - r;
      one.alt2[a] = glm::dot(e, e) / (scale * scale);
    }
    auto add = [&](ClassSum& to) {
      to.texels += one.texels, to.e2 += one.e2, to.noise2 += one.noise2;
      to.signedSum += one.signedSum;
      for (int a = 0; a < 4; ++a) to.alt2[a] += one.alt2[a];
    };
    add(all);
    capped.texels += 1, capped.e2 += std::min(one.e2, 1.0), capped.noise2 += std::min(one.noise2, 1.0);
    capped.signedSum += std::clamp(one.signedSum, -1.0, 1.0);
    for (int a = 0; a < 4; ++a) capped.alt2[a] += std::min(one.alt2[a], 1.0);
    const double h = probes[i].harmonic;
    add(classes[h < 2 ? "distance <2 edges" : h < 8 ? "distance 2-8 edges"
                 : h < 32 ? "distance 8-32 edges" : "distance >=32 edges"]);
    add(classes[directs[i] > 5.0 * sunny ? "sun: lit" : directs[i] > sunny ? "sun: penumbra"
                                                                           : "sun: shade"]);
    const uint32_t m = members[clusters.texelCluster[t]];
    add(classes[m < 4 ? "cluster <4 texels" : m < 16 ? "cluster 4-15 texels" : "cluster >=16 texels"]);
    const double u = probes[i].unevenness / (std::max(r.x + r.y + r.z, 0.1 * meanSum) / 3.0);
    add(classes[u < 0.1 ? "hit clusters' direct uneven <10%"
                : u < 0.3 ? "hit clusters' direct uneven 10-30%" : "hit clusters' direct uneven >=30%"]);
    add(classes[texels.nearGeometry[t] ? "nearGeometry 1" : "nearGeometry 0"]);
    add(classes[pointTexels[b.transport.texelPoint[t]] == 1 ? "gather point: alone"
                                                            : "gather point: block"]);
    add(classes[e2s[i] > top1 ? "rank: worst 1%" : e2s[i] > top10 ? "rank: worst 1-10%" : "rank: rest"]);
    const int material = baker::texelMaterial(scene, texels, t);
    add(classes["material " + (material >= 0 ? scene.materials[size_t(material)].name : "-")]);
  }
  const double tot = std::max(all.e2, 1e-30), totNoise = std::max(all.noise2, 1e-30);
  std::printf("indirect error by class (%zu texels, %d rays each for the classes and the final "
              "gathers):\n", n, rays);
  std::printf("  %-36s %7s %8s %9s %8s %7s %7s | RMSE of: %7s %7s %7s %7s\n", "class",
              "texels", "err²", "noise²", "excess", "RMSE", "bias", kGatherNames[0], kGatherNames[1], kGatherNames[2], kGatherNames[3]);
  auto row = [&](const std::string& name, const ClassSum& s) {
    const double k = double(std::max<size_t>(1, s.texels));
    std::printf("  %-36s %6.1f%% %7.1f%% %8.1f%% %7.1f%% %6.1f%% %+6.1f%% |         %6.1f%% "
                "%6.1f%% %6.1f%% %6.1f%%\n",
                name.c_str(), 100.0 * double(s.texels) / double(std::max<size_t>(1, n)),
                100.0 * s.e2 / tot, 100.0 * s.noise2 / totNoise,
                100.0 * (s.e2 - s.noise2) / std::max(all.e2 - all.noise2, 1e-30), 100.0 * std::sqrt(s.e2 / k),
                100.0 * s.signedSum / k, 100.0 * std::sqrt(s.alt2[0] / k),
                100.0 * std::sqrt(s.alt2[1] / k), 100.0 * std::sqrt(s.alt2[2] / k),
                100.0 * std::sqrt(s.alt2[3] / k));
  };
  row("all", all);
  row("all, each texel's e² capped at 1", capped);
  for (const auto& [name, s] : classes) row(name, s);
}

}  // namespace afterglow::bench
