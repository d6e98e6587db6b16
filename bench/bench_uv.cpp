// afterglow_bench uv: the lightmap-UV figures of issue 2.
//   afterglow_bench uv [SCENE] [--texels-per-unit 16] [--threads 2]
// Loads SCENE (default ../shared/scenes/sponza/Sponza.gltf), unwraps it, prints timings and
// quality metrics next to their targets, then unwraps twice more (same threads, then 1 thread)
// and reports whether the lightmap UVs came out bit-identical.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "afterglow/core/parallel.h"
#include "afterglow/uv/unwrap.h"
#include "bench_common.h"

namespace afterglow::bench {

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: afterglow_bench uv [SCENE] [--texels-per-unit N] [--threads N]\n"
               "  SCENE defaults to %s/scenes/sponza/Sponza.gltf; builtin:cornell and\n"
               "  builtin:furnace work too\n",
               AFTERGLOW_SHARED_DIR);
  return 2;
}

// True when both unwrapped scenes have the same meshes, uv1 bits and lightmap locations.
bool identical(const scenes::Scene& a, const scenes::Scene& b) {
  if (a.meshes.size() != b.meshes.size() || a.instances.size() != b.instances.size()) return false;
  for (size_t i = 0; i < a.instances.size(); ++i) {
    const scenes::LightmapLocation &la = a.instances[i].lightmap, &lb = b.instances[i].lightmap;
    if (a.instances[i].mesh != b.instances[i].mesh || la.atlas != lb.atlas ||
        la.width != lb.width || la.height != lb.height)
      return false;
  }
  for (size_t m = 0; m < a.meshes.size(); ++m) {
    const auto &pa = a.meshes[m].primitives, &pb = b.meshes[m].primitives;
    if (pa.size() != pb.size()) return false;
    for (size_t p = 0; p < pa.size(); ++p) {
      if (pa[p].uv1.size() != pb[p].uv1.size() || pa[p].indices != pb[p].indices) return false;
      if (!pa[p].uv1.empty() &&
          std::memcmp(pa[p].uv1.data(), pb[p].uv1.data(), pa[p].uv1.size() * sizeof(glm::vec2)))
        return false;
    }
  }
  return true;
}

}  // namespace

int benchUv(int argc, char** argv) {
  std::string scenePath = std::string(AFTERGLOW_SHARED_DIR) + "/scenes/sponza/Sponza.gltf";
  float texelsPerUnit = 16.0f;
  int threads = 2;
  for (int i = 2; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--texels-per-unit" && i + 1 < argc)
      texelsPerUnit = std::strtof(argv[++i], nullptr);
    else if (arg == "--threads" && i + 1 < argc)
      threads = std::atoi(argv[++i]);
    else if (arg.rfind("--", 0) == 0 || arg == "-h")
      return usage();
    else
      scenePath = arg;
  }
  if (!(texelsPerUnit > 0.0f) || threads < 1) return usage();

  auto t0 = Clock::now();
  Result<scenes::Scene> loaded = loadBenchScene(scenePath, false);
  double loadTime = secondsSince(t0);
  if (!loaded) {
    std::fprintf(stderr, "afterglow_bench: %s\n", loaded.message().c_str());
    return 1;
  }
  const scenes::Scene original = std::move(loaded.value());
  std::printf("scene              %s\n", scenePath.c_str());
  std::printf("input              %zu instances, %zu meshes, %zu unique / %zu instanced triangles\n",
              original.instances.size(), original.meshes.size(), original.meshTriangleCount(),
              original.instancedTriangleCount());
  std::printf("load               %.2f s (textures not decoded)\n", loadTime);

  uv::UnwrapOptions options;
  options.pack.texelsPerUnit = texelsPerUnit;
  auto run = [&](int threadCount, scenes::Scene* scene, double* seconds) {
    setThreadCount(threadCount);
    *scene = original;
    auto start = Clock::now();
    Result<uv::UnwrapResult> r = uv::unwrap(*scene, options);
    *seconds = secondsSince(start);
    if (!r) {
      std::fprintf(stderr, "afterglow_bench: %s\n", r.message().c_str());
      std::exit(1);
    }
    return std::move(r.value());
  };

  scenes::Scene first;
  double total = 0.0;
  uv::UnwrapResult result = run(threads, &first, &total);
  const uv::Metrics& m = result.metrics;
  const uv::UnwrapTimings& t = result.timings;
  std::printf("texels per unit    %g, threads %d\n", double(texelsPerUnit), threads);
  std::printf("unwrap             %.2f s (charts %.2f, pack %.2f, apply %.2f, metrics %.2f)   "
              "target <= 5 s at 2 threads: %s   [xatlas 9.6 s]\n",
              total, t.charts, t.pack, t.apply, t.metrics, mark(total <= 5.0));
  std::printf("unwrap w/o metrics %.2f s\n", total - t.metrics);
  std::printf("charts             %zu   [xatlas 10,192]\n", m.chartCount);
  std::printf("atlases            %zu:", m.atlases.size());
  for (const uv::AtlasMetrics& a : m.atlases)
    std::printf(" %dx%d (%.3f)", a.width, a.height, a.utilization);
  std::printf("\n");
  std::printf("utilisation        %.3f   target >= 0.88: %s   [xatlas 0.91]\n", m.utilization,
              mark(m.utilization >= 0.88));
  std::printf("overlapping texels %zu   target 0: %s\n", m.overlappingTexels,
              mark(m.overlappingTexels == 0));
  std::printf("padding violations %zu   target 0: %s\n", m.paddingViolations,
              mark(m.paddingViolations == 0));
  std::printf("outside [0,1]      %zu triangles\n", m.outOfRangeTriangles);
  std::printf("stretch L2         %.4f (worst chart %.3f)   target <= 1.05: %s\n", m.stretchL2,
              m.stretchL2Max, mark(m.stretchL2 <= 1.05));
  std::printf("flipped triangles  %zu\n", m.flippedTriangles);
  std::printf("density spread     %.4f (%.2f to %.2f texels/m)\n", m.densitySpread, m.densityMin,
              m.densityMax);
  for (const std::string& w : result.warnings) std::printf("warning            %s\n", w.c_str());

  scenes::Scene second, single;
  double secondTime = 0.0, singleTime = 0.0;
  run(threads, &second, &secondTime);
  run(1, &single, &singleTime);
  std::printf("second run         %.2f s, uv1 bit-identical: %s\n", secondTime,
              identical(first, second) ? "yes" : "NO");
  std::printf("1 thread           %.2f s, uv1 bit-identical: %s\n", singleTime,
              identical(first, single) ? "yes" : "NO");
  return 0;
}

}  // namespace afterglow::bench
