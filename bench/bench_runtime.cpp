// afterglow_bench runtime: what an engine pays for relighting (issue 4), single thread, for the
// Cornell box (256² atlas) and Sponza-sun at 4 and 16 texels per metre (bounced light on the
// auto indirect grid, issue 29):
//   - the transport file: size, bytes per texel, load time, memory the loaded runtime holds;
//   - one bounce iteration (Solver::iterate: every gather point's links, then the clusters);
//   - one update() of one bounce after a light colour change (bounce + direct + indirect
//     texels + atlas resolve), what an engine runs per frame; with an indirect grid, the
//     grid's atlases only (the engine composes the lightmap in its shader), and apart the
//     CPU's composition of the whole lightmap;
//   - one update() from scratch to convergence.
//   afterglow_bench runtime [--cornell-only | --sponza-only] [--repeat N]
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <unistd.h>
#include <string>
#include <vector>

#include "afterglow/baker/bake.h"
#include "afterglow/bakefiles/write.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/runtime/transport_file.h"
#include "bench_common.h"

namespace fs = std::filesystem;

namespace afterglow::bench {
namespace {

// The best of `repeat` timings of f(), milliseconds (the least disturbed by the machine).
template <class F>
double bestMs(int repeat, F&& f) {
  double best = 1e30;
  for (int i = 0; i < repeat; ++i) {
    const auto t0 = Clock::now();
    f();
    best = std::min(best, secondsSince(t0) * 1e3);
  }
  return best;
}

int measure(const char* label, scenes::Scene scene, float texelsPerUnit, int atlasSize,
            int repeat, double bounceTargetMs) {
  Result<float> density = unwrapForBench(scene, texelsPerUnit, atlasSize);
  if (!density) return fail(density.message());
  setThreadCount(2);  // the bake may use both cores; the runtime below runs on one
  Result<baker::BakeResult> baked = baker::bake(scene, baker::BakeOptions());
  if (!baked) return fail(baked.message());
  const std::string path =
      (fs::temp_directory_path() / ("afterglow_bench_runtime_" + std::to_string(::getpid()) + ".agt"))
          .string();
  std::string error;
  if (!runtime::saveTransport(baked->transport, path, &error)) return fail(error);
  const runtime::TransportData& t = baked->transport;
  const uint32_t texels = t.texelCount, clusters = t.clusterCount, points = t.gatherPointCount;
  const uint32_t lightmapTexels = t.lightmapTexelCount();
  const size_t layerBytes = t.lightmap.memoryBytes(), directBytes = t.lightmap.directBytes(),
               sources = t.sources.size();
  const bool grid = t.lightmap.active();
  const size_t links = t.linkCount(), sharedLinks = t.sharedFar.linkCount(), shared = t.sharedFar.rows();
  baked = Status::error("released");  // the runtime's memory below is its own

  std::error_code ec;
  const double fileBytes = double(fs::file_size(path, ec));
  auto t0 = Clock::now();
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::load(path, &error);
  const double loadMs = secondsSince(t0) * 1e3;
  if (!rt) return fail(error);
  const double heldBytes = double(rt->data().memoryBytes());
  fs::remove(path, ec);

  // One bounce alone, through a Solver on the runtime's data (what update() runs per pass).
  runtime::Solver solver(rt->data());
  solver.solve();
  const double bounceMs = bestMs(repeat, [&] { solver.iterate(); });
  // A frame: a light colour changes, one bounce, texels and atlases out.
  int frame = 0;
  runtime::UpdateOptions one;
  one.maxBounces = 1;
  one.composeLightmap = false;  // with one resolution this changes nothing
  auto change = [&] {
    if (rt->lightCount() > 0)
      rt->setLightColor(0, glm::vec3(1.0f, 0.5f + 0.05f * float(frame++ % 10), 0.3f));
    else
      rt->setSky(glm::vec3(0.1f * float(frame++ % 10)));
  };
  const double frameMs = bestMs(repeat, [&] {
    change();
    rt->update(one);
  });
  // The same with the lightmap composed on the CPU; its share apart.
  runtime::UpdateOptions composed = one;
  composed.composeLightmap = true;
  double composeMs = 1e30;
  const double composedFrameMs = bestMs(repeat, [&] {
    change();
    composeMs = std::min(composeMs, rt->update(composed).composeMilliseconds);
  });
  runtime::UpdateOptions full;
  full.fromScratch = true;
  runtime::UpdateStats stats;
  const double fullMs = bestMs(std::max(1, repeat / 4), [&] { stats = rt->update(full); });

  std::printf("%s\n", label);
  std::printf("  texels       %u, %u gather points, %u clusters, %zu links (%zu of them in %zu "
              "shared far fields)\n",
              texels, points, clusters, links, sharedLinks, shared);
  std::printf("  transport    %.1f MB, %.0f bytes a texel   target <= 200: %s\n", fileBytes / 1e6,
              fileBytes / double(texels), mark(fileBytes / double(texels) <= 200.0));
  std::printf("  load         %.1f ms, %.1f MB of transport in memory\n", loadMs, heldBytes / 1e6);
  if (bounceTargetMs > 0.0)
    std::printf("  one bounce   %.2f ms (%.2f ns a link)   target <= %.0f ms: %s\n", bounceMs,
                bounceMs * 1e6 / double(std::max<size_t>(1, links)), bounceTargetMs,
                mark(bounceMs <= bounceTargetMs));
  else
    std::printf("  one bounce   %.2f ms (%.2f ns a link)\n", bounceMs,
                bounceMs * 1e6 / double(std::max<size_t>(1, links)));
  if (grid) {
    std::printf("  lightmap     %u texels over an indirect grid of %u: layers %.1f MB (direct light "
                "%.2f bytes a texel a source, %zu sources)\n",
                lightmapTexels, texels, double(layerBytes) / 1e6,
                double(directBytes) / double(lightmapTexels) / double(std::max<size_t>(1, sources)),
                sources);
    std::printf("  frame        %.2f ms: light change + one bounce + the grid's atlases (what an "
                "engine uploads; it composes in its shader)\n",
                frameMs);
    std::printf("  composed     %.2f ms with the whole lightmap composed on the CPU (of which "
                "composition %.2f ms)\n",
                composedFrameMs, composeMs);
  } else {
    std::printf("  frame        %.2f ms: light change + one bounce + texels + atlases\n", frameMs);
  }
  std::printf("  converged    %.1f ms from scratch (%d bounces)\n", fullMs, stats.bounces);
  return 0;
}

}  // namespace

int benchRuntime(int argc, char** argv) {
  bool cornell = true, sponza = true;
  int repeat = 20;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--cornell-only") sponza = false;
    else if (arg == "--sponza-only") cornell = false;
    else if (arg == "--repeat" && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
    else return fail("runtime: unknown option " + arg);
  }
  std::printf("afterglow_bench runtime: single-thread relighting (best of %d)\n", repeat);
  if (cornell) {
    const std::string path =
        std::string(AFTERGLOW_SHARED_DIR) + "/scenes/cornell_box_mcguire/CornellBox-Original.gltf";
    Result<scenes::Scene> scene = loadBenchScene(fs::exists(path) ? path : "builtin:cornell");
    if (!scene) return fail(scene.message());
    if (int s = measure("Cornell box (256² atlas)", std::move(scene.value()), 0.0f, 256, repeat, 0.0))
      return s;
  }
  if (sponza) {
    const std::string path = std::string(AFTERGLOW_SHARED_DIR) + "/scenes/sponza/Sponza-sun.gltf";
    if (!fs::exists(path)) {
      std::printf("Sponza-sun: %s is absent, skipped\n", path.c_str());
      return 0;
    }
    Result<scenes::Scene> scene = loadBenchScene(path);
    if (!scene) return fail(scene.message());
    if (int s = measure("Sponza-sun at 4 texels/m", scene.value(), 4.0f, 0, repeat, 3.0))
      return s;
    if (int s = measure("Sponza-sun at 16 texels/m", std::move(scene.value()), 16.0f, 0, repeat,
                        3.0))
      return s;
  }
  return 0;
}

}  // namespace afterglow::bench
