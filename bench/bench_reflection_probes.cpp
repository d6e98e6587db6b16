// afterglow_bench reflection's figures of a bake (bench_reflection.cpp reads the options): on
// Sponza-sun at 4 texels per metre by default, with `--probes` probes of `--resolution`² along
// the level's long axis at a fifth of its height, their boxes fitted:
//   - the capture (ray tracing and hit records) per probe (target <= 0.2 s);
//   - the runtime's update of one probe on one thread: one capture pass (re-shading every
//     texel from the lightmaps and the previous pass's probes) and its GGX prefilter
//     (target <= 20 ms for 128²);
//   - the probes' share of the transport.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "afterglow/baker/bake.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/runtime/transport_file.h"
#include "bench_common.h"

namespace afterglow::bench {

int reflectionBakeFigures(const std::string& path, float texelsPerUnit, int threads, int repeat,
                          int probeCount, int resolution) {
  setThreadCount(threads);
  Result<scenes::Scene> loaded = loadBenchScene(path);
  if (!loaded) return fail(loaded.message());
  scenes::Scene scene = std::move(loaded.value());
  if (Result<float> density = unwrapForBench(scene, texelsPerUnit); !density)
    return fail(density.message());
  const scenes::Bounds bounds = scene.bounds();
  const glm::vec3 size = bounds.size();
  const int longAxis = size.x >= size.z ? 0 : 2;
  for (int k = 0; k < probeCount; ++k) {
    glm::vec3 p = bounds.min + size * glm::vec3(0.5f, 0.2f, 0.5f);
    p[longAxis] = bounds.min[longAxis] + size[longAxis] * (float(k) + 0.5f) / float(probeCount);
    scenes::ReflectionProbe probe;
    probe.name = "bench" + std::to_string(k);
    probe.transform[3] = glm::vec4(p, 1.0f);
    probe.resolution = resolution;
    scene.reflectionProbes.push_back(probe);
  }

  baker::BakeOptions options;  // no light probes: the figures are the reflection probes'
  const auto t0 = Clock::now();
  Result<baker::BakeResult> baked = baker::bake(scene, options);
  const double bakeSeconds = secondsSince(t0);
  if (!baked) return fail(baked.message());
  const baker::BakeResult& b = baked.value();
  double captureSeconds = 0.0, passSeconds = 0.0;
  for (const baker::StageTime& s : b.stages) {
    if (s.stage == Stage::ReflectionCapture) captureSeconds = s.seconds;
    if (s.stage == Stage::ReflectionPasses) passSeconds = s.seconds;
  }
  const runtime::TransportData& data = b.transport;
  const size_t fileBytes = runtime::serializeTransport(data).size();
  const size_t reflectionBytes = data.reflectionBytes();

  // The runtime on one thread: one unit (a capture pass and its prefilter) at a time, and the
  // two halves apart.
  std::string error;
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::fromData(data, &error);
  if (!rt) return fail(error);
  rt->update();
  // A full round (every probe's pass 0, then its bounces), per unit; then one unit a call, as
  // an engine updates one probe a frame: the heaviest unit (a bounce pass of a probe inside
  // several boxes, whose texels blend several probes) is the figure.
  double roundMs = 1e30;
  int units = 1;
  for (int r = 0; r < std::max(1, repeat / 3); ++r) {
    const runtime::UpdateStats s = rt->updateReflectionProbes(-1);
    roundMs = std::min(roundMs, s.reflectionMilliseconds);
    units = std::max(1, s.reflectionPasses);
  }
  const double unitMs = roundMs / double(units);
  std::vector<double> bestUnitMs(size_t(units), 1e30);
  for (int r = 0; r < repeat; ++r)
    for (int u = 0; u < units; ++u) {
      const runtime::UpdateStats s = rt->updateReflectionProbes(1);
      bestUnitMs[size_t(u)] = std::min(bestUnitMs[size_t(u)], s.reflectionMilliseconds);
    }
  const size_t heaviest = size_t(std::max_element(bestUnitMs.begin(), bestUnitMs.end()) -
                                 bestUnitMs.begin());
  const double heaviestMs = bestUnitMs[heaviest];
  // That unit's two halves apart: its capture pass and its prefilter.
  const size_t heavyProbe = heaviest % size_t(probeCount);
  const bool heavyBounce = heaviest >= size_t(probeCount);
  std::vector<std::vector<glm::vec3>> atlases(size_t(rt->atlasCount()));
  for (int a = 0; a < rt->atlasCount(); ++a) rt->readAtlas(a, atlases[size_t(a)]);
  std::vector<runtime::ProbeLight> lights;
  for (int p = 0; p < rt->reflectionProbeCount(); ++p)
    lights.push_back(runtime::probeLight(rt->reflectionChain(p)));
  const std::vector<runtime::ReflectionProbeBox> boxes = data.reflections.boxes();
  const runtime::ReflectionLighting lighting{&boxes, &lights, &rt->dfgTable(), runtime::kDfgSize};
  const runtime::ReflectionShadingSetup setup = runtime::prepareReflectionShading(
      rt->data(), heavyProbe, rt->dfgTable(), runtime::kDfgSize);
  double shadeMs = 1e30, prefilterMs = 1e30;
  for (int r = 0; r < std::max(1, repeat / 3); ++r) {
    auto s0 = Clock::now();
    const runtime::Cubemap cube = runtime::shadeReflectionCapture(
        rt->data(), heavyProbe, atlases, heavyBounce ? &lighting : nullptr, &setup);
    shadeMs = std::min(shadeMs, 1e3 * secondsSince(s0));
    s0 = Clock::now();
    const runtime::CubemapChain chain = runtime::reflectionChain(cube);
    prefilterMs = std::min(prefilterMs, 1e3 * secondsSince(s0));
  }

  std::printf("reflection probes  %s at %.3g texels/m, %d probes of %d², %d threads for the "
              "bake, 1 for the runtime\n",
              path.c_str(), double(texelsPerUnit), probeCount, resolution, threads);
  const double capturePer = captureSeconds / double(probeCount);
  std::printf("  capture      %.3f s per probe (%.2f s for %d, of a %.1f s bake; the bake's "
              "passes %.2f s)   target <= 0.2 s: %s\n",
              capturePer, captureSeconds, probeCount, bakeSeconds, passSeconds,
              mark(capturePer <= 0.2));
  std::printf("  runtime      the heaviest unit, probe %zu's %s, one a call: %.2f ms (capture pass "
              "%.2f ms + prefilter %.2f ms, timed apart)   target <= 20 ms: %s\n",
              heavyProbe, heavyBounce ? "bounce pass" : "pass 0", heaviestMs, shadeMs,
              prefilterMs, mark(heaviestMs <= 20.0));
  std::printf("               its static setup %.1f MB (%zu taps for %zu texels)\n",
              double(setup.bytes()) / 1e6, setup.taps.size(), setup.specular.size());
  std::printf("               a full round %.1f ms for %d units (%d probes x %u passes): %.2f ms "
              "per unit\n",
              roundMs, units, probeCount, data.reflections.bounces + 1, unitMs);
  std::printf("  transport    reflection probes %.2f MB of %.2f MB (%.1f%%), %.2f MB per probe\n",
              double(reflectionBytes) / 1e6, double(fileBytes) / 1e6,
              100.0 * double(reflectionBytes) / double(fileBytes),
              double(reflectionBytes) / 1e6 / double(probeCount));
  return 0;
}

}  // namespace afterglow::bench
