// An engine's relighting loop: load the baked transport, and every frame change a light's colour
// along a hue cycle, run one bounce (Enlighten's one iteration a frame, warm-started from the
// previous frame), and read the atlases back as a renderer would upload them.
//
// A bake with an indirect grid (two resolutions) hands the engine its layers: the grid's atlases
// each frame, composed in the engine's shader with the per-light direct layers (uploaded once)
// and the light colours. --compose composes the lightmap on the CPU instead and uploads it.
//
// --no-probes leaves the light and reflection probes out of the frame. --directional refreshes
// the directional lightmaps' gradient atlases too (runtime/directional.h) and uploads them.
//
//   relight_loop OUT/transport.agt [--frames N] [--light NAME] [--compose] [--no-probes]
//                [--directional]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "afterglow/runtime/runtime.h"

namespace {

// Fully saturated colour of hue h in [0, 1).
glm::vec3 hue(float h) {
  const float r = std::fabs(h * 6.0f - 3.0f) - 1.0f;
  const float g = 2.0f - std::fabs(h * 6.0f - 2.0f);
  const float b = 2.0f - std::fabs(h * 6.0f - 4.0f);
  return glm::clamp(glm::vec3(r, g, b), glm::vec3(0.0f), glm::vec3(1.0f));
}

int usage() {
  std::fprintf(stderr,
               "usage: relight_loop OUT/transport.agt [--frames N] [--light NAME] [--compose] "
               "[--no-probes] [--directional]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path, lightName;
  int frames = 120;
  bool compose = false, probes = true, directional = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--compose") == 0) {
      compose = true;
    } else if (std::strcmp(argv[i], "--directional") == 0) {
      directional = true;
    } else if (std::strcmp(argv[i], "--no-probes") == 0) {
      probes = false;
    } else if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      frames = std::atoi(argv[++i]);
      if (frames <= 0) return usage();
    } else if (std::strcmp(argv[i], "--light") == 0 && i + 1 < argc) {
      lightName = argv[++i];
    } else if (argv[i][0] != '-' && path.empty()) {
      path = argv[i];
    } else {
      return usage();
    }
  }
  if (path.empty()) return usage();

  std::string error;
  std::unique_ptr<afterglow::runtime::Runtime> rt = afterglow::runtime::Runtime::load(path, &error);
  if (!rt) {
    std::fprintf(stderr, "relight_loop: %s\n", error.c_str());
    return 1;
  }
  if (rt->lightCount() == 0) {
    std::fprintf(stderr, "relight_loop: %s has no lights to relight\n", path.c_str());
    return 1;
  }
  const int light = lightName.empty() ? 0 : rt->findLight(lightName);
  if (light < 0) {
    std::fprintf(stderr, "relight_loop: no light named '%s'; lights:", lightName.c_str());
    for (int i = 0; i < rt->lightCount(); ++i) std::fprintf(stderr, " '%s'", rt->lightName(i).c_str());
    std::fprintf(stderr, "\n");
    return 1;
  }
  std::printf("%s: %d texels, %d atlases, %d lights; cycling '%s'\n", path.c_str(),
              rt->texelCount(), rt->atlasCount(), rt->lightCount(), rt->lightName(light).c_str());

  // The converged baked state first, as the level would start.
  const afterglow::runtime::UpdateStats first = rt->update();
  std::printf("initial solve: %d bounces, %.2f ms\n", first.bounces, first.milliseconds);

  // What the engine uploads each frame: the lightmap's atlases, or with an indirect grid and
  // the engine composing, the grid's (allocated once).
  const bool layers = rt->indirectAtlasCount() > 0 && !compose;
  if (rt->indirectAtlasCount() > 0)
    std::printf("indirect grid: %d atlases (%dx%d); %s\n", rt->indirectAtlasCount(),
                rt->indirectAtlasWidth(0), rt->indirectAtlasHeight(0),
                layers ? "uploading its atlases, the engine composes"
                       : "composing the lightmap on the CPU");
  std::vector<std::vector<float>> upload(size_t(rt->atlasCount()));
  for (int a = 0; a < rt->atlasCount() && !layers; ++a)
    upload[size_t(a)].resize(size_t(rt->atlasWidth(a)) * size_t(rt->atlasHeight(a)) * 3);
  std::vector<std::vector<glm::vec3>> gridUpload(size_t(rt->indirectAtlasCount()));

  afterglow::runtime::UpdateOptions perFrame;
  perFrame.maxBounces = 1;
  perFrame.composeLightmap = !layers;
  // One reflection probe capture pass a frame: a full round of a level's probes each frame
  // would cost a frame many times over (issue 28 made them the default).
  perFrame.reflectionPasses = probes ? 1 : 0;
  perFrame.probes = probes;
  perFrame.directional = directional;
  std::vector<glm::vec3> gradientUpload;
  const glm::vec3 baseColor = rt->lightColor(light);
  const float brightness = std::max({baseColor.x, baseColor.y, baseColor.z, 1e-6f});
  std::vector<double> ms, lightmapMs;  // the whole update; its lightmaps' part (no probes)
  ms.reserve(size_t(frames));
  lightmapMs.reserve(size_t(frames));
  for (int f = 0; f < frames; ++f) {
    rt->setLightColor(light, brightness * hue(float(f % 120) / 120.0f));
    const afterglow::runtime::UpdateStats s = rt->update(perFrame);
    if (layers)
      for (int a = 0; a < rt->indirectAtlasCount(); ++a)
        rt->readIndirectAtlas(a, gridUpload[size_t(a)]);
    else
      for (int a = 0; a < rt->atlasCount(); ++a) rt->readAtlas(a, upload[size_t(a)].data());
    for (int a = 0; a < rt->directionalAtlasCount() && directional; ++a)
      for (int axis = 0; axis < 3; ++axis) rt->readDirectionalAtlas(a, axis, gradientUpload);
    ms.push_back(s.milliseconds);
    std::printf("frame %4d  update %7.3f ms  (light change %.3f, bounce %.3f, atlases %.3f of which "
                "compose %.3f, light probes %.3f, reflection %.3f ms)  change %.2e\n",
                f, s.milliseconds, s.prepareMilliseconds, s.bounceMilliseconds,
                s.outputMilliseconds, s.composeMilliseconds, s.probeMilliseconds,
                s.reflectionMilliseconds, double(s.change));
    lightmapMs.push_back(s.milliseconds - s.probeMilliseconds - s.reflectionMilliseconds);
  }

  auto summary = [&](const char* what, std::vector<double> v) {
    std::sort(v.begin(), v.end());
    double sum = 0.0;
    for (double x : v) sum += x;
    const size_t n = v.size();
    const double median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    std::printf("%d frames: %s mean %.3f ms, median %.3f ms, max %.3f ms\n", frames, what,
                sum / double(n), median, v.back());
  };
  summary("update", ms);
  summary("light change + bounce + lightmap outputs (no probes)", lightmapMs);
  return 0;
}
