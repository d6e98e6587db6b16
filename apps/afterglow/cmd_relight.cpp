// afterglow relight: the command line's changes to a bake (light colours and intensities, bounce
// intensities, sky, albedo, emission, bounces) for bakefiles/relight.h, which relights the bake
// folder from its transport through the runtime API an engine links, without tracing a ray.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "afterglow/bakefiles/relight.h"
#include "afterglow/core/atomic_file.h"
#include "args.h"
#include "commands.h"
#include "common.h"

namespace fs = std::filesystem;

namespace afterglow::cli {

const char kRelightHelp[] =
    "Usage: afterglow relight OUT/ -o RELIT/ [options]\n"
    "\n"
    "Re-solves the bounced light of a bake from its transport file (OUT/transport.agt) with\n"
    "changed settings, as an engine does at run time, and writes RELIT/lightmaps/*.exr and\n"
    "*.png, RELIT/scene.gltf (OUT's, with the changed lights and materials) and\n"
    "RELIT/report.json, so 'afterglow render RELIT/scene.gltf' shows the result, and the relit\n"
    "light probes: RELIT/probes/light_probes.json (OUT's, its settings noting the relight) and\n"
    "RELIT/probes/light_probes_sh.bin. When the bake has reflection probes, their cubemaps are\n"
    "relit too (every capture pass, from the relit lightmaps) and written as the bake writes\n"
    "them: RELIT/probes/reflection_sky.exr and reflection_<i>.exr (OpenEXR cube maps, the\n"
    "prefiltered mips as mip levels), dfg.exr, reflection_probes.json, and the relit sky as\n"
    "EXT_lights_image_based in RELIT/scene.gltf (RELIT/probes/sky_specular_*.png), so they\n"
    "equal a fresh bake's with the same changes. Options that name a light or material may\n"
    "repeat; NAME may also be #INDEX.\n"
    "\n"
    "Options:\n"
    "  -o, --output RELIT/          output folder (required)\n"
    "  --light NAME=r,g,b[,i]       a light's linear colour, and optionally its intensity\n"
    "  --intensity NAME=i           a light's intensity (lux or candela, as in glTF)\n"
    "  --bounce NAME=x              a light's bounce intensity (its share in bounced light)\n"
    "  --disable NAME               switch a light off\n"
    "  --sky r,g,b                  constant sky radiance, linear\n"
    "  --albedo MAT=r,g,b           a material's bounce albedo, linear (what the bake derives\n"
    "                               from its base colour, metallic, roughness and specular).\n"
    "                               RELIT/scene.gltf gets the base colour that gives it, the\n"
    "                               other factors kept, so a bake of it gives these lightmaps\n"
    "                               (exactly for an untextured material; textured ones scale\n"
    "                               by their texture here, approximately in a bake). Where no\n"
    "                               base colour in [0, 1] gives it (a rough dielectric above\n"
    "                               0.98, a mirror metal), the material is written Lambertian:\n"
    "                               metallic 0, KHR_materials_specular specularFactor 0, base\n"
    "                               colour = the albedo, with a warning naming it\n"
    "  --emission MAT=r,g,b         a material's emitted radiance (materials that were emissive\n"
    "                               when baked)\n"
    "  --indirect-intensity X       scales all bounced light\n"
    "  --bounces N                  bounce passes (default: the bake's; 0 = until converged)\n"
    "  --quiet                      print nothing but errors\n"
    "  -h, --help                   this help\n";

namespace {

const std::vector<OptionSpec> kRelightOptions = {
    {"output", 'o'}, {"light"},   {"intensity"},          {"bounce"},
    {"disable"},     {"sky"},     {"albedo"},             {"emission"},
    {"indirect-intensity"},       {"bounces"},            {"quiet", 0, false},
    {"help", 'h', false}};

const Command kRelight = {"relight", "relight", kRelightHelp};

// "NAME=VALUE" split at the last '=' (names may contain '=' but values do not), the value
// `count` comma-separated floats (or from `count` to `maxCount`).
bool parseAssignment(const std::string& text, std::string* name, std::vector<float>* values,
                     size_t count, size_t maxCount = 0) {
  const size_t eq = text.rfind('=');
  if (eq == std::string::npos || eq == 0) return false;
  *name = text.substr(0, eq);
  return parseFloats(text.substr(eq + 1), *values) && values->size() >= count &&
         values->size() <= std::max(count, maxCount);
}

// --light, --intensity, --bounce and --disable. False, with *error set, when one is malformed.
bool parseLightChanges(const Args& args, bakefiles::RelightChanges* changes, std::string* error) {
  std::string name;
  std::vector<float> v;
  for (const std::string& a : args.getAll("light")) {
    if (!parseAssignment(a, &name, &v, 3, 4)) {
      *error = "--light wants NAME=r,g,b[,intensity], got '" + a + "'";
      return false;
    }
    changes->lightColors.push_back({name, glm::vec3(v[0], v[1], v[2]),
                                    v.size() == 4 ? std::optional<float>(v[3]) : std::nullopt});
  }
  for (const std::string& a : args.getAll("intensity")) {
    if (!parseAssignment(a, &name, &v, 1)) {
      *error = "--intensity wants NAME=i, got '" + a + "'";
      return false;
    }
    changes->intensities.push_back({name, v[0]});
  }
  for (const std::string& a : args.getAll("bounce")) {
    if (!parseAssignment(a, &name, &v, 1) || v[0] < 0) {
      *error = "--bounce wants NAME=x with x >= 0, got '" + a + "'";
      return false;
    }
    changes->bounceIntensities.push_back({name, v[0]});
  }
  changes->disabledLights = args.getAll("disable");
  return true;
}

// --albedo MAT=r,g,b or --emission MAT=r,g,b into `out`.
bool parseMaterialChanges(const Args& args, const std::string& option,
                          std::vector<bakefiles::NamedColor>* out, std::string* error) {
  std::string name;
  std::vector<float> v;
  for (const std::string& a : args.getAll(option)) {
    if (!parseAssignment(a, &name, &v, 3)) {
      *error = "--" + option + " wants MAT=r,g,b, got '" + a + "'";
      return false;
    }
    out->push_back({name, glm::vec3(v[0], v[1], v[2])});
  }
  return true;
}

// Every change the options ask for. False, with *error set, when one is malformed.
bool parseChanges(Args& args, bakefiles::RelightChanges* changes, std::string* error) {
  if (!parseLightChanges(args, changes, error)) return false;
  if (args.has("sky")) {
    glm::vec3 sky;
    if (!parseVec3(args.get("sky"), &sky)) {
      *error = "--sky wants r,g,b, got '" + args.get("sky") + "'";
      return false;
    }
    changes->sky = sky;
  }
  if (!parseMaterialChanges(args, "albedo", &changes->albedos, error) ||
      !parseMaterialChanges(args, "emission", &changes->emissions, error))
    return false;
  float indirect = 0.0f;
  int bounces = 0;
  if (!args.getFloat("indirect-intensity", 0.0f, -1e-30f, 1e6f, &indirect) ||
      !args.getInt("bounces", 0, 0, 100000, &bounces)) {
    *error = args.error();
    return false;
  }
  if (args.has("indirect-intensity")) changes->indirectIntensity = indirect;
  if (args.has("bounces")) changes->bounces = bounces;
  return true;
}

// A failed step's message, and its exit code: the user's mistake, the bake's or the output's.
int failed(const bakefiles::RelightError& error) {
  switch (error.fault) {
    case bakefiles::RelightFault::BadChange:
      return kRelight.usage(error.message);
    case bakefiles::RelightFault::BadBake:
      printError(error.message);
      return kExitBadInput;
    case bakefiles::RelightFault::Output:
      break;
  }
  printError(error.message);
  return kExitOutput;
}

void printSummary(const bakefiles::RelitBake& bake, const std::string& outDir) {
  const runtime::Runtime& rt = *bake.runtime;
  const runtime::UpdateStats& stats = bake.stats;
  std::printf("loaded        %s in %.3f s (%d texels, %d lights, %d materials)\n",
              bake.transportPath.c_str(), bake.loadSeconds, rt.texelCount(), rt.lightCount(),
              rt.materialCount());
  std::printf("solved        %d bounces%s in %.1f ms\n", stats.bounces,
              stats.converged ? " (converged)" : "", stats.milliseconds);
  if (stats.reflectionPasses > 0)
    std::printf("reflections   %d probes and the sky, %d capture passes in %.1f ms\n",
                bake.reflectionProbeCount(), stats.reflectionPasses,
                stats.reflectionMilliseconds);
  std::printf("wrote         %s (%d atlases, %d light probes, %d reflection probes)\n",
              outDir.c_str(), rt.atlasCount(), bake.lightProbeCount(),
              bake.reflectionProbeCount());
  for (const std::string& w : bake.warnings) std::printf("warning       %s\n", w.c_str());
}

}  // namespace

int runRelight(int argc, char** argv, int first) {
  Args args;
  if (std::optional<int> stop = parseOrExit(args, argc, argv, first, kRelightOptions, kRelight))
    return *stop;
  if (args.positional().size() != 1) return kRelight.usage("give one bake folder OUT/");
  if (!args.has("output")) return kRelight.usage("-o RELIT/ is required");
  const std::string in = args.positional()[0];
  const std::string outDir = args.get("output");
  std::error_code ec;
  if (fs::equivalent(in, outDir, ec))
    return kRelight.usage("RELIT/ must not be the bake folder itself");

  // The bake folder first, as a folder that is no bake is the error to report whatever the
  // options say; then the options' changes, named as the bake names its lights and materials.
  bakefiles::RelitBake bake;
  if (auto e = bakefiles::openBakeForRelight(in, &bake)) return failed(*e);
  if (interrupted()) return interruptedExit();
  bakefiles::RelightChanges changes;
  std::string malformed;
  if (!parseChanges(args, &changes, &malformed)) return kRelight.usage(malformed);
  if (auto e = bakefiles::applyRelightChanges(changes, bake)) return failed(*e);
  std::optional<bakefiles::RelightError> error = bakefiles::relightBake(bake);
  if (interrupted()) return interruptedExit();
  if (error) return failed(*error);

  AtomicOutput files;
  if (auto e = bakefiles::writeRelitFolder(bake, outDir, files)) return failed(*e);
  if (interrupted()) return interruptedExit();
  if (Status s = files.commit(); !s) {
    printError(s.message());
    return kExitOutput;
  }
  if (!args.has("quiet")) printSummary(bake, outDir);
  return kExitOk;
}

}  // namespace afterglow::cli
