// afterglow render: a ray-traced picture of a baked scene (albedo × lightmap + emission), or
// with --reference a path-traced picture of the same view to compare it with.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>

#include "afterglow/preview/exposure.h"
#include "afterglow/preview/probe_spheres.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/preview/render.h"
#include "afterglow/core/parallel.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "afterglow/scenes/gltf.h"
#include "args.h"
#include "commands.h"
#include "common.h"

namespace afterglow::cli {

const char kRenderHelp[] =
    "Usage: afterglow render SCENE.gltf -o VIEW.png|VIEW.exr [options]\n"
    "\n"
    "Ray traces a view of a scene written by 'afterglow bake' and shades every visible surface\n"
    "with its diffuse albedo x its lightmap (the EXR files the bake wrote, found through the\n"
    "glTF's MOZ_lightmap materials) + its emission. VIEW.png is tone mapped to sRGB; VIEW.exr\n"
    "holds the linear picture as it is (32-bit float RGB radiance in the lightmaps' units, no\n"
    "exposure or tone map, row 0 at the top), to compare with other renderers' EXRs. Surfaces\n"
    "without a lightmap (dynamic instances) show only their emission. When the bake has\n"
    "reflection probes (SCENE's folder/probes/reflection_probes.json), surfaces are shaded as an\n"
    "engine would: the metallic-roughness BRDF's diffuse colour x lightmap + its specular\n"
    "reflection from the probes.\n"
    "With --reference it path-traces the same view instead, to compare with: each visible\n"
    "point is shaded the same way but with a path-traced estimate in place of its lightmap and,\n"
    "with reflection probes, its reflection path-traced too (GGX-sampled, 4 reflections deep),\n"
    "so a mirror shows what it really reflects; lit as the bake was (sky, sky image, indirect\n"
    "intensity and albedo boost from the report.json beside SCENE.gltf; without one, a black\n"
    "sky and intensities 1).\n"
    "\n"
    "Options:\n"
    "  -o, --output VIEW.png|VIEW.exr\n"
    "                           output picture, by its extension: tone-mapped PNG or linear\n"
    "                           EXR; required\n"
    "  --camera NAME            view from the glTF camera NAME (default: the first camera)\n"
    "  --look-from X,Y,Z        view from this point (with --look-at) instead of a camera\n"
    "  --look-at X,Y,Z          point the view at this point\n"
    "  --fov DEG                vertical field of view in degrees (default: the camera's, or 45)\n"
    "  --width N, --height N    picture size in pixels (default 640 x 480)\n"
    "  --exposure X             scale by 2^X before tone mapping (default: automatic, the\n"
    "                           99th percentile maps to 0.8); PNG only\n"
    "  --probe-spheres [N|all]  draw white diffuse spheres (albedo 0.8) lit by the light probes\n"
    "                           the bake wrote (SCENE's folder/probes/): what a dynamic object\n"
    "                           would receive there, shaded 0.8 x E/pi with the probes sampled\n"
    "                           at each sphere's centre. N (default 8): spheres at probes the\n"
    "                           camera sees, picked far apart on the picture, each 2/5 of the\n"
    "                           distance to its probe's nearest neighbour in radius; 'all': one\n"
    "                           at every probe, 1/5 of the probes' median spacing. Spheres keep\n"
    "                           clear of the walls beside them, hide what is behind them and\n"
    "                           cast no shadows (they are not in the bake); not with --reference.\n"
    "                           With reflection probes in the bake, every second sphere is a\n"
    "                           mirror and every third a rough metal (silver, roughness 0.4)\n"
    "                           lit by the reflection probes\n"
    "  --sphere-at X,Y,Z,R      a diffuse sphere of radius R at X,Y,Z (metres) lit by the light\n"
    "                           probes there, as --probe-spheres draws them; repeatable, and\n"
    "                           with --probe-spheres drawn besides its spheres\n"
    "  --no-directional         ignore the directional lightmaps (default: normal textures tilt\n"
    "                           the normal the bounced light is read at, as an engine does)\n"
    "  --reference              path-trace the view instead of reading the lightmaps (slow)\n"
    "  --spp N                  paths per pixel for --reference (default 256)\n"
    "  --threads N              worker threads (default: every core); the picture is\n"
    "                           identical for any count\n"
    "  --quiet                  no progress bar\n"
    "  -h, --help               this help\n";

namespace {

// How many specular reflections --reference follows when the bake has reflection probes: the
// probes' own capture follows two by default (pass 0 and one bounce); a reference a few deeper
// shows what the probes leave out.
constexpr int kReferenceReflections = 4;

// Whether any instance has a lightmap layout: the reference path-traces only what a bake lit,
// so without one its picture would be black but for emission.
bool hasLightmapLayout(const scenes::Scene& scene) {
  for (const scenes::Instance& inst : scene.instances)
    if (inst.isStatic && inst.lightmap.atlas >= 0) return true;
  return false;
}

// What shades the picture: the bake's lighting for --reference, its lightmaps otherwise.
// Loaded before the (slower) ray tracer so that bad inputs fail fast. Returns the exit code.
int loadShading(const std::string& input, const scenes::Scene& scene, bool reference, bool quiet,
                baker::Environment* environment, std::vector<bakefiles::LightmapImage>* lightmaps,
                bakefiles::BakedReflections* reflections,
                bakefiles::BakedDirectional* directional) {
  if (!reference) {
    Result<std::vector<bakefiles::LightmapImage>> loaded = bakefiles::loadBakedLightmaps(input);
    if (!loaded) {
      printError(loaded.message());
      return kExitBadInput;
    }
    *lightmaps = std::move(loaded.value());
    Result<bakefiles::BakedReflections> probes = bakefiles::loadBakedReflections(input);
    if (!probes) {
      printError(probes.message());
      return kExitBadInput;
    }
    *reflections = std::move(probes.value());
    if (directional) {
      Result<bakefiles::BakedDirectional> gradients = bakefiles::loadBakedDirectional(input);
      if (!gradients) {
        printError(gradients.message());
        return kExitBadInput;
      }
      *directional = std::move(gradients.value());
    }
    return kExitOk;
  }
  if (!hasLightmapLayout(scene)) {
    printError(input + ": no instance has a lightmap (extras.afterglow.lightmap), so the "
               "reference would show emission only; render the scene.gltf afterglow bake wrote");
    return kExitBadInput;
  }
  bool reportFound = false;
  Result<baker::Environment> loaded = bakefiles::loadBakeEnvironment(input, &reportFound);
  if (!loaded) {
    printError(loaded.message());
    return kExitBadInput;
  }
  *environment = loaded.value();
  if (!reportFound && !quiet)
    std::printf("note          no report.json beside %s: lighting the reference with a black "
                "sky, indirect intensity 1 and albedo boost 1\n",
                input.c_str());
  return kExitOk;
}

// --probe-spheres takes the next argument as its count only when it is one (a number or
// "all"), so `--probe-spheres SCENE.gltf` leaves the scene where it is.
bool isSphereCount(const std::string& next) {
  const bool digits = !next.empty() && std::all_of(next.begin(), next.end(), [](char c) {
    return c >= '0' && c <= '9';
  });
  return digits || next == "all";
}

// Which probes got spheres, so that a sphere in the picture can be traced to its probe.
void printSpheres(const std::vector<preview::ProbeSphere>& spheres, int count, size_t probes) {
  if (spheres.empty()) {
    std::printf("note          no light probe is in view: the picture has no probe spheres\n");
    return;
  }
  float lo = spheres.front().radius, hi = lo;
  for (const preview::ProbeSphere& s : spheres) {
    lo = std::min(lo, s.radius);
    hi = std::max(hi, s.radius);
  }
  const std::string radius = lo == hi
                                 ? format("radius %.3g m", double(lo))
                                 : format("radius %.3g-%.3g m", double(lo), double(hi));
  const double albedo = double(preview::kProbeSphereAlbedo);
  if (count == 0) {
    std::printf("spheres       at every probe: %zu of %zu may show in this view (%s, albedo "
                "%.1f)\n",
                spheres.size(), probes, radius.c_str(), albedo);
    return;
  }
  std::string which;
  for (const preview::ProbeSphere& s : spheres)
    which += (which.empty() ? "" : ", ") + std::to_string(s.probe);
  std::printf("spheres       %zu at probes %s (%s, albedo %.1f)\n", spheres.size(), which.c_str(),
              radius.c_str(), albedo);
}

// The PNG's exposure, and a warning when the lightmaps shown are essentially black for the
// light the bake had (its report's sky, the glTF's lights and emission): auto exposure would
// brighten their noise into a picture.
void printBrightness(const std::string& input, const scenes::Scene& scene,
                     const std::vector<bakefiles::LightmapImage>& lightmaps,
                     const std::vector<glm::vec3>& image, float exposureStops, bool png) {
  if (png)
    std::printf("exposure      %s\n",
                preview::describeExposure(preview::chooseExposure(image, exposureStops)).c_str());
  if (lightmaps.empty()) return;  // --reference: lit by paths, not lightmaps
  // A report that does not load (rendering a copied glTF) leaves a black sky: the lights and
  // emission still give a scale.
  Result<baker::Environment> environment = bakefiles::loadBakeEnvironment(input);
  const std::string warning = preview::blackLightmapsWarning(
      scene, lightmaps, environment ? environment.value() : baker::Environment(), input);
  if (!warning.empty()) std::printf("warning       %s\n", warning.c_str());
}

}  // namespace

int runRender(int argc, char** argv, int first) {
  const Command command = {"render", "render", kRenderHelp};
  Args args;
  if (std::optional<int> stop = parseOrExit(args, argc, argv, first,
                                            {{"output", 'o'},
                                             {"camera"},
                                             {"look-from"},
                                             {"look-at"},
                                             {"fov"},
                                             {"width"},
                                             {"height"},
                                             {"exposure"},
                                             {"threads"},
                                             {"reference", 0, false},
                                             {"no-directional", 0, false},
                                             {"probe-spheres", 0, true, isSphereCount},
                                             {"sphere-at"},
                                             {"spp"},
                                             {"quiet", 0, false},
                                             {"help", 'h', false}},
                                            command))
    return *stop;
  if (args.positional().size() != 1) return command.usage("wants exactly one SCENE.gltf");
  const std::string input = args.positional()[0];
  if (!args.has("output")) return command.usage("missing -o VIEW.png or -o VIEW.exr");
  const std::string output = args.get("output");
  const bool exr = endsWith(output, ".exr");
  if (!exr && !endsWith(output, ".png"))
    return command.usage("the output must end in .png (tone mapped) or .exr (linear), got '" +
                         output + "'");
  preview::RenderOptions options;
  int threads = 0;
  int spp = 256;
  float fovDeg = 45.0f;
  float exposure = std::numeric_limits<float>::quiet_NaN();
  if (!args.getInt("width", 640, 1, 16384, &options.width) ||
      !args.getInt("height", 480, 1, 16384, &options.height) ||
      !args.getFloat("fov", 45.0f, 0.0f, 179.0f, &fovDeg) ||
      !args.getInt("threads", 0, 0, 1024, &threads) ||
      !args.getInt("spp", 256, 1, 1 << 20, &spp))
    return command.usage(args.error());
  if (args.has("exposure") && !args.getFloat("exposure", 0.0f, -100.0f, 100.0f, &exposure))
    return command.usage(args.error());
  if (args.has("exposure") && exr)
    return command.usage(
        "--exposure sets the PNG's tone mapping; an EXR holds the picture unscaled");
  // 0 = a sphere at every probe.
  int sphereCount = -1;
  if (args.has("probe-spheres")) {
    const std::string value = args.get("probe-spheres");
    if (value == "all") {
      sphereCount = 0;
    } else if (value.empty()) {
      sphereCount = 8;
    } else if (!args.getInt("probe-spheres", 8, 1, 100000, &sphereCount)) {
      return command.usage(args.error() + " (or 'all')");
    }
  }
  // Spheres at given points (x, y, z, radius).
  std::vector<glm::vec4> sphereAt;
  for (const std::string& a : args.getAll("sphere-at")) {
    std::vector<float> v;
    if (!parseFloats(a, v) || v.size() != 4 || !(v[3] > 0.0f))
      return command.usage("--sphere-at wants x,y,z,radius (metres, radius > 0), got '" + a + "'");
    sphereAt.emplace_back(v[0], v[1], v[2], v[3]);
  }
  // Spheres of either kind are lit by the probes the bake wrote beside the glTF.
  if (sphereCount >= 0 || !sphereAt.empty()) {
    const std::string option = sphereCount >= 0 ? "--probe-spheres" : "--sphere-at";
    if (args.has("reference"))
      return command.usage(option + " draws into the baked view; the --reference path tracer "
                           "has no probes");
    if (isBuiltinScene(input))
      return command.usage(option + " reads the light probes afterglow bake wrote beside the "
                           "scene; render the scene.gltf it wrote, not " + input);
  }
  glm::vec3 from(0.0f), at(0.0f);
  const bool lookAt = args.has("look-from") || args.has("look-at");
  if (lookAt) {
    if (args.has("camera"))
      return command.usage("give --camera or --look-from/--look-at, not both");
    if (!args.has("look-from") || !args.has("look-at"))
      return command.usage("--look-from and --look-at go together");
    if (!parseVec3(args.get("look-from"), &from))
      return command.usage("--look-from wants X,Y,Z, got '" + args.get("look-from") + "'");
    if (!parseVec3(args.get("look-at"), &at))
      return command.usage("--look-at wants X,Y,Z, got '" + args.get("look-at") + "'");
  }
  setThreadCount(threads);
  ConsoleProgress progress(stderr, args.has("quiet"));
  InterruptGuard guard(progress);

  int code = kExitOk;
  // Normal textures tilt the directional lightmaps' normals (not with --reference, which has
  // no lightmaps, nor --no-directional).
  Result<scenes::Scene> loaded =
      loadSceneOrExit(input, true, &code, !args.has("reference") && !args.has("no-directional"));
  if (!loaded) return code;
  const scenes::Scene& scene = loaded.value();
  const bool reference = args.has("reference");
  const bool quiet = args.has("quiet");
  baker::Environment environment;
  std::vector<bakefiles::LightmapImage> lightmaps;
  bakefiles::BakedReflections reflections;
  bakefiles::BakedDirectional directional;
  if (int code = loadShading(input, scene, reference, quiet, &environment, &lightmaps,
                             &reflections, args.has("no-directional") ? nullptr : &directional);
      code != kExitOk)
    return code;
  bakefiles::LightProbes lightProbes;
  if (sphereCount >= 0 || !sphereAt.empty()) {
    Result<bakefiles::LightProbes> probes = bakefiles::loadLightProbes(input);
    if (!probes) {
      printError(probes.message());
      return kExitBadInput;
    }
    lightProbes = std::move(probes.value());
  }
  if (interrupted()) return interruptedExit();

  const float fovRad = fovDeg * 3.14159265f / 180.0f;
  trace::View view;
  if (lookAt) {
    view = trace::lookAtView(from, at, fovRad);
  } else if (args.has("camera")) {
    const std::string name = args.get("camera");
    const scenes::Camera* camera = nullptr;
    for (const scenes::Camera& c : scene.cameras)
      if (c.name == name) camera = &c;
    if (!camera) {
      std::string names;
      for (const scenes::Camera& c : scene.cameras) names += (names.empty() ? "" : ", ") + c.name;
      printError("render: " + input + " has no camera '" + name + "'" +
                 (names.empty() ? std::string(" (it has no cameras)") : " (it has: " + names + ")"));
      return kExitBadInput;
    }
    view = trace::cameraView(*camera);
    if (args.has("fov")) view.yfov = fovRad;
  } else if (!scene.cameras.empty()) {
    view = trace::cameraView(scene.cameras.front());
    if (args.has("fov")) view.yfov = fovRad;
  } else {
    view = trace::defaultView(scene, fovRad);
  }

  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  if (!tracer) {
    printError(tracer.message());
    return kExitBadInput;
  }
  std::vector<preview::ProbeSphere> spheres;
  for (const glm::vec4& s : sphereAt) spheres.push_back(preview::sphereAt(lightProbes, glm::vec3(s), s.w));
  if (sphereCount >= 0) {
    Result<std::vector<preview::ProbeSphere>> chosen = preview::chooseProbeSpheres(
        *tracer.value(), lightProbes, view, options.width, options.height, sphereCount);
    if (!chosen) {
      printError(input + ": light probes: " + chosen.message());
      return kExitBadInput;
    }
    // With reflection probes every second and third sphere is a mirror and a rough metal.
    if (!reflections.empty())
      for (size_t i = 0; i < chosen->size(); ++i)
        (*chosen)[i].finish = preview::SphereFinish(i % 3);
    if (!quiet) printSpheres(chosen.value(), sphereCount, lightProbes.sh.size());
    spheres.insert(spheres.end(), chosen->begin(), chosen->end());
  }
  Result<std::vector<glm::vec3>> image =
      reference ? baker::renderReference(scene, *tracer.value(), environment, view, options.width,
                                         options.height, spp,
                                         scene.reflectionProbes.empty() ? 0
                                                                        : kReferenceReflections,
                                         progress)
                : preview::renderBaked(scene, *tracer.value(), lightmaps, view, options, progress,
                                     spheres, &reflections, &directional);
  if (interrupted() || progress.cancelled()) return interruptedExit();
  if (!image) {
    printError(image.message());
    return kExitBadInput;
  }
  const Status st =
      exr ? preview::writeRenderExr(output, options.width, options.height, image.value())
          : preview::writeRenderPng(output, options.width, options.height, image.value(), exposure);
  if (!st) {
    printError(st.message());
    return kExitOutput;
  }
  if (!quiet) {
    printBrightness(input, scene, lightmaps, image.value(), exposure, !exr);
    const std::string how =
        reference ? format("reference: path traced, %d paths per pixel%s", spp,
                           scene.reflectionProbes.empty()
                               ? ""
                               : format(", reflections %d deep", kReferenceReflections).c_str())
                  : std::string("baked: albedo x lightmap + emission") +
                        (spheres.empty() ? ""
                                         : format(", probe spheres %.1f x E/pi",
                                                  double(preview::kProbeSphereAlbedo)));
    std::printf("wrote         %s (%dx%d, %s)\n", output.c_str(), options.width, options.height,
                how.c_str());
  }
  return kExitOk;
}

}  // namespace afterglow::cli
