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
#include "afterglow/uv/unwrap.h"
#include "bench_common.h"

namespace afterglow::bench {

int reflectionBakeFigures(const std::string& path, float texelsPerUnit, int threads, int repeat,
                          int probeCount, int resolution) {
  setThreadCount(threads);
  Result<scenes::Scene> loaded = loadBenchScene(path);
  if (!loaded) return fail(loaded.message());
  scenes::Scene scene = std::move(loaded.value());
  uv::UnwrapOptions unwrap;
  unwrap.pack.texelsPerUnit = texelsPerUnit;
  Result<uv::UnwrapResult> unwrapped = uv::unwrap(scene, unwrap);
  if (!unwrapped) return fail(unwrapped.message());
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
    if (s.name == "reflection capture") captureSeconds = s.seconds;
    if (s.name == "reflection passes") passSeconds = s.seconds;
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
  // A full round (every probe's pass 0, then its bounces), per unit; and the heaviest unit, a
  // bounce pass (its texels look the previous pass's probes up), timed in its two halves below.
  double roundMs = 1e30;
  int units = 1;
  for (int r = 0; r < std::max(1, repeat / 3); ++r) {
    const runtime::UpdateStats s = rt->updateReflectionProbes(-1);
    roundMs = std::min(roundMs, s.reflectionMilliseconds);
    units = std::max(1, s.reflectionPasses);
  }
  const double unitMs = roundMs / double(units);
  std::vector<std::vector<glm::vec3>> atlases(size_t(rt->atlasCount()));
  for (int a = 0; a < rt->atlasCount(); ++a) rt->readAtlas(a, atlases[size_t(a)]);
  std::vector<runtime::CubemapChain> chains;
  for (int p = 0; p < rt->reflectionProbeCount(); ++p) chains.push_back(rt->reflectionChain(p));
  const std::vector<runtime::ReflectionProbeBox> boxes = data.reflections.boxes();
  std::vector<runtime::ShL2> sh;
  std::vector<runtime::BorderedChain> bordered;
  for (const runtime::CubemapChain& c : chains) {
    sh.push_back(runtime::chainIrradianceSh(c));
    bordered.push_back(runtime::withBorders(c));
  }
  const runtime::ReflectionLighting lighting{&boxes,  &chains, &rt->dfgTable(), runtime::kDfgSize,
                                             &sh, &bordered};
  std::vector<runtime::ReflectionShadingSetup> setups;
  for (int p = 0; p < probeCount; ++p)
    setups.push_back(runtime::prepareReflectionShading(rt->data(), size_t(p), rt->dfgTable(),
                                                       runtime::kDfgSize));
  // The slowest probe's bounce pass (probes inside several boxes blend several lookups).
  double shadeMs = 0.0, prefilterMs = 1e30;
  for (int p = 0; p < probeCount; ++p) {
    double best = 1e30;
    for (int r = 0; r < std::max(1, repeat / 3); ++r) {
      auto s0 = Clock::now();
      const runtime::Cubemap cube =
          runtime::shadeReflectionCapture(rt->data(), size_t(p), atlases, &lighting, &setups[size_t(p)]);
      best = std::min(best, 1e3 * secondsSince(s0));
      s0 = Clock::now();
      const runtime::CubemapChain chain = runtime::reflectionChain(cube);
      prefilterMs = std::min(prefilterMs, 1e3 * secondsSince(s0));
    }
    shadeMs = std::max(shadeMs, best);
  }

  std::printf("reflection probes  %s at %.3g texels/m, %d probes of %d², %d threads for the "
              "bake, 1 for the runtime\n",
              path.c_str(), double(texelsPerUnit), probeCount, resolution, threads);
  const double capturePer = captureSeconds / double(probeCount);
  std::printf("  capture      %.3f s per probe (%.2f s for %d, of a %.1f s bake; the bake's "
              "passes %.2f s)   target <= 0.2 s: %s\n",
              capturePer, captureSeconds, probeCount, bakeSeconds, passSeconds,
              mark(capturePer <= 0.2));
  const double heaviestMs = shadeMs + prefilterMs;
  std::printf("  runtime      one probe's update (a bounce pass) %.2f ms: capture pass %.2f ms + "
              "prefilter %.2f ms   target <= 20 ms: %s\n",
              heaviestMs, shadeMs, prefilterMs, mark(heaviestMs <= 20.0));
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
