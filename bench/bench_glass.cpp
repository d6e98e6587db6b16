// afterglow_bench glass: issue 28's figure for light through glass. The gas station of
// ../shared/scenes (no lights; its shop's windows are alphaMode BLEND glass) baked under a
// constant sky, as `afterglow bake` bakes it (auto texels per metre, default quality), against
// the reference path tracer on the shop's interior texels:
//   afterglow_bench glass [SCENE] [--sky R,G,B] [--spp N] [--stride N] [--threads N]
//       [--texels-per-unit N] [--glass-sky-samples N] [--reference-cache FILE]
//       [--quality draft|default|high] [--texel-rays N] [--opaque-glass] [--open-glass]
//       [--no-glass-texels]
// The interior: the valid texels inside the world bounds of the shop's shell, the instance
// named "Mesh_new_base_0" (walls, floor and roof), shrunk by 2 cm so that the outside of its
// walls and roof stays out (they are 4 cm thick; the windows sit in their inner plane, so the
// glass's own texels are in, unless --no-glass-texels); one in `stride` of them, picked by a
// hash of the texel index (as `afterglow_bench accuracy` picks them). --opaque-glass bakes the
// windows as they were before glass let light through (BLEND opaque), against the same
// reference; --open-glass cuts the windows out instead, in the bake and the reference alike (a
// room lit through holes, for what the gather does without glass); --glass-sky-samples sets
// LinkOptions::glassSkySamples.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "afterglow/baker/bake.h"
#include "afterglow/core/parallel.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/material_eval.h"
#include "afterglow/trace/raytracer.h"
#include "bench_common.h"
#include "reference_cache.h"

namespace afterglow::bench {

namespace {

// The shop's shell, whose bounds hold the interior.
constexpr const char* kShell = "Mesh_new_base_0";
constexpr float kInset = 0.02f;  // metres: the shell's walls and roof are thicker

// World bounds of the instance called `name` (empty when there is none).
scenes::Bounds instanceBounds(const scenes::Scene& scene, const std::string& name) {
  scenes::Bounds box;
  for (const scenes::Instance& inst : scene.instances)
    if (inst.name == name)
      scenes::forEachWorldTriangle(scene, inst, [&](size_t, size_t, glm::vec3 a, glm::vec3 b,
                                                    glm::vec3 c) {
        box.extend(a);
        box.extend(b);
        box.extend(c);
      });
  return box;
}

// Whether texel t lies on glass.
bool onGlass(const scenes::Scene& scene, const baker::TexelSet& texels, uint32_t t) {
  const scenes::Instance& inst = scene.instances[texels.instance[t]];
  const scenes::Mesh* mesh = scene.meshOf(inst);
  if (!mesh) return false;
  for (const scenes::Primitive& prim : mesh->primitives)
    if (scenes::transmissive(scene, prim.material)) return true;
  return false;
}

// One in `stride` of the valid texels inside `box` (inset), by a hash of the texel's index;
// those on glass only with `glass`.
std::vector<uint32_t> texelsInside(const scenes::Scene& scene, const baker::TexelSet& texels,
                                   const scenes::Bounds& box, int stride, bool glass) {
  std::vector<uint32_t> out;
  const glm::vec3 lo = box.min + kInset, hi = box.max - kInset;
  for (uint32_t t = 0; t < texels.size(); ++t) {
    uint32_t h = t * 0x9e3779b1u;
    h ^= h >> 15;
    const glm::vec3 p = texels.position[t];
    if (texels.valid[t] && glm::all(glm::greaterThan(p, lo)) && glm::all(glm::lessThan(p, hi)) &&
        h % uint32_t(std::max(1, stride)) == 0 && (glass || !onGlass(scene, texels, t)))
      out.push_back(t);
  }
  return out;
}

// Mean E/π over the texels, RGB summed (to say how bright the interior is).
double meanLight(const std::vector<uint32_t>& which, const std::vector<glm::vec3>& a,
                 const std::vector<glm::vec3>& b) {
  double sum = 0.0;
  for (size_t i = 0; i < which.size(); ++i) {
    const glm::vec3 v = a[i] + b[i];
    sum += double(v.x + v.y + v.z);
  }
  return which.empty() ? 0.0 : sum / double(which.size());
}

}  // namespace

int benchGlass(int argc, char** argv) {
  std::string scenePath = std::string(AFTERGLOW_SHARED_DIR) + "/scenes/gas_station/GasStation.gltf";
  glm::vec3 sky(1.0f);
  int spp = 16384, stride = 4, threads = 2;
  int glassSkySamples = baker::LinkOptions().glassSkySamples, texelRays = 0;
  baker::Quality quality = baker::Quality::Default;
  float texelsPerUnit = 0.0f;
  bool opaqueGlass = false, glassTexels = true, openGlass = false;
  std::string referenceCache;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() { return i + 1 < argc ? std::atof(argv[++i]) : 0.0; };
    if (arg == "--spp") spp = int(next());
    else if (arg == "--stride") stride = int(next());
    else if (arg == "--threads") threads = int(next());
    else if (arg == "--texels-per-unit") texelsPerUnit = float(next());
    else if (arg == "--glass-sky-samples") glassSkySamples = int(next());
    else if (arg == "--texel-rays") texelRays = int(next());
    else if (arg == "--quality" && i + 1 < argc) quality = qualityNamed(argv[++i]);
    else if (arg == "--opaque-glass") opaqueGlass = true;
    else if (arg == "--open-glass") openGlass = true;
    else if (arg == "--no-glass-texels") glassTexels = false;
    else if (arg == "--reference-cache" && i + 1 < argc) referenceCache = argv[++i];
    else if (arg == "--sky" && i + 1 < argc &&
             std::sscanf(argv[++i], "%f,%f,%f", &sky.x, &sky.y, &sky.z) == 3) continue;
    else if (arg.rfind("--", 0) == 0) return fail("glass: unknown or malformed option " + arg);
    else scenePath = arg;
  }
  setThreadCount(threads);
  Result<scenes::Scene> loaded = loadBenchScene(scenePath);
  if (!loaded) return fail(loaded.message());
  scenes::Scene& scene = loaded.value();
  if (openGlass)
    for (scenes::Material& m : scene.materials)
      if (m.alphaMode == scenes::AlphaMode::Blend) {
        m.alphaMode = scenes::AlphaMode::Mask;
        m.baseColorFactor.a = 0.0f;
      }
  const scenes::Bounds shop = instanceBounds(scene, kShell);
  if (shop.empty()) return fail("glass: " + scenePath + " has no instance '" + kShell + "'");
  Result<float> density = unwrapForBench(scene, texelsPerUnit);
  if (!density) return fail(density.message());

  scenes::Scene baked = scene;  // the reference always sees the glass
  if (opaqueGlass)
    for (scenes::Material& m : baked.materials)
      if (m.alphaMode == scenes::AlphaMode::Blend) m.alphaMode = scenes::AlphaMode::Opaque;
  baker::BakeOptions options = baker::bakePreset(quality);
  if (texelRays > 0) options.links.texelRays = texelRays;
  options.skyColor = sky;
  options.links.glassSkySamples = glassSkySamples;
  auto t0 = Clock::now();
  Result<baker::BakeResult> bake = baker::bake(baked, options);
  const double bakeSeconds = secondsSince(t0);
  if (!bake) return fail(bake.message());
  const baker::BakeResult& b = bake.value();
  const std::vector<uint32_t> interior = texelsInside(scene, b.texels, shop, stride, glassTexels);
  std::printf("scene        %s, sky %g,%g,%g%s\n", scenePath.c_str(), double(sky.x),
              double(sky.y), double(sky.z), opaqueGlass ? ", glass baked opaque" : "");
  std::printf("bake         %u texels at %.1f texels/m in %.1f s, %.1f M rays\n",
              b.texels.size(), double(density.value()), bakeSeconds,
              double(b.raysTraced) / 1e6);
  std::printf("interior     %zu texels (1 in %d) inside '%s' (%.2f..%.2f, %.2f..%.2f, "
              "%.2f..%.2f m, less %g cm)%s\n",
              interior.size(), stride, kShell, double(shop.min.x), double(shop.max.x),
              double(shop.min.y), double(shop.max.y), double(shop.min.z), double(shop.max.z),
              double(kInset * 100.0f), glassTexels ? "" : ", not on glass");
  if (spp <= 0 || interior.empty()) return 0;

  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  if (!tracer) return fail(tracer.message());
  baker::Environment env;
  runtime::constantSkySh(sky, env.skySh);
  baker::ReferenceOptions ro;
  ro.samples = spp;
  t0 = Clock::now();
  const std::string key = scenePath + format(" sky %g,%g,%g", double(sky.x), double(sky.y),
                                             double(sky.z)) +
                          (openGlass ? " open glass" : "");
  Result<baker::ReferenceTexels> ref = referenceWithCache(scene, *tracer.value(), b.texels, env,
                                                          ro, interior, referenceCache, key);
  if (!ref) return fail("glass: " + ref.message());
  std::printf("reference    %zu texels x %d paths in %.1f s\n", interior.size(), spp,
              secondsSince(t0));
  std::vector<glm::vec3> bakedDirect, bakedIndirect;
  for (uint32_t t : interior) {
    bakedDirect.push_back(b.texelDirect[t]);
    bakedIndirect.push_back(b.texelIndirect[t]);
  }
  std::printf("mean E/pi    bake %.4f, reference %.4f (RGB summed)\n",
              meanLight(interior, bakedDirect, bakedIndirect),
              meanLight(interior, ref->direct, ref->indirect));
  printErrors(baker::compareToReference(ref.value(), b.texelDirect, b.texelIndirect));
  return 0;
}

}  // namespace afterglow::bench
