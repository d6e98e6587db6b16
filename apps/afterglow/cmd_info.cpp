// afterglow info: what afterglow makes of a scene, so a user can check a level before baking.
#include <cmath>
#include <cstdio>
#include <optional>
#include <set>
#include <vector>

#include "afterglow/scenes/scene.h"
#include "args.h"
#include "commands.h"
#include "common.h"

namespace afterglow::cli {

const char kInfoHelp[] =
    "Usage: afterglow info SCENE [options]\n"
    "\n"
    "Prints what afterglow loads from SCENE: instances, meshes, triangles (unique and\n"
    "instanced), materials, textures (loaded, failed, or kept as references only: normal and\n"
    "occlusion maps are not decoded), lights, cameras, lightmap UVs, bounds\n"
    "and size in metres, and every warning of the loader, and one when the level's sizes say it\n"
    "is in centimetres or millimetres rather than metres (glTF's unit), naming the fix.\n"
    "SCENE is a .gltf or .glb file, or a built-in scene: builtin:cornell,\n"
    "builtin:cornell-metal (mirror and copper blocks, a reflection probe), builtin:furnace.\n"
    "\n"
    "Options:\n"
    "  --no-textures   do not decode texture images (faster; they then count as skipped)\n"
    "  --unit-scale X  the level's metres per unit (0.01: centimetres, 0.001: millimetres):\n"
    "                  scales it first, as afterglow bake --unit-scale does (default 1)\n"
    "  -h, --help      this help\n";

namespace {

const char* lightTypeName(scenes::LightType type) {
  switch (type) {
    case scenes::LightType::Directional: return "directional";
    case scenes::LightType::Point: return "point";
    case scenes::LightType::Spot: return "spot";
  }
  return "?";
}

const char* lightUnit(scenes::LightType type) {
  return type == scenes::LightType::Directional ? "lx" : "cd";
}

// 1234567 -> "1,234,567": triangle counts are easier to read grouped.
std::string grouped(size_t n) {
  std::string digits = std::to_string(n), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

void printScene(const std::string& input, const scenes::Scene& scene) {
  size_t statics = 0;
  for (const scenes::Instance& inst : scene.instances) statics += inst.isStatic ? 1 : 0;
  std::printf("scene         %s\n", input.c_str());
  std::printf("instances     %zu (%zu static, %zu dynamic)\n", scene.instances.size(), statics,
              scene.instances.size() - statics);
  std::printf("meshes        %zu\n", scene.meshes.size());
  std::printf("triangles     %s unique, %s instanced\n", grouped(scene.meshTriangleCount()).c_str(),
              grouped(scene.instancedTriangleCount()).c_str());
  size_t emissive = 0;
  for (const scenes::Material& m : scene.materials) emissive += m.emissive() ? 1 : 0;
  std::printf("materials     %zu (%zu emissive)\n", scene.materials.size(), emissive);
  // Only textures that feed lighting are decoded; normal and occlusion maps stay references
  // for the exporter, so "not loaded" only means failure for the former.
  std::vector<bool> decodable(scene.textures.size(), false);
  auto mark = [&](const scenes::TextureRef& ref) {
    if (ref.valid() && ref.texture < int(decodable.size())) decodable[ref.texture] = true;
  };
  for (const scenes::Material& m : scene.materials) {
    mark(m.baseColorTexture);
    mark(m.metallicRoughnessTexture);
    mark(m.emissiveTexture);
  }
  size_t decoded = 0, failed = 0, references = 0;
  for (size_t i = 0; i < scene.textures.size(); ++i) {
    if (scene.textures[i].loaded())
      ++decoded;
    else if (decodable[i])
      ++failed;
    else
      ++references;
  }
  std::printf("textures      %zu (%zu loaded, %zu failed or skipped, %zu normal/occlusion kept as "
              "references)\n",
              scene.textures.size(), decoded, failed, references);
  for (size_t i = 0; i < scene.textures.size(); ++i) {
    const scenes::Texture& t = scene.textures[i];
    if (!t.loaded() && decodable[i])
      std::printf("  not loaded  %s%s%s\n", t.name.empty() ? "(unnamed)" : t.name.c_str(),
                  t.uri.empty() ? "" : " ", t.uri.c_str());
  }
  std::printf("lights        %zu\n", scene.lights.size());
  for (const scenes::Light& l : scene.lights) {
    std::printf("  %-11s '%s' %g %s, colour (%.3g, %.3g, %.3g)", lightTypeName(l.type),
                l.name.c_str(), double(l.intensity), lightUnit(l.type), double(l.color.r),
                double(l.color.g), double(l.color.b));
    if (l.type != scenes::LightType::Directional && l.range > 0.0f)
      std::printf(", range %g m", double(l.range));
    if (l.type == scenes::LightType::Spot)
      std::printf(", cone %.1f..%.1f deg", double(l.innerConeAngle) * 57.29577951308232,
                  double(l.outerConeAngle) * 57.29577951308232);
    if (l.bounceIntensity != 1.0f) std::printf(", bounceIntensity %g", double(l.bounceIntensity));
    std::printf("\n");
  }
  std::printf("cameras       %zu\n", scene.cameras.size());
  for (const scenes::Camera& c : scene.cameras) {
    if (c.perspective)
      std::printf("  perspective '%s' yfov %.1f deg\n", c.name.c_str(),
                  double(c.yfov) * 57.29577951308232);
    else
      std::printf("  orthographic '%s' %g x %g m\n", c.name.c_str(), 2.0 * double(c.xmag),
                  2.0 * double(c.ymag));
  }

  // Lightmap UVs: whether the static geometry already has TEXCOORD_1, and any recorded layout.
  size_t withUv1 = 0, withLightmap = 0;
  std::set<int> atlases;
  for (const scenes::Instance& inst : scene.instances) {
    if (!inst.isStatic || inst.mesh < 0 || inst.mesh >= int(scene.meshes.size())) continue;
    bool all = true;
    for (const scenes::Primitive& p : scene.meshes[inst.mesh].primitives)
      if (p.triangleCount() > 0 && p.uv1.size() != p.positions.size()) all = false;
    withUv1 += all ? 1 : 0;
    if (inst.lightmap.atlas >= 0) {
      ++withLightmap;
      atlases.insert(inst.lightmap.atlas);
    }
  }
  std::printf("lightmap UVs  %zu of %zu static instances have TEXCOORD_1", withUv1, statics);
  if (withLightmap > 0)
    std::printf("; %zu have extras.afterglow.lightmap in %zu atlas(es)", withLightmap,
                atlases.size());
  std::printf("\n");

  scenes::Bounds b = scene.bounds();
  if (b.empty()) {
    std::printf("bounds        empty\n");
  } else {
    glm::vec3 s = b.size();
    std::printf("bounds        (%.3f, %.3f, %.3f) to (%.3f, %.3f, %.3f)\n", double(b.min.x),
                double(b.min.y), double(b.min.z), double(b.max.x), double(b.max.y),
                double(b.max.z));
    std::printf("size          %.3f x %.3f x %.3f m\n", double(s.x), double(s.y), double(s.z));
    const float largest = std::max(s.x, std::max(s.y, s.z));
    // glTF is in metres. A level in centimetres or millimetres is told by what it holds and
    // warned about among the warnings (scenes/units.h); one this small is only hinted at.
    if (largest < 0.1f)
      std::printf("hint          the level is only %.3f m across: glTF is in metres; check the "
                  "exporter's unit scale\n",
                  double(largest));
  }
  std::printf("warnings      %zu\n", scene.warnings.size());
  for (const std::string& w : scene.warnings) std::printf("  %s\n", w.c_str());
}

}  // namespace

int runInfo(int argc, char** argv, int first) {
  const Command command = {"info", "info", kInfoHelp};
  Args args;
  if (std::optional<int> stop = parseOrExit(
          args, argc, argv, first,
          {{"no-textures", 0, false}, kUnitScaleOption, {"help", 'h', false}}, command))
    return *stop;
  float unitScale = 1.0f;
  if (!getUnitScale(args, &unitScale)) return command.usage(args.error());
  if (args.positional().size() != 1)
    return command.usage(args.positional().empty() ? "missing SCENE" : "one SCENE only");
  const std::string input = args.positional()[0];
  int code = kExitOk;
  Result<scenes::Scene> loaded = loadSceneOrExit(input, !args.has("no-textures"), &code);
  if (!loaded) return code;
  applyUnitScale(loaded.value(), unitScale, input);
  printScene(input, loaded.value());
  return kExitOk;
}

}  // namespace afterglow::cli
