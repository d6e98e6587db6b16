#include "relight_materials.h"

#include <algorithm>

#include "afterglow/bakefiles/layout.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/material_eval.h"

using nlohmann::json;

namespace afterglow::bakefiles {

namespace {

// MOZ_lightmap.extras.afterglow of a lightmapped copy, or null.
const json* copyExtras(const json& material) {
  if (!material.is_object() || !material.contains("extensions") ||
      !material["extensions"].is_object() || !material["extensions"].contains("MOZ_lightmap"))
    return nullptr;
  const json& lightmap = material["extensions"]["MOZ_lightmap"];
  if (!lightmap.is_object() || !lightmap.contains("extras") || !lightmap["extras"].is_object() ||
      !lightmap["extras"].contains("afterglow") || !lightmap["extras"]["afterglow"].is_object())
    return nullptr;
  return &lightmap["extras"]["afterglow"];
}

// Whether glTF material j (a copy) copies scene material `source` named `sourceName`.
bool copies(const json& material, int source, const std::string& sourceName) {
  const json* extras = copyExtras(material);
  if (!extras) return false;
  if (extras->contains("material") && (*extras)["material"].is_number_integer())
    return (*extras)["material"].get<int>() == source;
  return extras->contains("atlas") && (*extras)["atlas"].is_number_integer() &&
         material.value("name", std::string()) ==
             sourceName + format("_lightmap%d", (*extras)["atlas"].get<int>());
}

// The warning for an albedo no glTF base colour gives: the material is written Lambertian.
std::string lambertianWarning(const std::string& label, const scenes::Material& params,
                              glm::vec3 albedo, glm::vec3 base) {
  const std::string albedoText =
      format("%g, %g, %g", double(albedo.r), double(albedo.g), double(albedo.b));
  if (base == albedo)
    return format(
        "%s: no base colour in [0, 1] gives bounce albedo %s with its metallic %g, roughness "
        "%g and specular; RELIT/scene.gltf makes it Lambertian (metallicFactor 0, "
        "KHR_materials_specular specularFactor 0, base colour = the albedo), so a bake of it "
        "gives these lightmaps",
        label.c_str(), albedoText.c_str(), double(params.metallicFactor),
        double(params.roughnessFactor));
  return format(
      "%s: bounce albedo %s is outside [0, 1], which no glTF material reflects; "
      "RELIT/scene.gltf makes it Lambertian with base colour %g, %g, %g (clamped), so a "
      "bake of it will differ from these lightmaps",
      label.c_str(), albedoText.c_str(), double(base.r), double(base.g), double(base.b));
}

// Base colour `base` on glTF material j, its alpha kept; Lambertian also sets metallic and
// specular to 0.
void writeBaseColor(json& gltf, size_t j, glm::vec3 base, bool lambertian) {
  json& m = gltf["materials"][j];
  json& pbr = m["pbrMetallicRoughness"];
  json& factor = pbr["baseColorFactor"];
  const float alpha = factor.is_array() && factor.size() == 4 && factor[3].is_number()
                          ? factor[3].get<float>()
                          : 1.0f;
  factor = {base.r, base.g, base.b, alpha};
  if (!lambertian) return;
  pbr["metallicFactor"] = 0.0f;
  m["extensions"]["KHR_materials_specular"]["specularFactor"] = 0.0f;
  json& used = gltf["extensionsUsed"];
  if (!used.is_array()) used = json::array();
  if (std::find(used.begin(), used.end(), "KHR_materials_specular") == used.end())
    used.push_back("KHR_materials_specular");
}

}  // namespace

std::string MaterialMap::why() const {
  return problem.empty() ? std::string(kSceneGltf) + " has no material for it" : problem;
}

std::vector<size_t> MaterialMap::gltfMaterials(const json& gltf, int material) const {
  std::vector<size_t> found;
  if (!problem.empty() || !gltf.contains("materials") || !gltf["materials"].is_array())
    return found;
  const json& materials = gltf["materials"];
  const int source = sceneMaterial(material);
  const bool original = source >= 0 && size_t(source) < originals;
  if (original) found.push_back(size_t(source));
  const std::string sourceName =
      original && materials[size_t(source)].contains("name") &&
              materials[size_t(source)]["name"].is_string()
          ? materials[size_t(source)]["name"].get<std::string>()
          : format("material%d", source);
  for (size_t j = originals; j < materials.size(); ++j)
    if (copies(materials[j], source, sourceName)) found.push_back(j);
  return found;
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
    map.problem = format("%s has %zu materials before its lightmapped copies, the transport %d, "
                         "so they cannot be matched",
                         kSceneGltf, map.originals, transportMaterials);
  }
  return map;
}

Result<scenes::Scene> loadBakedScene(const std::string& bakeDir) {
  scenes::LoadOptions load;
  load.loadTextures = false;
  return scenes::loadGltf(inFolder(bakeDir, kSceneGltf), load);
}

MaterialEdit setAlbedo(json& gltf, const MaterialMap& map, const scenes::Scene& baked,
                       int material, const std::string& label, glm::vec3 albedo,
                       std::vector<std::string>& warnings) {
  MaterialEdit edit;
  const std::vector<size_t> targets = map.gltfMaterials(gltf, material);
  if (targets.empty()) {
    warnings.push_back(label + ": " + map.why() +
                       "; its base colour is not written, so a bake of RELIT/scene.gltf will "
                       "differ from these lightmaps");
    return edit;
  }
  const scenes::Material& params = baked.material(map.sceneMaterial(material));
  edit.written = true;
  edit.lambertian = !scenes::baseColorForAlbedoFactor(params, albedo, &edit.baseColor);
  if (edit.lambertian) {
    edit.baseColor = glm::clamp(albedo, glm::vec3(0.0f), glm::vec3(1.0f));
    warnings.push_back(lambertianWarning(label, params, albedo, edit.baseColor));
  }
  for (size_t j : targets) writeBaseColor(gltf, j, edit.baseColor, edit.lambertian);
  return edit;
}

void setEmission(json& gltf, const MaterialMap& map, int material, const std::string& label,
                 glm::vec3 emission, std::vector<std::string>& warnings) {
  const std::vector<size_t> targets = map.gltfMaterials(gltf, material);
  if (targets.empty())
    warnings.push_back(label + ": " + map.problem +
                       "; its emission is not written, so a bake of RELIT/scene.gltf will "
                       "differ from these lightmaps");
  for (size_t j : targets) {
    json& m = gltf["materials"][j];
    m["emissiveFactor"] = {emission.r, emission.g, emission.b};
    if (m.contains("extensions")) m["extensions"].erase("KHR_materials_emissive_strength");
  }
}

}  // namespace afterglow::bakefiles
