// afterglow_bench probes [SCENE] [--texels-per-unit 4] [--threads 2] [--repeat 5]: the light
// probes' figures issue 14 asks for, on Sponza-sun at 4 texels per metre by default:
//   - placement: time and count with the default settings (target <= 3 s);
//   - the probes' precompute against the whole bake (target <= 20%);
//   - the runtime's probe refresh on one thread, per 10,000 probes (target <= 3 ms);
//   - the probes' share of the transport, bytes per probe.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "afterglow/baker/bake.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/core/parallel.h"
#include "afterglow/probes/placement.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/runtime/transport_file.h"
#include "bench_common.h"

namespace afterglow::bench {

int benchProbes(int argc, char** argv) {
  std::string path = std::string(AFTERGLOW_SHARED_DIR) + "/scenes/sponza/Sponza-sun.gltf";
  float texelsPerUnit = 4.0f;
  int threads = 2, repeat = 5;
  baker::ProbeOptions probeOptions;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() { return i + 1 < argc ? std::atof(argv[++i]) : 0.0; };
    if (arg == "--texels-per-unit") texelsPerUnit = float(next());
    else if (arg == "--threads") threads = int(next());
    else if (arg == "--repeat") repeat = std::max(1, int(next()));
    else if (arg == "--rays-side") probeOptions.raysSide = int(next());
    else if (arg == "--regions-side") probeOptions.binsSide = int(next());
    else if (arg == "--far-distance") probeOptions.farDistance = float(next());
    else if (!arg.empty() && arg[0] != '-') path = arg;
    else
      return fail("unknown option " + arg +
                  " (--texels-per-unit N, --threads N, --repeat N, --rays-side N, --regions-side N, "
                  "--far-distance X)");
  }
  setThreadCount(threads);
  Result<scenes::Scene> loaded = loadBenchScene(path);
  if (!loaded) return fail(loaded.message());
  scenes::Scene scene = std::move(loaded.value());
  if (Result<float> density = unwrapForBench(scene, texelsPerUnit); !density)
    return fail(density.message());

  // Placement as `afterglow bake` does it by default: its own ray tracer, then the tetrahedra.
  auto t0 = Clock::now();
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  if (!tracer) return fail(tracer.message());
  const double tracerSeconds = secondsSince(t0);
  t0 = Clock::now();
  Result<probes::Placement> placed = probes::placeProbes(scene, *tracer.value(), {});
  if (!placed) return fail(placed.message());
  const double placeSeconds = secondsSince(t0);
  t0 = Clock::now();
  Result<runtime::ProbeTetrahedra> mesh = probes::tetrahedralize(placed->positions);
  if (!mesh) return fail(mesh.message());
  const double tetSeconds = secondsSince(t0);
  tracer = Status::error("released");

  baker::BakeOptions options;
  options.probes = mesh.value();
  options.probeOptions = probeOptions;
  t0 = Clock::now();
  Result<baker::BakeResult> baked = baker::bake(scene, options);
  const double bakeSeconds = secondsSince(t0);
  if (!baked) return fail(baked.message());
  const baker::BakeResult& b = baked.value();
  double probeSeconds = 0.0, gatherRate = 0.0, probeRate = 0.0;
  for (const baker::StageTime& s : b.stages) {
    if (s.stage == Stage::Probes) probeSeconds = s.seconds, probeRate = double(s.rays) / s.seconds / 1e6;
    if (s.stage == Stage::Gather) gatherRate = double(s.rays) / s.seconds / 1e6;
  }
  const size_t count = placed->positions.size();
  const double placementTotal = tracerSeconds + placeSeconds + tetSeconds;

  // The runtime on one thread: the probes' refresh alone, and a one-bounce update with and
  // without them.
  const runtime::TransportData& data = b.transport;
  const size_t fileBytes = runtime::serializeTransport(data).size();
  const size_t probeBytes = data.probeBytes();
  std::string error;
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::fromData(data, &error);
  if (!rt) return fail(error);
  rt->update();
  double refreshMs = 1e30;
  for (int r = 0; r < repeat; ++r) refreshMs = std::min(refreshMs, rt->updateProbes().milliseconds);
  runtime::UpdateOptions one;
  one.maxBounces = 1;
  double withMs = 1e30, withoutMs = 1e30, shareMs = 0.0;
  for (int r = 0; r < repeat; ++r) {
    rt->setLightColor(0, glm::vec3(1.0f, 0.9f - 0.01f * float(r), 0.8f));
    const runtime::UpdateStats s = rt->update(one);
    if (s.milliseconds < withMs) withMs = s.milliseconds, shareMs = s.probeMilliseconds;
  }
  one.probes = false;
  for (int r = 0; r < repeat; ++r) {
    rt->setLightColor(0, glm::vec3(1.0f, 0.8f + 0.01f * float(r), 0.8f));
    withoutMs = std::min(withoutMs, rt->update(one).milliseconds);
  }
  size_t probeLinks = data.probes.links.linkCount();
  const double per10k = refreshMs * 10000.0 / double(std::max<size_t>(1, count));

  std::printf("light probes  %s at %.3g texels/m, %d threads for the bake, 1 for the runtime\n",
              path.c_str(), double(texelsPerUnit), threads);
  std::printf("  placement    %zu probes (spacing %.3g m, %zu refined, %zu moved, %zu rejected) in "
              "%.2f s (ray tracer %.2f s, placement %.2f s, tetrahedra %.2f s for %zu)   target "
              "<= 3 s: %s\n",
              count, double(placed->spacing), placed->refined, placed->moved, placed->rejected,
              placementTotal, tracerSeconds, placeSeconds, tetSeconds, mesh->tetrahedra.size(),
              mark(placementTotal <= 3.0));
  std::printf("  precompute   probes %.2f s of a %.2f s bake: %.1f%%   target <= 20%%: %s\n",
              probeSeconds, bakeSeconds, 100.0 * probeSeconds / bakeSeconds,
              mark(probeSeconds <= 0.2 * bakeSeconds));
  std::printf("               %.1f Mrays/s in the probes' stage, %.1f in the texels' gather\n",
              probeRate, gatherRate);
  std::printf("               with the placement: %.2f s of %.2f s, %.1f%%\n",
              probeSeconds + placementTotal, bakeSeconds + placementTotal,
              100.0 * (probeSeconds + placementTotal) / (bakeSeconds + placementTotal));
  std::printf("  runtime      refresh %.2f ms for %zu probes = %.2f ms per 10,000   target <= 3 ms: "
              "%s\n",
              refreshMs, count, per10k, mark(per10k <= 3.0));
  std::printf("               one-bounce update %.2f ms with the probes (their share %.2f ms), "
              "%.2f ms without\n",
              withMs, shareMs, withoutMs);
  std::printf("  transport    probes %.2f MB of %.2f MB: %.0f bytes per probe (%.0f links, %u "
              "regions)\n",
              double(probeBytes) / 1e6, double(fileBytes) / 1e6,
              double(probeBytes) / double(std::max<size_t>(1, count)),
              double(probeLinks) / double(std::max<size_t>(1, count)), data.probes.bins);
  return 0;
}

}  // namespace afterglow::bench
