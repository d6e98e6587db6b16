// afterglow relight: new lightmaps from a bake's transport file with changed light colours and
// intensities, bounce intensities, sky, albedo or emission, through the runtime API an engine
// links (runtime/runtime.h), without tracing a ray.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <optional>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afterglow/bakefiles/write.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/status.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/material_eval.h"
#include "args.h"
#include "afterglow/bakefiles/read.h"
#include "commands.h"
#include "common.h"

namespace fs = std::filesystem;
using nlohmann::json;

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

// "NAME=VALUE" split at the last '=' (names may contain '=' but values do not).
bool splitAssignment(const std::string& text, std::string& name, std::string& value) {
  const size_t eq = text.rfind('=');
  if (eq == std::string::npos || eq == 0) return false;
  name = text.substr(0, eq);
  value = text.substr(eq + 1);
  return true;
}

// "'a', 'b'" from count names, or "none".
template <class Name>
std::string nameList(int count, Name name) {
  std::string names;
  for (int i = 0; i < count; ++i) names += (i ? ", '" : "'") + name(i) + "'";
  return names.empty() ? "none" : names;
}

// NAME or #INDEX into an index, or -1.
int resolve(const std::string& name, int count, int (runtime::Runtime::*find)(const std::string&) const,
            const runtime::Runtime& rt) {
  if (int i = (rt.*find)(name); i >= 0) return i;
  if (name.size() > 1 && name[0] == '#') {
    char* end = nullptr;
    const long i = std::strtol(name.c_str() + 1, &end, 10);
    if (*end == '\0' && i >= 0 && i < count) return int(i);
  }
  return -1;
}

// Which glTF materials of the bake's scene.gltf carry each transport material. The bake writes
// the scene's materials first, in the transport's order (the transport appends "default" for
// glTF's default material when primitives without a material are lightmapped), then a
// MOZ_lightmap copy per material and atlas for the lightmapped primitives, which names its
// original in extras.afterglow.material (-1 for the default material). Copies written before
// that field are recognised by their name, the original's (or "material-1") + "_lightmap<i>".
struct MaterialMap {
  size_t originals = 0;   // glTF materials before the first copy
  int defaultIndex = -1;  // the transport's index of glTF's default material, if it has one
  std::string problem;    // why nothing maps, when the counts disagree

  std::string why() const { return problem.empty() ? "scene.gltf has no material for it" : problem; }

  // The scene material (Scene::material's index; -1 = the default) of a transport material.
  int sceneMaterial(int material) const { return material == defaultIndex ? -1 : material; }

  std::vector<size_t> gltfMaterials(const json& gltf, int material) const {
    std::vector<size_t> found;
    if (!problem.empty() || !gltf.contains("materials") || !gltf["materials"].is_array())
      return found;
    const json& materials = gltf["materials"];
    const int source = sceneMaterial(material);
    if (source >= 0 && size_t(source) < originals) found.push_back(size_t(source));
    const std::string sourceName =
        source >= 0 && size_t(source) < originals && materials[size_t(source)].contains("name") &&
                materials[size_t(source)]["name"].is_string()
            ? materials[size_t(source)]["name"].get<std::string>()
            : format("material%d", source);
    for (size_t j = originals; j < materials.size(); ++j) {
      const json* extras = copyExtras(materials[j]);
      if (!extras) continue;
      if (extras->contains("material") && (*extras)["material"].is_number_integer()) {
        if ((*extras)["material"].get<int>() == source) found.push_back(j);
      } else if (extras->contains("atlas") && (*extras)["atlas"].is_number_integer() &&
                 materials[j].value("name", std::string()) ==
                     sourceName + format("_lightmap%d", (*extras)["atlas"].get<int>())) {
        found.push_back(j);
      }
    }
    return found;
  }

  // MOZ_lightmap.extras.afterglow of a lightmapped copy, or null.
  static const json* copyExtras(const json& material) {
    if (!material.is_object() || !material.contains("extensions") ||
        !material["extensions"].is_object() ||
        !material["extensions"].contains("MOZ_lightmap"))
      return nullptr;
    const json& lightmap = material["extensions"]["MOZ_lightmap"];
    if (!lightmap.is_object() || !lightmap.contains("extras") ||
        !lightmap["extras"].is_object() || !lightmap["extras"].contains("afterglow") ||
        !lightmap["extras"]["afterglow"].is_object())
      return nullptr;
    return &lightmap["extras"]["afterglow"];
  }
};

// The relit light probes' two files: OUT/probes/light_probes.json as the bake wrote it (the
// placement: positions, kinds, names, tetrahedra), its settings noting the relight under
// "relight", and the runtime's relit SH, deringed with the window the bake's SH were.
struct RelitProbes {
  std::string text;  // empty: OUT has no probes file to relight (a warning says so)
  std::string sh;
};

Result<RelitProbes> relightProbes(const fs::path& in, const runtime::Runtime& rt,
                                  const json& relightNote, std::vector<std::string>& warnings) {
  const std::string path = (in / "probes" / "light_probes.json").string();
  RelitProbes out;
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    warnings.push_back(format("the transport has %d light probes but %s is missing; the relit "
                              "probes are not written", rt.probeCount(), path.c_str()));
    return out;
  }
  Result<std::string> text = readFile(path);
  if (!text) return text.status();
  // Checked as `bake --probes` checks it, and against the transport it was baked with.
  Result<probes::ProbesFile> file = probes::parseProbesFile(text.value(), path);
  if (!file) return file.status();
  if (file->positions.size() != size_t(rt.probeCount()))
    return Status::error(format("%s: %zu probes, but the transport has %d", path.c_str(),
                                file->positions.size(), rt.probeCount()));
  for (int i = 0; i < rt.probeCount(); ++i)
    if (file->positions[size_t(i)] != rt.probePosition(i))
      return Status::error(format("%s: probe %d is not where the transport's is", path.c_str(), i));
  json doc = json::parse(text.value());
  const json sh = doc.value("sh", json::object());
  const json window = sh.is_object() ? sh.value("deringWindow", json(0.0)) : json(0.0);
  if (!window.is_number() || !(window.get<double>() >= 0.0) || !(window.get<double>() < 1e6))
    return Status::error(path + ": sh.deringWindow is not a window: " + window.dump());
  if (!doc["settings"].is_object()) doc["settings"] = json::object();
  doc["settings"]["relight"] = relightNote;

  runtime::ProbeShFile shFile;
  shFile.deringWindow = window.get<float>();
  shFile.sh.resize(size_t(rt.probeCount()));
  for (int i = 0; i < rt.probeCount(); ++i) {
    rt.probeSh(i, &shFile.sh[size_t(i)]);
    if (shFile.deringWindow > 0.0f)
      shFile.sh[size_t(i)] = runtime::deringed(shFile.sh[size_t(i)], shFile.deringWindow);
  }
  const std::vector<uint8_t> bytes = runtime::serializeProbeSh(shFile);
  out.text = doc.dump() + "\n";
  out.sh.assign(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  return out;
}

MaterialMap mapMaterials(const json& gltf, int transportMaterials) {
  MaterialMap map;
  if (gltf.contains("materials") && gltf["materials"].is_array())
    for (const json& m : gltf["materials"]) {
      if (m.is_object() && m.contains("extensions") && m["extensions"].is_object() &&
          m["extensions"].contains("MOZ_lightmap"))
        break;
      ++map.originals;
    }
  if (size_t(transportMaterials) == map.originals + 1) {
    map.defaultIndex = transportMaterials - 1;
  } else if (size_t(transportMaterials) != map.originals) {
    map.problem = format("scene.gltf has %zu materials before its lightmapped copies, the "
                         "transport %d, so they cannot be matched",
                         map.originals, transportMaterials);
  }
  return map;
}

}  // namespace

int runRelight(int argc, char** argv, int first) {
  const Command command = {"relight", "relight", kRelightHelp};
  auto usage = [&](const std::string& message) { return command.usage(message); };
  Args args;
  if (std::optional<int> stop = parseOrExit(args, argc, argv, first, kRelightOptions, command))
    return *stop;
  if (args.positional().size() != 1) return usage("give one bake folder OUT/");
  if (!args.has("output")) return usage("-o RELIT/ is required");
  const fs::path in = args.positional()[0];
  const fs::path outDir = args.get("output");
  const bool quiet = args.has("quiet");
  std::error_code ec;
  if (fs::equivalent(in, outDir, ec)) return usage("RELIT/ must not be the bake folder itself");

  // The bake's report: how it solved (bounces) and what it recorded, carried into ours.
  const fs::path reportPath = in / "report.json";
  Result<std::string> reportText = readFile(reportPath.string());
  if (!reportText) {
    printError(reportText.message() + " (is " + in.string() + " a bake folder?)");
    return kExitBadInput;
  }
  json report = json::parse(reportText.value(), nullptr, false);
  if (report.is_discarded() || !report.is_object() || !report.value("settings", json()).is_object()) {
    printError(reportPath.string() + ": not a bake report");
    return kExitBadInput;
  }
  json& settings = report["settings"];
  const Result<int> baked = bakefiles::bakedBounces(settings, reportPath.string());
  if (!baked) {
    printError(baked.message());
    return kExitBadInput;
  }
  int bounces = baked.value();
  if (!args.getInt("bounces", bounces, 0, 100000, &bounces)) return usage(args.error());

  auto t0 = Clock::now();
  const std::string transportPath = (in / "transport.agt").string();
  std::string error;
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::load(transportPath, &error);
  if (!rt) {
    printError(error);
    return kExitBadInput;
  }
  const double loadSeconds = secondsSince(t0);
  if (interrupted()) return interruptedExit();

  Result<std::string> gltfText = readFile((in / "scene.gltf").string());
  if (!gltfText) {
    printError(gltfText.message());
    return kExitBadInput;
  }
  json gltf = json::parse(gltfText.value(), nullptr, false);
  if (gltf.is_discarded() || !gltf.is_object()) {
    printError((in / "scene.gltf").string() + ": not valid JSON");
    return kExitBadInput;
  }
  // The bake exports lights and materials in the transport's order.
  json* gltfLights = nullptr;
  if (gltf.contains("extensions") && gltf["extensions"].contains("KHR_lights_punctual"))
    gltfLights = &gltf["extensions"]["KHR_lights_punctual"]["lights"];
  auto gltfLight = [&](int i) -> json* {
    return gltfLights && gltfLights->is_array() && size_t(i) < gltfLights->size()
               ? &(*gltfLights)[size_t(i)] : nullptr;
  };
  const MaterialMap materialMap = mapMaterials(gltf, rt->materialCount());

  json changes = json::array();
  auto findLight = [&](const std::string& option, const std::string& name, int* light) {
    *light = resolve(name, rt->lightCount(), &runtime::Runtime::findLight, *rt);
    if (*light < 0) {
      error = "--" + option + ": no light '" + name + "' in " + transportPath + " (lights: " +
              nameList(rt->lightCount(), [&](int i) { return rt->lightName(i); }) + ")";
      return false;
    }
    return true;
  };
  auto findMaterial = [&](const std::string& option, const std::string& name, int* material) {
    *material = resolve(name, rt->materialCount(), &runtime::Runtime::findMaterial, *rt);
    if (*material < 0) {
      error = "--" + option + ": no material '" + name + "' in " + transportPath +
              " (materials: " + nameList(rt->materialCount(), [&](int i) { return rt->materialName(i); }) + ")";
      return false;
    }
    return true;
  };
  std::string name, value;
  std::vector<float> v;
  for (const std::string& a : args.getAll("light")) {
    int light = -1;
    if (!splitAssignment(a, name, value) || !parseFloats(value, v) || v.size() < 3 || v.size() > 4)
      return usage("--light wants NAME=r,g,b[,intensity], got '" + a + "'");
    if (!findLight("light", name, &light)) return usage(error);
    const glm::vec3 color(v[0], v[1], v[2]);
    rt->setLightColor(light, color);
    if (json* l = gltfLight(light)) (*l)["color"] = {color.r, color.g, color.b};
    if (v.size() == 4) {
      rt->setLightIntensity(light, v[3]);
      if (json* l = gltfLight(light)) (*l)["intensity"] = v[3];
    }
    changes.push_back({{"light", rt->lightName(light)}, {"color", {color.r, color.g, color.b}},
                       {"intensity", rt->lightIntensity(light)}});
  }
  for (const std::string& a : args.getAll("intensity")) {
    int light = -1;
    if (!splitAssignment(a, name, value) || !parseFloats(value, v) || v.size() != 1)
      return usage("--intensity wants NAME=i, got '" + a + "'");
    if (!findLight("intensity", name, &light)) return usage(error);
    rt->setLightIntensity(light, v[0]);
    if (json* l = gltfLight(light)) (*l)["intensity"] = v[0];
    changes.push_back({{"light", rt->lightName(light)}, {"intensity", v[0]}});
  }
  for (const std::string& a : args.getAll("bounce")) {
    int light = -1;
    if (!splitAssignment(a, name, value) || !parseFloats(value, v) || v.size() != 1 || v[0] < 0)
      return usage("--bounce wants NAME=x with x >= 0, got '" + a + "'");
    if (!findLight("bounce", name, &light)) return usage(error);
    rt->setBounceIntensity(light, v[0]);
    if (json* l = gltfLight(light)) (*l)["extras"]["afterglow"]["bounceIntensity"] = v[0];
    changes.push_back({{"light", rt->lightName(light)}, {"bounceIntensity", v[0]}});
  }
  for (const std::string& a : args.getAll("disable")) {
    int light = -1;
    if (!findLight("disable", a, &light)) return usage(error);
    rt->setLightEnabled(light, false);
    if (json* l = gltfLight(light)) (*l)["intensity"] = 0.0f;
    changes.push_back({{"light", rt->lightName(light)}, {"enabled", false}});
  }
  if (args.has("sky")) {
    if (!parseFloats(args.get("sky"), v) || v.size() != 3)
      return usage("--sky wants r,g,b, got '" + args.get("sky") + "'");
    rt->setSky(glm::vec3(v[0], v[1], v[2]));
    settings["sky"] = {v[0], v[1], v[2]};
    settings["skyImage"] = "";
    changes.push_back({{"sky", {v[0], v[1], v[2]}}});
  }
  // --albedo sets the bounce albedo; the glTF gets the base colour giving it, on the material
  // and on the bake's lightmapped copies of it, with the material's other factors read back
  // through the importer (as the bake reads them). Loaded on the first --albedo only.
  std::optional<scenes::Scene> bakedScene;
  std::vector<std::string> warnings;
  for (const std::string& a : args.getAll("albedo")) {
    int material = -1;
    if (!splitAssignment(a, name, value) || !parseFloats(value, v) || v.size() != 3)
      return usage("--albedo wants MAT=r,g,b, got '" + a + "'");
    if (!findMaterial("albedo", name, &material)) return usage(error);
    const glm::vec3 albedo(v[0], v[1], v[2]);
    rt->setAlbedo(material, albedo);
    json change = {{"material", rt->materialName(material)}, {"albedo", {v[0], v[1], v[2]}}};
    if (!bakedScene) {
      scenes::LoadOptions load;
      load.loadTextures = false;
      Result<scenes::Scene> loaded = scenes::loadGltf((in / "scene.gltf").string(), load);
      if (!loaded) {
        printError(loaded.message());
        return kExitBadInput;
      }
      bakedScene = std::move(loaded.value());
    }
    const std::string label = "material '" + rt->materialName(material) + "'";
    const std::vector<size_t> targets = materialMap.gltfMaterials(gltf, material);
    if (targets.empty()) {
      warnings.push_back(label + ": " + materialMap.why() +
                         "; its base colour is not written, so a bake of RELIT/scene.gltf will "
                         "differ from these lightmaps");
      changes.push_back(change);
      continue;
    }
    const scenes::Material& params = bakedScene->material(materialMap.sceneMaterial(material));
    glm::vec3 base;
    const bool invertible = scenes::baseColorForAlbedoFactor(params, albedo, &base);
    if (!invertible) {
      base = glm::clamp(albedo, glm::vec3(0.0f), glm::vec3(1.0f));
      const std::string albedoText = format("%g, %g, %g", v[0], v[1], v[2]);
      if (base == albedo)
        warnings.push_back(format(
            "%s: no base colour in [0, 1] gives bounce albedo %s with its metallic %g, roughness "
            "%g and specular; RELIT/scene.gltf makes it Lambertian (metallicFactor 0, "
            "KHR_materials_specular specularFactor 0, base colour = the albedo), so a bake of it "
            "gives these lightmaps", label.c_str(), albedoText.c_str(),
            double(params.metallicFactor), double(params.roughnessFactor)));
      else
        warnings.push_back(format(
            "%s: bounce albedo %s is outside [0, 1], which no glTF material reflects; "
            "RELIT/scene.gltf makes it Lambertian with base colour %g, %g, %g (clamped), so a "
            "bake of it will differ from these lightmaps", label.c_str(), albedoText.c_str(),
            double(base.r), double(base.g), double(base.b)));
    }
    for (size_t j : targets) {
      json& m = gltf["materials"][j];
      json& pbr = m["pbrMetallicRoughness"];
      json& factor = pbr["baseColorFactor"];
      const float alpha = factor.is_array() && factor.size() == 4 && factor[3].is_number()
                              ? factor[3].get<float>() : 1.0f;
      factor = {base.r, base.g, base.b, alpha};
      if (!invertible) {
        pbr["metallicFactor"] = 0.0f;
        m["extensions"]["KHR_materials_specular"]["specularFactor"] = 0.0f;
        json& used = gltf["extensionsUsed"];
        if (!used.is_array()) used = json::array();
        if (std::find(used.begin(), used.end(), "KHR_materials_specular") == used.end())
          used.push_back("KHR_materials_specular");
      }
    }
    change["baseColorFactor"] = {base.r, base.g, base.b};
    change["lambertian"] = !invertible;
    changes.push_back(change);
  }
  for (const std::string& a : args.getAll("emission")) {
    int material = -1;
    if (!splitAssignment(a, name, value) || !parseFloats(value, v) || v.size() != 3)
      return usage("--emission wants MAT=r,g,b, got '" + a + "'");
    if (!findMaterial("emission", name, &material)) return usage(error);
    if (!rt->setEmission(material, glm::vec3(v[0], v[1], v[2])))
      return usage("--emission: material '" + rt->materialName(material) +
                   "' was not emissive when baked, so its light was never traced (bake it with "
                   "some emission to relight it)");
    const std::vector<size_t> targets = materialMap.gltfMaterials(gltf, material);
    if (targets.empty())
      warnings.push_back("material '" + rt->materialName(material) + "': " + materialMap.problem +
                         "; its emission is not written, so a bake of RELIT/scene.gltf will "
                         "differ from these lightmaps");
    for (size_t j : targets) {
      json& m = gltf["materials"][j];
      m["emissiveFactor"] = {v[0], v[1], v[2]};
      if (m.contains("extensions")) m["extensions"].erase("KHR_materials_emissive_strength");
    }
    changes.push_back(
        {{"material", rt->materialName(material)}, {"emission", {v[0], v[1], v[2]}}});
  }
  float indirect = rt->indirectIntensity();
  if (!args.getFloat("indirect-intensity", indirect, -1e-30f, 1e6f, &indirect))
    return usage(args.error());
  if (args.has("indirect-intensity")) {
    rt->setIndirectIntensity(indirect);
    settings["indirectIntensity"] = indirect;
    changes.push_back({{"indirectIntensity", indirect}});
  }

  // From scratch, with the bake's stopping rule: the same passes a fresh bake with these
  // settings runs, so the lightmaps agree with it. Then every reflection probe's every capture
  // pass (a full round: the bake's solveReflectionProbes, in its order) from those lightmaps,
  // so the cubemaps agree with the bake's too.
  runtime::UpdateOptions update;
  update.maxBounces = bounces;
  update.fromScratch = true;
  update.reflectionPasses = -1;
  const runtime::UpdateStats stats = rt->update(update);
  if (interrupted()) return interruptedExit();

  std::optional<RelitProbes> relitProbes;
  if (rt->probeCount() > 0) {
    const json note = {{"from", fs::absolute(in).string()},
                       {"changes", changes},
                       {"bounces", stats.bounces},
                       {"converged", stats.converged}};
    Result<RelitProbes> made = relightProbes(in, *rt, note, warnings);
    if (!made) {
      printError(made.message());
      return kExitBadInput;
    }
    if (!made->text.empty()) relitProbes = std::move(made.value());
  }

  AtomicOutput files;
  std::vector<glm::vec3> image;
  json atlases = json::array();
  for (int a = 0; a < rt->atlasCount(); ++a) {
    rt->readAtlas(a, image);
    const int w = rt->atlasWidth(a), h = rt->atlasHeight(a);
    const std::string exr = format("lightmaps/lightmap%d.exr", a);
    const std::string png = format("lightmaps/lightmap%d.png", a);
    std::vector<uint8_t> covered(image.size(), 0);
    const std::vector<uint32_t>& texelOf = rt->data().atlases[size_t(a)].texelOfPixel;
    for (size_t p = 0; p < covered.size() && p < texelOf.size(); ++p)
      covered[p] = texelOf[p] != runtime::kNoTexel;
    const float exposure = bakefiles::autoExposure(image, covered);
    Status s = bakefiles::writeExr((outDir / exr).string(), w, h, image, files);
    if (s) s = bakefiles::writeTonemappedPng((outDir / png).string(), w, h, image, exposure, files);
    if (!s) {
      printError(s.message());
      return kExitOutput;
    }
    atlases.push_back({{"width", w}, {"height", h}, {"exr", exr}, {"png", png},
                       {"previewExposure", exposure}});
  }
  // The glTF and its buffer, so render finds geometry, lights and the relit lightmaps alike;
  // the level's own textures stay where they are, referred to from RELIT/.
  if (gltf.contains("images"))
    for (json& image : gltf["images"]) {
      const std::string uri = image.value("uri", std::string());
      if (uri.empty() || uri.rfind("data:", 0) == 0 || uri.rfind("lightmaps/", 0) == 0 ||
          fs::path(uri).is_absolute())
        continue;
      image["uri"] = fs::proximate(fs::absolute(in / uri), fs::absolute(outDir)).generic_string();
    }
  Status s = Status::ok();
  if (gltf.contains("buffers"))
    for (const json& b : gltf["buffers"]) {
      const std::string uri = b.value("uri", std::string());
      if (uri.empty() || uri.rfind("data:", 0) == 0) continue;
      Result<std::string> bytes = readFile((in / uri).string());
      if (!bytes) {
        printError(bytes.message());
        return kExitBadInput;
      }
      if (s = files.write((outDir / uri).string(), bytes.value()); !s) break;
    }
  if (s && relitProbes) {
    const fs::path dir = outDir / "probes";
    s = files.write((dir / "light_probes.json").string(), relitProbes->text);
    if (s) s = files.write((dir / "light_probes_sh.bin").string(), relitProbes->sh);
  }
  // The relit reflection probes, through the bake's own writer: the cube EXRs, dfg.exr,
  // reflection_probes.json and the sky's EXT_lights_image_based, replacing the bake's (whose
  // images the loop above pointed back into OUT/) in the glTF written below.
  std::vector<std::string> reflectionFiles;
  if (s && rt->reflectionProbeCount() > 0) {
    std::vector<runtime::CubemapChain> chains;
    for (int p = 0; p < rt->reflectionProbeCount(); ++p) chains.push_back(rt->reflectionChain(p));
    s = bakefiles::writeReflectionOutputs(rt->data(), chains, rt->dfgTable(), outDir.string(), gltf,
                                      files, reflectionFiles);
  }
  if (s) s = files.write((outDir / "scene.gltf").string(), gltf.dump(1) + "\n");
  report["relight"] = {{"from", fs::absolute(in).string()},
                       {"changes", changes},
                       {"bounces", stats.bounces},
                       {"converged", stats.converged},
                       {"probes", relitProbes ? rt->probeCount() : 0},
                       // The level's, as printed below (the sky's cubemap comes besides).
                       {"reflectionProbes", std::max(0, rt->reflectionProbeCount() - 1)},
                       {"reflectionPasses", stats.reflectionPasses},
                       {"reflectionMilliseconds", stats.reflectionMilliseconds},
                       {"loadSeconds", loadSeconds},
                       {"updateMilliseconds", stats.milliseconds},
                       {"warnings", warnings}};
  report["atlases"] = atlases;
  if (s) s = files.write((outDir / "report.json").string(), report.dump(2) + "\n");
  if (s && interrupted()) return interruptedExit();
  if (s) s = files.commit();
  if (!s) {
    printError(s.message());
    return kExitOutput;
  }
  if (!quiet) {
    std::printf("loaded        %s in %.3f s (%d texels, %d lights, %d materials)\n",
                transportPath.c_str(), loadSeconds, rt->texelCount(), rt->lightCount(),
                rt->materialCount());
    std::printf("solved        %d bounces%s in %.1f ms\n", stats.bounces,
                stats.converged ? " (converged)" : "", stats.milliseconds);
    if (stats.reflectionPasses > 0)
      std::printf("reflections   %d probes and the sky, %d capture passes in %.1f ms\n",
                  rt->reflectionProbeCount() - 1, stats.reflectionPasses,
                  stats.reflectionMilliseconds);
    std::printf("wrote         %s (%d atlases, %d light probes, %d reflection probes)\n",
                outDir.string().c_str(), rt->atlasCount(), relitProbes ? rt->probeCount() : 0,
                std::max(0, rt->reflectionProbeCount() - 1));
    for (const std::string& w : warnings) std::printf("warning       %s\n", w.c_str());
  }
  return kExitOk;
}

}  // namespace afterglow::cli
