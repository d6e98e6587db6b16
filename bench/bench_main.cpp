// afterglow_bench: prints the figures the issues ask for (not a test; nothing here fails a
// build). One subcommand per capability:
//   afterglow_bench uv [SCENE] [--texels-per-unit 16] [--threads 2]
//   afterglow_bench bake [--threads 2] [--cornell-only | --sponza-only] [--quick]
//   afterglow_bench runtime [--cornell-only | --sponza-only] [--repeat N]
//   afterglow_bench accuracy [SCENE] [--texels-per-unit N] [--spp N] [--stride N] ...
//   afterglow_bench views SCENE A.exr B.exr [--look-from X,Y,Z --look-at X,Y,Z --fov DEG]
//   afterglow_bench probes [SCENE] [--texels-per-unit 4] [--threads 2] [--repeat 5]
//   afterglow_bench reflection [SCENE] [--texels-per-unit 4] [--threads 2] [--probes 4]
//       [--resolution 128] [--repeat 10] [--sampled] [--prefilter-only]
//   afterglow_bench glass [SCENE] [--sky R,G,B] [--spp N] [--stride N] [--opaque-glass] ...
//   afterglow_bench noise [SCENE] [--instance NAME] [--texels-per-unit N] ...
#include <cstdio>
#include <cstring>

#include "bench_common.h"

int main(int argc, char** argv) {
  using namespace afterglow::bench;
  const char* command = argc >= 2 ? argv[1] : "";
  if (std::strcmp(command, "uv") == 0) return benchUv(argc, argv);
  if (std::strcmp(command, "accuracy") == 0) return benchAccuracy(argc, argv);
  if (std::strcmp(command, "bake") == 0) return benchBake(argc, argv);
  if (std::strcmp(command, "runtime") == 0) return benchRuntime(argc, argv);
  if (std::strcmp(command, "views") == 0) return benchViews(argc, argv);
  if (std::strcmp(command, "probes") == 0) return benchProbes(argc, argv);
  if (std::strcmp(command, "reflection") == 0) return benchReflection(argc, argv);
  if (std::strcmp(command, "glass") == 0) return benchGlass(argc, argv);
  if (std::strcmp(command, "noise") == 0) return benchNoise(argc, argv);
  std::fprintf(stderr,
               "usage: afterglow_bench uv|bake|runtime|accuracy|views|probes|reflection|glass|noise "
               "[options]\n"
               "  uv        lightmap UVs of Sponza: utilisation, stretch, time (issue 2)\n"
               "  bake      bake time, accuracy, ray throughput, memory (issue 3)\n"
               "  runtime   transport size and load, bounce and update times, one thread (issue 4)\n"
               "  accuracy  a bake against the reference path tracer (Cornell box)\n"
               "  views     two linear pictures of one view (afterglow, Cycles) per material\n"
               "  probes    light probes: placement, precompute share, refresh time, bytes (issue 14)\n"
               "  reflection  reflection probes: prefilter, capture, runtime update, transport share (issue 15)\n"
               "  glass     the gas station's shop, lit by the sky through its windows (issue 28)\n"
               "  noise     patch-scale noise of one instance's bounced light (issue 29)\n");
  return 2;
}
