// How a relight's material changes reach the bake's scene.gltf: which glTF materials carry a
// transport material, and the base colour or emission written into them, so a fresh bake of the
// relit scene.gltf gives the relit lightmaps.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "afterglow/core/status.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::bakefiles {

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

  // Why a material has no glTF material to write to.
  std::string why() const;
  // The scene material (Scene::material's index; -1 = the default) of a transport material.
  int sceneMaterial(int material) const { return material == defaultIndex ? -1 : material; }
  // The glTF materials (the original and its lightmapped copies) of a transport material.
  std::vector<size_t> gltfMaterials(const nlohmann::json& gltf, int material) const;
};
MaterialMap mapMaterials(const nlohmann::json& gltf, int transportMaterials);

// The bake's scene.gltf through the importer, without textures: the material factors as the
// bake read them.
Result<scenes::Scene> loadBakedScene(const std::string& bakeDir);

// What setAlbedo wrote.
struct MaterialEdit {
  bool written = false;    // false: no glTF material to write to (a warning says so)
  glm::vec3 baseColor{0.0f};
  bool lambertian = false;  // no base colour in [0, 1] gives the albedo
};
// Writes the base colour giving bounce albedo `albedo` (with the material's other factors, read
// from `baked`) on transport material `material`'s glTF materials, or makes them Lambertian
// where no base colour does; `label` names the material in the warnings.
MaterialEdit setAlbedo(nlohmann::json& gltf, const MaterialMap& map, const scenes::Scene& baked,
                       int material, const std::string& label, glm::vec3 albedo,
                       std::vector<std::string>& warnings);
// Writes the emitted radiance on transport material `material`'s glTF materials.
void setEmission(nlohmann::json& gltf, const MaterialMap& map, int material,
                 const std::string& label, glm::vec3 emission,
                 std::vector<std::string>& warnings);

}  // namespace afterglow::bakefiles
