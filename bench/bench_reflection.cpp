// afterglow_bench reflection [SCENE] [--repeat 10] [--sampled] [--prefilter-only] [--texels-per-unit
// 4] [--threads 2] [--probes 4] [--resolution 128]: the reflection probes' figures issue 15
// asks for, on one thread: the prefilter below, then a bake's (bench_reflection_probes.cpp). The runtime recomputes one probe a frame, its cubemap and its GGX
// mip chain together in <= 20 ms; the radiance takes a few ms, so:
//   - the prefilter: a 128² probe's 7-mip chain (prefilter_plan.h) in <= 12 ms (the best of
//     --repeat), with the plan's build time and memory; --sampled also times the sampled path
//     (prefilterChain with kPrefilterSamples, ~2 s) once, for comparison.
// Each group of figures is its own function below; benchReflection only reads the options.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "afterglow/runtime/cubemap.h"
#include "afterglow/runtime/prefilter_plan.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "bench_common.h"

namespace afterglow::bench {
namespace {

// The prefilter of a 128² probe: plan build, memory, and the chain per probe update.
void prefilterFigures(int repeat, bool sampled) {
  const int size = 128;
  // Any content: the plan's work does not depend on it. A sky with a sun, like a probe's.
  runtime::Cubemap source = runtime::makeCubemap(size, glm::vec3(0.2f, 0.3f, 0.5f));
  source.at(runtime::kCubeFacePosY, 40, 50) = glm::vec3(5e4f);

  auto t0 = Clock::now();
  const runtime::PrefilterPlan plan = runtime::PrefilterPlan::build(size);
  const double buildSeconds = secondsSince(t0);

  std::vector<runtime::Cubemap> chain;
  std::vector<glm::vec4> scratch;
  double best = 1e30;
  for (int i = 0; i < repeat; ++i) {
    t0 = Clock::now();
    plan.prefilter(source, chain, scratch);
    best = std::min(best, secondsSince(t0) * 1e3);
  }

  std::printf("prefilter    a %d² probe's %d-mip GGX chain, one thread, best of %d\n", size,
              plan.mipCount(), repeat);
  std::printf("  chain        %.2f ms per probe update   target <= 12 ms: %s\n", best,
              mark(best <= 12.0));
  std::printf("  plan         built in %.2f s, %.1f MB, %zu taps (per output texel, mips 1..%d:",
              buildSeconds, double(plan.bytes()) / 1e6, plan.tapCount(), plan.mipCount() - 1);
  for (int m = 1; m < plan.mipCount(); ++m) {
    const int n = std::max(1, size >> m);
    std::printf(" %.0f", double(plan.tapCount(m)) / double(runtime::kCubeFaceCount * n * n));
  }
  std::printf(")\n");
  if (sampled) {
    t0 = Clock::now();
    const std::vector<runtime::Cubemap> reference =
        runtime::prefilterChain(source, plan.mipCount(), runtime::kPrefilterSamples);
    std::printf("  sampled      %.0f ms (%d samples a texel, once)\n", secondsSince(t0) * 1e3,
                runtime::kPrefilterSamples);
  }
}

}  // namespace

int benchReflection(int argc, char** argv) {
  std::string path = std::string(AFTERGLOW_SHARED_DIR) + "/scenes/sponza/Sponza-sun.gltf";
  float texelsPerUnit = 4.0f;
  int repeat = 10, threads = 2, probes = 4, resolution = 128;
  bool sampled = false, prefilterOnly = false;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() { return i + 1 < argc ? std::atof(argv[++i]) : 0.0; };
    if (arg == "--repeat") repeat = std::max(1, int(next()));
    else if (arg == "--texels-per-unit") texelsPerUnit = float(next());
    else if (arg == "--threads") threads = int(next());
    else if (arg == "--probes") probes = std::max(1, int(next()));
    else if (arg == "--resolution") resolution = int(next());
    else if (arg == "--sampled") sampled = true;
    else if (arg == "--prefilter-only") prefilterOnly = true;
    else if (!arg.empty() && arg[0] != '-') path = arg;
    else
      return fail("unknown option " + arg +
                  " (--repeat N, --sampled, --prefilter-only, --texels-per-unit N, --threads N, "
                  "--probes N, --resolution N)");
  }
  std::printf("afterglow_bench reflection: reflection probes (issue 15)\n");
  prefilterFigures(repeat, sampled);
  if (prefilterOnly) return 0;
  return reflectionBakeFigures(path, texelsPerUnit, threads, repeat, probes, resolution);
}

}  // namespace afterglow::bench
