// afterglow_bench views: two linear pictures of one view compared surface by surface, e.g.
// `afterglow render -o view.exr` against an independent renderer's picture of the same glTF
// view (../shared/tools/cycles_render.py renders it with Blender's Cycles). Each pixel is
// assigned the material its centre ray hits, through the project's own ray tracer and camera;
// pixels within two of a different material (or a miss) are left out, since renderers filter
// pixels differently at edges (Cycles: a 1.5-pixel Blackman-Harris). Per material it prints
// the mean luminance of both pictures and their ratio, and the ratio per channel.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "afterglow/core/math.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/preview/render.h"
#include "bench_common.h"

namespace afterglow::bench {
namespace {

bool parse3(const char* s, glm::vec3* v) {
  return std::sscanf(s, "%f,%f,%f", &v->x, &v->y, &v->z) == 3;
}

}  // namespace

int benchViews(int argc, char** argv) {
  if (argc < 5)
    return fail("usage: afterglow_bench views SCENE.gltf A.exr B.exr [--look-from X,Y,Z "
                "--look-at X,Y,Z] [--fov DEG] [--camera-index N]");
  const std::string scenePath = argv[2], pathA = argv[3], pathB = argv[4];
  glm::vec3 from(0.0f), at(0.0f, 0.0f, -1.0f);
  float fovDeg = 45.0f;
  bool look = false;
  for (int i = 5; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--look-from") && parse3(argv[i + 1], &from)) look = true;
    else if (!std::strcmp(argv[i], "--look-at") && parse3(argv[i + 1], &at)) look = true;
    else if (!std::strcmp(argv[i], "--fov")) fovDeg = float(std::atof(argv[i + 1]));
    else return fail(std::string("views: unknown option ") + argv[i]);
  }
  Result<scenes::Scene> scene = loadBenchScene(scenePath, false);
  if (!scene) return fail(scene.message());
  Result<bakefiles::LightmapImage> a = bakefiles::readLinearImage(pathA), b = bakefiles::readLinearImage(pathB);
  if (!a) return fail(a.message());
  if (!b) return fail(b.message());
  if (a->width != b->width || a->height != b->height)
    return fail("views: the pictures differ in size");
  trace::View view;
  if (look) view = trace::lookAtView(from, at, fovDeg * 3.14159265f / 180.0f);
  else if (!scene->cameras.empty()) view = trace::cameraView(scene->cameras.front());
  else return fail("views: no --look-from/--look-at and no camera in the scene");
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene.value());
  if (!tracer) return fail(tracer.message());

  // The material each pixel's centre ray hits (-1: a miss), through the renderer's camera.
  const int w = a->width, h = a->height;
  std::vector<int> material(size_t(w) * size_t(h), -1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const trace::Ray ray = trace::cameraRay(view, w, h, float(x) + 0.5f, float(y) + 0.5f);
      const trace::Hit hit = tracer.value()->intersect(ray);
      if (!hit.valid()) continue;
      const scenes::Instance& inst = scene->instances[hit.instance];
      material[size_t(y) * size_t(w) + size_t(x)] =
          scene->meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
    }
  struct Sums {
    size_t pixels = 0;
    glm::dvec3 a{0.0}, b{0.0};
  };
  std::map<int, Sums> sums;
  constexpr int kMargin = 2;
  for (int y = kMargin; y < h - kMargin; ++y)
    for (int x = kMargin; x < w - kMargin; ++x) {
      const int m = material[size_t(y) * size_t(w) + size_t(x)];
      if (m < 0) continue;
      bool inside = true;
      for (int dy = -kMargin; dy <= kMargin && inside; ++dy)
        for (int dx = -kMargin; dx <= kMargin && inside; ++dx)
          inside = material[size_t(y + dy) * size_t(w) + size_t(x + dx)] == m;
      if (!inside) continue;
      Sums& s = sums[m];
      const size_t i = size_t(y) * size_t(w) + size_t(x);
      ++s.pixels;
      s.a += glm::dvec3(a->pixels[i]);
      s.b += glm::dvec3(b->pixels[i]);
    }
  std::printf("%-14s %7s %10s %10s %9s   %s\n", "material", "pixels", "A lum", "B lum", "A/B-1",
              "A/B-1 per channel (r g b)");
  for (const auto& [m, s] : sums) {
    const glm::dvec3 ma = s.a / double(s.pixels), mb = s.b / double(s.pixels);
    const double la = luminance(glm::vec3(ma)), lb = luminance(glm::vec3(mb));
    std::printf("%-14s %7zu %10.5f %10.5f %+8.2f%%   %+.2f%% %+.2f%% %+.2f%%\n",
                scene->material(m).name.c_str(), s.pixels, la, lb, 100.0 * (la / lb - 1.0),
                100.0 * (ma.x / mb.x - 1.0), 100.0 * (ma.y / mb.y - 1.0),
                100.0 * (ma.z / mb.z - 1.0));
  }
  return 0;
}

}  // namespace afterglow::bench
