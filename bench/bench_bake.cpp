// afterglow_bench accuracy: a bake against the reference path tracer, direct and indirect light
// apart, with the time of each.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <cmath>
#include <string>

#include "afterglow/baker/bake.h"
#include "afterglow/baker/raytracer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/uv/unwrap.h"
#include "bench_common.h"

namespace afterglow::bench {

int benchAccuracy(int argc, char** argv) {
  std::string scenePath =
      std::string(AFTERGLOW_SHARED_DIR) + "/scenes/cornell_box_mcguire/CornellBox-Original.gltf";
  float texelsPerUnit = 40.0f;
  int threads = 2, spp = 4096, stride = 16;
  baker::BakeOptions options;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() { return i + 1 < argc ? std::atof(argv[++i]) : 0.0; };
    if (arg == "--texels-per-unit") texelsPerUnit = float(next());
    else if (arg == "--threads") threads = int(next());
    else if (arg == "--spp") spp = int(next());
    else if (arg == "--stride") stride = int(next());
    else if (arg == "--texel-rays") options.links.texelRays = int(next());
    else if (arg == "--cluster-rays") options.links.clusterRays = int(next());
    else if (arg == "--cluster-size") options.clusters.clusterSize = float(next());
    else if (arg == "--adaptive-scale") options.clusters.adaptiveScale = float(next());
    else if (arg == "--distance-ratio") options.clusters.maxDistanceRatio = float(next());
    else if (arg == "--filter-passes") options.links.filterPasses = int(next());
    else if (arg == "--min-texels") options.clusters.minTexels = int(next());
    else if (arg == "--emissive-samples") options.direct.emissiveSamples = int(next());
    else if (arg == "--light-samples") options.direct.lightSamples = int(next());
    else if (arg.rfind("--", 0) == 0) {
      std::fprintf(stderr, "accuracy: unknown option %s\n", arg.c_str());
      return 2;
    } else scenePath = arg;
  }
  setThreadCount(threads);
  Result<scenes::Scene> loaded = loadBenchScene(scenePath);
  if (!loaded) return fail(loaded.message());
  scenes::Scene& scene = loaded.value();
  if (std::getenv("AG_ONESIDED"))
    for (scenes::Material& m : scene.materials)
      if (m.emissive()) m.doubleSided = false;
  uv::UnwrapOptions unwrapOptions;
  unwrapOptions.pack.texelsPerUnit = texelsPerUnit;
  Result<uv::UnwrapResult> unwrapped = uv::unwrap(scene, unwrapOptions);
  if (!unwrapped) return fail(unwrapped.message());

  auto t0 = Clock::now();
  Result<baker::BakeResult> baked = baker::bake(scene, options);
  const double bakeSeconds = secondsSince(t0);
  if (!baked) return fail(baked.message());
  const baker::BakeResult& b = baked.value();
  std::printf("scene        %s\n", scenePath.c_str());
  std::printf("atlas        %dx%d, %u texels, %u clusters, %zu texel links, %zu cluster links\n",
              b.texels.atlases[0].width, b.texels.atlases[0].height, b.texels.size(),
              b.clusters.size(), b.transport.texelLinks.size(), b.transport.clusterLinks.size());
  std::printf("bake         %.3f s (", bakeSeconds);
  for (const baker::StageTime& s : b.stages) std::printf(" %s %.3f", s.name.c_str(), s.seconds);
  std::printf(" )\n");

  Result<std::unique_ptr<baker::RayTracer>> tracer = baker::RayTracer::build(scene);
  if (!tracer) return fail(tracer.message());
  std::vector<uint32_t> subset;
  for (uint32_t t = 0; t < b.texels.size(); t += uint32_t(std::max(1, stride)))
    if (b.texels.valid[t]) subset.push_back(t);
  baker::Environment env;
  baker::ReferenceOptions ro;
  ro.samples = spp;
  t0 = Clock::now();
  Result<baker::ReferenceTexels> ref =
      baker::referenceTexels(scene, *tracer.value(), b.texels, env, ro, subset);
  const double refSeconds = secondsSince(t0);
  if (!ref) return fail(ref.message());
  if (std::getenv("AG_NOGAP")) {
    baker::ReferenceTexels& r = ref.value();
    baker::ReferenceTexels kept;
    for (size_t i = 0; i < r.texels.size(); ++i) {
      const glm::vec3 p = b.texels.position[r.texels[i]];
      if (p.y > 1.98f && std::abs(p.x) < 0.27f && std::abs(p.z) < 0.23f) continue;
      kept.texels.push_back(r.texels[i]);
      kept.direct.push_back(r.direct[i]);
      kept.indirect.push_back(r.indirect[i]);
      kept.directVariance.push_back(r.directVariance[i]);
      kept.indirectVariance.push_back(r.indirectVariance[i]);
    }
    r = kept;
  }
  const baker::ReferenceComparison c =
      baker::compareToReference(ref.value(), b.texelDirect, b.texelIndirect);
  std::printf("reference    %zu texels x %d paths in %.1f s\n", c.texels, spp, refSeconds);
  auto line = [](const char* name, const baker::ErrorStats& e) {
    std::printf("%-12s rel. RMSE %.4f  bias %+.4f  (reference noise %.4f, mean %.5f)\n", name,
                e.relativeRmse, e.bias, e.referenceNoise, e.referenceMean);
  };
  line("direct", c.direct);
  line("indirect", c.indirect);
  line("total", c.total);
  if (const char* dbg = std::getenv("AG_TEXEL")) {
    const uint32_t t = uint32_t(std::atoi(dbg));
    runtime::Solver solver(b.transport);
    solver.solve();
    const auto& R = solver.clusterReflected();
    const auto& L = b.transport.texelLinks;
    std::printf("texel %u cluster %u back %u\n", t, b.clusters.texelCluster[t], b.clusters.texelBackCluster[t]);
    for (uint32_t k = L.rowStart[t]; k < L.rowStart[t + 1]; ++k) {
      const uint32_t c = L.target[k];
      const glm::vec3 p = b.clusters.position[c], n = b.clusters.normal[c];
      std::printf("  -> cl %u w %.4f R %.5f back %d p (%.3f %.3f %.3f) n (%.2f %.2f %.2f) texels %u\n", c, L.weight[k], R[c].x,
                  int(b.clusters.back[c]), p.x, p.y, p.z, n.x, n.y, n.z, b.clusters.firstTexel[c + 1] - b.clusters.firstTexel[c]);
    }
  }
  if (const char* dbg = std::getenv("AG_CLUSTER")) {
    const uint32_t c0 = uint32_t(std::atoi(dbg));
    runtime::Solver solver(b.transport);
    solver.solve();
    const auto& R = solver.clusterReflected();
    const auto& L = b.transport.clusterLinks;
    std::printf("cluster %u R %.6f direct", c0, R[c0].x);
    for (const auto& src : b.transport.sources) std::printf(" %.6f", src.clusterTransfer[c0]);
    std::printf(" sky %.6f\n", b.transport.clusterSky[c0 * 9]);
    for (uint32_t k = L.rowStart[c0]; k < L.rowStart[c0 + 1]; ++k) {
      const uint32_t c = L.target[k];
      const glm::vec3 p = b.clusters.position[c], n = b.clusters.normal[c];
      if (L.weight[k] * R[c].x < 1e-6f) continue;
      std::printf("  -> cl %u w %.4f R %.5f back %d p (%.3f %.3f %.3f) n (%.2f %.2f %.2f) texels %u\n", c, L.weight[k], R[c].x,
                  int(b.clusters.back[c]), p.x, p.y, p.z, n.x, n.y, n.z, b.clusters.firstTexel[c + 1] - b.clusters.firstTexel[c]);
    }
  }
  if (std::getenv("AG_SLICE")) {
    for (size_t i = 0; i < ref->texels.size(); ++i) {
      const uint32_t t = ref->texels[i];
      const glm::vec3 p = b.texels.position[t];
      if (p.y < 1.98f || std::abs(p.z) > 0.06f) continue;
      std::printf("  slice x %.3f z %.3f bake dir %.4f ind %.4f | ref dir %.4f ind %.4f +- %.4f  h %.3f\n", p.x, p.z,
                  b.texelDirect[t].x, b.texelIndirect[t].x, ref->direct[i].x, ref->indirect[i].x,
                  std::sqrt(ref->indirectVariance[i].x), 0.0);
    }
  }
  if (std::getenv("AG_WORST")) {
    std::vector<size_t> order(ref->texels.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    const bool direct = std::getenv("AG_DIRECT") != nullptr;
    const auto& bv = direct ? b.texelDirect : b.texelIndirect;
    const auto& rv = direct ? ref->direct : ref->indirect;
    const auto& rvar = direct ? ref->directVariance : ref->indirectVariance;
    std::vector<double> rel;
    for (size_t i = 0; i < ref->texels.size(); ++i) {
      const uint32_t t = ref->texels[i];
      const double r = double(rv[i].x + rv[i].y + rv[i].z);
      const double bb = double(bv[t].x + bv[t].y + bv[t].z);
      rel.push_back((bb - r) / std::max(r, 1e-9));
    }
    std::sort(rel.begin(), rel.end());
    std::printf("signed rel error percentiles: 1%% %.3f 5%% %.3f 25%% %.3f 50%% %.3f 75%% %.3f 95%% %.3f 99%% %.3f\n",
                rel[rel.size() / 100], rel[rel.size() / 20], rel[rel.size() / 4], rel[rel.size() / 2],
                rel[rel.size() * 3 / 4], rel[rel.size() * 19 / 20], rel[rel.size() * 99 / 100]);
    auto err = [&](size_t i) {
      const uint32_t t = ref->texels[i];
      if (direct)
        return glm::length(bv[t] - rv[i]) / std::max(0.003f, glm::length(rv[i]));
      if (std::getenv("AG_REL"))
        return glm::length(b.texelIndirect[t] - ref->indirect[i]) / std::max(0.003f, glm::length(ref->indirect[i]));
      return glm::length(b.texelIndirect[t] - ref->indirect[i]);
    };
    std::sort(order.begin(), order.end(), [&](size_t a, size_t c2) { return err(a) > err(c2); });
    for (size_t k = 0; k < 15 && k < order.size(); ++k) {
      const size_t i = order[k];
      const uint32_t t = ref->texels[i];
      const glm::vec3 p = b.texels.position[t], n = b.texels.normal[t];
      std::printf("  texel %6u p (%.3f %.3f %.3f) n (%.2f %.2f %.2f) bake %.4f ref %.4f +- %.4f cl %u\n",
                  t, p.x, p.y, p.z, n.x, n.y, n.z, bv[t].x, rv[i].x,
                  std::sqrt(rvar[i].x), b.clusters.texelCluster[t]);
    }
  }
  return 0;
}

}  // namespace afterglow::bench
