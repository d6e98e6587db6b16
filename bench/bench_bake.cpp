// afterglow_bench accuracy: one bake against the reference path tracer, direct and indirect
// light apart, with any bake setting changed from the command line; a tool for tuning the
// precompute (afterglow_bench bake prints the figures with the default settings).
//   afterglow_bench accuracy [SCENE] [--texels-per-unit N | --atlas-size N]
//       [--indirect-texels-per-unit N] [--spp N]
//       [--stride N] [--threads N] [--quality draft|default|high] [--texel-rays N]
//       [--near-rays N] [--near-distance X] [--near-field X] [--block-distance X]
//       [--cluster-size M] [--cluster-texels N] [--adaptive-scale X] [--distance-ratio X] [--min-texels N]
//       [--far-levels N] [--far-scale X] [--far-distance X] [--shared-far-span N] [--shared-far-points X]
//       [--filter-passes N] [--filter-reach X] [--filter-angle DEG] [--filter-light-ratio R]
//       [--filter-noise-sigmas S]
//       [--far-light-ratio R] [--shared-far-light-ratio R] [--no-light-match] [--min-weight W]
//       [--light-samples N] [--emissive-samples N]
//       [--penumbra-samples N] [--worst N [--direct]] [--repeat N] [--single-sided-emission]
//       [--reference-cache FILE] [--breakdown RAYS]
// SCENE defaults to the Cornell box of ../shared/scenes; --spp 0 only times the bake; --repeat
// bakes N times and reports the fastest (for profiling and best-of-N timings); --reference-cache
// keeps the reference in FILE and reuses it while the texels stay the same (reference_cache.h);
// --breakdown prints where the indirect error sits, by class of texel
// (bench_accuracy_breakdown.cpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "afterglow/baker/bake.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/core/parallel.h"
#include "bench_accuracy_breakdown.h"
#include "bench_common.h"
#include "reference_cache.h"

namespace afterglow::bench {

namespace {

// The `count` texels whose error relative to the reference is largest.
void printWorst(const baker::BakeResult& b, const baker::ReferenceTexels& ref, size_t count,
                bool direct) {
  const std::vector<glm::vec3>& baked = direct ? b.texelDirect : b.texelIndirect;
  const std::vector<glm::vec3>& want = direct ? ref.direct : ref.indirect;
  const std::vector<glm::vec3>& variance = direct ? ref.directVariance : ref.indirectVariance;
  double mean = 0.0;
  for (const glm::vec3& v : want) mean += glm::length(v);
  mean /= double(std::max<size_t>(1, want.size()));
  std::vector<size_t> order(ref.texels.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto error = [&](size_t i) {
    const double scale = std::max(double(glm::length(want[i])), 0.1 * mean);
    return double(glm::length(baked[ref.texels[i]] - want[i])) / scale;
  };
  std::sort(order.begin(), order.end(), [&](size_t a, size_t c) { return error(a) > error(c); });
  std::printf("worst %s texels (relative error, bake, reference ± its noise):\n",
              direct ? "direct" : "indirect");
  for (size_t k = 0; k < count && k < order.size(); ++k) {
    const size_t i = order[k];
    const uint32_t t = ref.texels[i];
    const glm::vec3 p = b.texels.position[t], n = b.texels.normal[t];
    std::printf("  texel %6u at (%.3f %.3f %.3f) n (%.2f %.2f %.2f) cluster %u: %.3f, %.5f vs "
                "%.5f ± %.5f\n",
                t, p.x, p.y, p.z, n.x, n.y, n.z,
                // With an indirect grid the clusters are the grid's texels'.
                t < b.clusters.texelCluster.size() && !b.transport.lightmap.active()
                    ? b.clusters.texelCluster[t]
                    : runtime::kNoTexel,
                error(i),
                glm::length(baked[t]), glm::length(want[i]), std::sqrt(variance[i].x));
  }
}

}  // namespace

int benchAccuracy(int argc, char** argv) {
  std::string scenePath =
      std::string(AFTERGLOW_SHARED_DIR) + "/scenes/cornell_box_mcguire/CornellBox-Original.gltf";
  float texelsPerUnit = 0.0f, indirectTexelsPerUnit = 0.0f;
  int atlasSize = 256, threads = 2, spp = 16384, stride = 32, worst = 0, repeat = 1;
  int breakdownRays = 0;
  bool worstDirect = false, singleSidedEmission = false;
  std::string referenceCache;
  baker::BakeOptions options;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() { return i + 1 < argc ? std::atof(argv[++i]) : 0.0; };
    if (arg == "--texels-per-unit") texelsPerUnit = float(next()), atlasSize = 0;
    else if (arg == "--atlas-size") atlasSize = int(next());
    else if (arg == "--indirect-texels-per-unit") indirectTexelsPerUnit = float(next());
    else if (arg == "--threads") threads = int(next());
    else if (arg == "--spp") spp = int(next());
    else if (arg == "--stride") stride = int(next());
    else if (arg == "--worst") worst = int(next());
    else if (arg == "--repeat") repeat = std::max(1, int(next()));
    else if (arg == "--direct") worstDirect = true;
    else if (arg == "--breakdown") breakdownRays = int(next());
    else if (arg == "--single-sided-emission") singleSidedEmission = true;
    else if (arg == "--reference-cache" && i + 1 < argc) referenceCache = argv[++i];
    else if (arg == "--quality" && i + 1 < argc)
      options = baker::bakePreset(qualityNamed(argv[++i]));
    else if (arg == "--texel-rays") options.links.texelRays = int(next());
    else if (arg == "--near-rays") options.links.nearRays = int(next());
    else if (arg == "--near-distance") options.links.nearDistance = float(next());
    else if (arg == "--near-field") options.links.nearField = float(next());
    else if (arg == "--block-distance") options.links.blockDistance = float(next());
    else if (arg == "--cluster-size") options.clusters.clusterSize = float(next());
    else if (arg == "--cluster-texels") options.clusters.clusterTexels = float(next());
    else if (arg == "--adaptive-scale") options.clusters.adaptiveScale = float(next());
    else if (arg == "--distance-ratio") options.clusters.maxDistanceRatio = float(next());
    else if (arg == "--min-texels") options.clusters.minTexels = int(next());
    else if (arg == "--far-levels") options.clusters.farLevels = int(next());
    else if (arg == "--far-scale") options.clusters.farScale = float(next());
    else if (arg == "--far-distance") options.links.farDistance = float(next());
    else if (arg == "--shared-far-span") options.links.sharedFarSpan = int(next());
    else if (arg == "--shared-far-points") options.links.sharedFarPoints = float(next());
    else if (arg == "--filter-passes") options.links.filterPasses = int(next());
    else if (arg == "--min-weight") options.links.minWeight = float(next());
    else if (arg == "--filter-reach") options.links.filterReach = float(next());
    else if (arg == "--filter-angle") options.links.filterMaxAngleDeg = float(next());
    else if (arg == "--filter-light-ratio") options.links.filterLightRatio = float(next());
    else if (arg == "--filter-noise-sigmas") options.links.filterNoiseSigmas = float(next());
    else if (arg == "--far-light-ratio") options.links.farLightRatio = float(next());
    else if (arg == "--shared-far-light-ratio") options.links.sharedFarLightRatio = float(next());
    else if (arg == "--refine-error") options.links.refineError = float(next());
    else if (arg == "--refine-rays") options.links.refineRays = int(next());
    else if (arg == "--albedo-detail") options.links.albedoDetail = float(next());
    else if (arg == "--no-light-match") options.links.lightMatch = false;
    else if (arg == "--light-samples") options.direct.lightSamples = int(next());
    else if (arg == "--emissive-samples") options.direct.emissiveSamples = int(next());
    else if (arg == "--penumbra-samples") options.direct.penumbraSamples = int(next());
    else if (arg.rfind("--", 0) == 0) return fail("accuracy: unknown option " + arg);
    else scenePath = arg;
  }
  setThreadCount(threads);
  Result<scenes::Scene> loaded = loadBenchScene(scenePath);
  if (!loaded) return fail(loaded.message());
  scenes::Scene& scene = loaded.value();
  if (singleSidedEmission)
    for (scenes::Material& m : scene.materials) m.singleSidedEmission = true;
  Result<float> density =
      unwrapForBench(scene, texelsPerUnit > 0.0f ? texelsPerUnit : 16.0f, atlasSize, indirectTexelsPerUnit);
  if (!density) return fail(density.message());

  auto t0 = Clock::now();
  Result<baker::BakeResult> baked = baker::bake(scene, options);
  double bakeSeconds = secondsSince(t0);
  if (!baked) return fail(baked.message());
  for (int run = 1; run < repeat; ++run) {
    t0 = Clock::now();
    Result<baker::BakeResult> again = baker::bake(scene, options);
    const double seconds = secondsSince(t0);
    if (!again) return fail(again.message());
    if (seconds < bakeSeconds) bakeSeconds = seconds, baked = std::move(again);
  }
  const baker::BakeResult& b = baked.value();
  // (Before the reference, which takes a while.)
  if (breakdownRays > 0 && b.transport.lightmap.active())
    return fail("accuracy: --breakdown classes the lightmap's texels by their clusters and gather "
                "points, which an indirect grid does not have (the grid's texels do): give "
                "--indirect-texels-per-unit equal to --texels-per-unit for one resolution");
  std::printf("scene        %s\n", scenePath.c_str());
  size_t valid = 0;
  for (uint8_t v : b.texels.valid) valid += v;
  std::printf("atlas        %dx%d at %.1f texels/m, %u texels (%zu valid), %u gather points, "
              "%u clusters, %zu links\n",
              b.texels.atlases[0].width, b.texels.atlases[0].height,
              double(density.value()), b.texels.size(), valid,
              b.transport.gatherPointCount, b.clusters.size(), b.transport.linkCount());
  std::printf("bake         %.3f s (", bakeSeconds);
  for (const baker::StageTime& s : b.stages) std::printf(" %s %.3f", stageName(s.stage), s.seconds);
  std::printf(" )\n");
  std::printf("rays         %.2f M intersect, %.2f M occluded\n", double(b.raysIntersected) / 1e6,
              double(b.raysOccluded) / 1e6);
  if (spp <= 0) return 0;

  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  if (!tracer) return fail(tracer.message());
  // The texels compared: a fixed pseudo-random 1 in `stride` of the atlas (by a hash of the
  // texel's index), those of them the bake kept. Not every stride-th valid texel: a bake that
  // buries one texel more would shift every later pick, and two bakes would be measured on
  // different texels (the figures move by a few tenths of a percent point from that alone).
  std::vector<uint32_t> subset;
  for (uint32_t t = 0; t < b.texels.size(); ++t) {
    uint32_t h = t * 0x9e3779b1u;
    h ^= h >> 15;
    if (b.texels.valid[t] && h % uint32_t(std::max(1, stride)) == 0) subset.push_back(t);
  }
  baker::ReferenceOptions ro;
  ro.samples = spp;
  t0 = Clock::now();
  const std::string cacheKey = scenePath + (singleSidedEmission ? " single-sided emission" : "");
  Result<baker::ReferenceTexels> ref = referenceWithCache(
      scene, *tracer.value(), b.texels, baker::Environment(), ro, subset, referenceCache, cacheKey);
  if (!ref) return fail("accuracy: " + ref.message());
  const double refSeconds = secondsSince(t0);
  const baker::ReferenceComparison c =
      baker::compareToReference(ref.value(), b.texelDirect, b.texelIndirect);
  std::printf("reference    %zu texels x %d paths in %.1f s\n", c.texels, spp, refSeconds);
  printErrors(c);
  if (worst > 0) printWorst(b, ref.value(), size_t(worst), worstDirect);
  if (breakdownRays > 0)
    printIndirectBreakdown(scene, *tracer.value(), b, ref.value(), breakdownRays);
  return 0;
}

}  // namespace afterglow::bench
