#include "afterglow/bakefiles/layout.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace afterglow::bakefiles {

std::string lightmapExr(size_t atlas) {
  return std::string(kLightmapsDir) + "/lightmap" + std::to_string(atlas) + ".exr";
}

std::string lightmapPng(size_t atlas) {
  return std::string(kLightmapsDir) + "/lightmap" + std::to_string(atlas) + ".png";
}

std::string directionalExr(size_t atlas, int axis, bool grid) {
  return std::string(kLightmapsDir) + (grid ? "/indirect" : "/lightmap") + std::to_string(atlas) +
         "_d" + "xyz"[axis] + ".exr";
}

std::string indirectExr(size_t atlas) {
  return std::string(kLightmapsDir) + "/indirect" + std::to_string(atlas) + ".exr";
}

std::string indirectPng(size_t atlas) {
  return std::string(kLightmapsDir) + "/indirect" + std::to_string(atlas) + ".png";
}

std::string shadowmaskPng(size_t atlas) {
  return std::string(kLightmapsDir) + "/shadowmask" + std::to_string(atlas) + ".png";
}

std::string reflectionExr(size_t chain) {
  return chain == 0 ? "reflection_sky.exr" : "reflection_" + std::to_string(chain) + ".exr";
}

std::string inFolder(const std::string& dir, const std::string& file) {
  return (fs::path(dir) / file).string();
}

std::string inProbes(const std::string& dir, const std::string& file) {
  return (fs::path(dir) / kProbesDir / file).string();
}

}  // namespace afterglow::bakefiles
