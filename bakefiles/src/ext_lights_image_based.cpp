#include "afterglow/bakefiles/ext_lights_image_based.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "afterglow/core/math.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::bakefiles {

namespace {

// Â_l per coefficient (Ramamoorthi & Hanrahan), and the sign each coefficient takes into
// Babylon's basis (Condon–Shortley phase) and frame (x negated): header.
constexpr float kCosineLobe[runtime::kShCount] = {kPi,        2 * kPi / 3, 2 * kPi / 3,
                                                  2 * kPi / 3, kPi / 4,     kPi / 4,
                                                  kPi / 4,     kPi / 4,     kPi / 4};
constexpr float kBabylonSign[runtime::kShCount] = {1, -1, 1, 1, -1, -1, 1, 1, 1};

// Babylon's gamma approximation (GammaEncodePowerApprox = 1/2.2, LinearEncodePowerApprox = 2.2).
constexpr float kRgbdGamma = 2.2f;

bool isPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

Status writeRgbdPng(const std::string& path, int size, const std::vector<uint8_t>& rgbd,
                    AtomicOutput& out) {
  OIIO::ImageSpec spec(size, size, 4, OIIO::TypeDesc::UINT8);
  // The alpha is RGBD's divisor, not coverage: without this OIIO un-premultiplies the colour.
  spec.attribute("oiio:UnassociatedAlpha", 1);
  const std::string temp = out.tempPath(path);
  auto writer = OIIO::ImageOutput::create("png");
  if (!writer) return Status::error(path + ": no PNG writer in OpenImageIO");
  if (!writer->open(temp, spec) || !writer->write_image(OIIO::TypeDesc::UINT8, rgbd.data()) ||
      !writer->close())
    return Status::error(path + ": cannot write: " + writer->geterror());
  return Status::ok();
}

Status checkMips(const std::vector<runtime::Cubemap>& mips) {
  if (mips.empty()) return Status::error("EXT_lights_image_based: no specular mips");
  const int size = mips[0].size;
  if (!isPowerOfTwo(size))
    return Status::error(format("EXT_lights_image_based: the specular size %d is not a power "
                                "of two (the extension's rule; Babylon.js refuses it)",
                                size));
  for (size_t m = 0; m < mips.size(); ++m) {
    const int expected = m < 31 ? size >> m : 0;
    if (expected < 1 || mips[m].size != expected)
      return Status::error(format("EXT_lights_image_based: mip %zu has size %d, not %d (each "
                                  "mip halves the one before)",
                                  m, mips[m].size, expected));
    if (mips[m].texels.size() !=
        size_t(runtime::kCubeFaceCount) * size_t(expected) * size_t(expected))
      return Status::error(format("EXT_lights_image_based: mip %zu has %zu texels, not 6 × %d²",
                                  m, mips[m].texels.size(), expected));
    for (const glm::vec3& t : mips[m].texels)
      if (!std::isfinite(t.x) || !std::isfinite(t.y) || !std::isfinite(t.z))
        return Status::error(format("EXT_lights_image_based: mip %zu has a texel that is not "
                                    "finite",
                                    m));
  }
  return Status::ok();
}

}  // namespace

std::array<glm::vec3, runtime::kShCount> extLightsIrradianceCoefficients(
    const runtime::ShL2& radianceSh) {
  std::array<glm::vec3, runtime::kShCount> c{};
  for (int i = 0; i < runtime::kShCount; ++i)
    c[size_t(i)] = kCosineLobe[i] * kBabylonSign[i] * radianceSh.c[i];
  return c;
}

std::array<uint8_t, 4> encodeRgbd(glm::vec3 linear) {
  for (int k = 0; k < 3; ++k)
    if (!(linear[k] > 0.0f)) linear[k] = 0.0f;  // negative and NaN
  const float maxRgb = std::max(1e-7f, std::max(linear.r, std::max(linear.g, linear.b)));
  // D = floor(max(255 / max, 1)) / 255: the largest divisor that keeps the colour ≤ 1.
  const float steps = std::min(255.0f, std::floor(std::max(255.0f / maxRgb, 1.0f)));
  const float d = steps / 255.0f;
  std::array<uint8_t, 4> out{};
  for (int k = 0; k < 3; ++k) {
    const float encoded = std::pow(std::min(1.0f, linear[k] * d), 1.0f / kRgbdGamma);
    out[size_t(k)] = uint8_t(std::lround(encoded * 255.0f));
  }
  out[3] = uint8_t(steps);
  return out;
}

glm::vec3 decodeRgbd(const std::array<uint8_t, 4>& rgbd) {
  const float d = float(std::max<uint8_t>(rgbd[3], 1)) / 255.0f;
  glm::vec3 c;
  for (int k = 0; k < 3; ++k) c[k] = std::pow(float(rgbd[size_t(k)]) / 255.0f, kRgbdGamma) / d;
  return c;
}

runtime::CubeTexel extLightsFaceTexel(int slot, int column, int row, int size) {
  const int flippedRow = size - 1 - row, flippedColumn = size - 1 - column;
  switch (slot) {
    case 0: return {runtime::kCubeFaceNegX, column, flippedRow};
    case 1: return {runtime::kCubeFacePosX, column, flippedRow};
    case 2: return {runtime::kCubeFacePosY, flippedColumn, row};
    case 3: return {runtime::kCubeFaceNegY, flippedColumn, row};
    case 4: return {runtime::kCubeFacePosZ, column, flippedRow};
    default: return {runtime::kCubeFaceNegZ, column, flippedRow};
  }
}

float babylonRoughnessOfMip(int mip, int mipCount, int size) {
  if (mipCount <= 1 || size <= 1) return 0.0f;
  const float m = std::clamp(float(mip) / float(mipCount - 1), 0.0f, 1.0f);
  const float alpha = std::pow(float(size), m - 1.0f);
  return std::sqrt(alpha);
}

Result<std::vector<std::string>> attachImageBasedLight(
    json& doc, const std::string& outDir, const runtime::ShL2& skyRadianceSh,
    const std::vector<runtime::Cubemap>& specularMips, AtomicOutput& out,
    const ImageBasedLightOptions& options) {
  using R = Result<std::vector<std::string>>;
  if (Status s = checkMips(specularMips); !s) return s;
  for (const glm::vec3& c : skyRadianceSh.c)
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
      return R::error("EXT_lights_image_based: the sky's SH is not finite");
  if (!std::isfinite(options.intensity))
    return R::error("EXT_lights_image_based: the intensity is not finite");
  if (!doc.contains("scenes") || !doc["scenes"].is_array() || doc["scenes"].empty())
    return R::error("EXT_lights_image_based: the glTF has no scene to light");

  // Every face of every mip, written before the document is touched.
  std::vector<std::string> written;
  json imageEntries = json::array();
  const int size0 = specularMips[0].size;
  for (size_t m = 0; m < specularMips.size(); ++m) {
    const runtime::Cubemap& cube = specularMips[m];
    const int n = cube.size;
    for (int slot = 0; slot < runtime::kCubeFaceCount; ++slot) {
      std::vector<uint8_t> rgbd(size_t(n) * size_t(n) * 4);
      for (int row = 0; row < n; ++row)
        for (int column = 0; column < n; ++column) {
          const runtime::CubeTexel t = extLightsFaceTexel(slot, column, row, n);
          const std::array<uint8_t, 4> px = encodeRgbd(cube.at(t.face, t.x, t.y));
          std::copy(px.begin(), px.end(), rgbd.begin() + (ptrdiff_t(row) * n + column) * 4);
        }
      const std::string uri = (fs::path(options.imageFolder) /
                               format("%s_m%zu_f%d.png", options.imagePrefix.c_str(), m, slot))
                                  .generic_string();
      const std::string path = (fs::path(outDir) / uri).string();
      if (Status s = writeRgbdPng(path, n, rgbd, out); !s) return s;
      written.push_back(path);
      imageEntries.push_back({{"uri", uri},
                              {"mimeType", "image/png"},
                              {"name", format("%s_m%zu_f%d", options.imagePrefix.c_str(), m,
                                              slot)}});
    }
  }

  json& images = doc["images"];
  if (!images.is_array()) images = json::array();
  json specularImages = json::array();
  for (size_t m = 0; m < specularMips.size(); ++m) {
    json faces = json::array();
    for (int slot = 0; slot < runtime::kCubeFaceCount; ++slot) {
      faces.push_back(images.size());
      images.push_back(imageEntries[m * runtime::kCubeFaceCount + size_t(slot)]);
    }
    specularImages.push_back(std::move(faces));
  }
  json coefficients = json::array();
  for (const glm::vec3& c : extLightsIrradianceCoefficients(skyRadianceSh))
    coefficients.push_back({c.r, c.g, c.b});

  json& root = doc["extensions"][kExtLightsImageBased]["lights"];
  if (!root.is_array()) root = json::array();
  const size_t light = root.size();
  root.push_back({{"name", options.name},
                  {"rotation", {0.0, 0.0, 0.0, 1.0}},
                  {"intensity", options.intensity},  // Babylon needs it: NaN SH without
                  {"irradianceCoefficients", std::move(coefficients)},
                  {"specularImageSize", size0},
                  {"specularImages", std::move(specularImages)}});
  for (json& scene : doc["scenes"])
    scene["extensions"][kExtLightsImageBased] = {{"light", light}};
  json& used = doc["extensionsUsed"];
  if (!used.is_array()) used = json::array();
  if (std::find(used.begin(), used.end(), kExtLightsImageBased) == used.end())
    used.push_back(kExtLightsImageBased);
  return written;
}

namespace {

// Calls f on every image index a document refers to: textures' sources (glTF's and their
// extensions', e.g. KHR_texture_basisu, EXT_texture_webp) and EXT_lights_image_based lights'
// specular faces (all lights, or those `keep` accepts).
template <class F, class Keep>
void forEachImageRef(json& doc, F f, Keep keep) {
  if (doc.contains("textures") && doc["textures"].is_array())
    for (json& t : doc["textures"]) {
      if (!t.is_object()) continue;
      if (t.contains("source") && t["source"].is_number_integer()) f(t["source"]);
      if (t.contains("extensions") && t["extensions"].is_object())
        for (auto& [key, ext] : t["extensions"].items())
          if (ext.is_object() && ext.contains("source") && ext["source"].is_number_integer())
            f(ext["source"]);
    }
  if (!doc.contains("extensions") || !doc["extensions"].is_object() ||
      !doc["extensions"].contains(kExtLightsImageBased))
    return;
  json& lights = doc["extensions"][kExtLightsImageBased]["lights"];
  if (!lights.is_array()) return;
  for (size_t i = 0; i < lights.size(); ++i) {
    if (!keep(i) || !lights[i].is_object() || !lights[i].contains("specularImages")) continue;
    for (json& mip : lights[i]["specularImages"])
      if (mip.is_array())
        for (json& face : mip)
          if (face.is_number_integer()) f(face);
  }
}

}  // namespace

size_t detachImageBasedLights(json& doc, const std::string& name) {
  if (!doc.is_object() || !doc.contains("extensions") || !doc["extensions"].is_object() ||
      !doc["extensions"].contains(kExtLightsImageBased))
    return 0;
  json& ext = doc["extensions"][kExtLightsImageBased];
  if (!ext.is_object() || !ext.contains("lights") || !ext["lights"].is_array()) return 0;
  json& lights = ext["lights"];
  std::vector<uint8_t> removed(lights.size(), 0);
  size_t count = 0;
  for (size_t i = 0; i < lights.size(); ++i)
    if (lights[i].is_object() && lights[i].value("name", std::string()) == name)
      removed[i] = 1, ++count;
  if (count == 0) return 0;

  // The images the removed lights use that nothing else does.
  const size_t imageCount = doc.contains("images") && doc["images"].is_array() ? doc["images"].size() : 0;
  std::vector<uint8_t> used(imageCount, 0), kept(imageCount, 0);
  auto mark = [&](std::vector<uint8_t>& into) {
    return [&into](json& ref) {
      const long long i = ref.get<long long>();
      if (i >= 0 && size_t(i) < into.size()) into[size_t(i)] = 1;
    };
  };
  forEachImageRef(doc, mark(used), [&](size_t light) { return removed[light] != 0; });
  // Textures are visited whatever `keep` says: only lights are filtered.
  forEachImageRef(doc, mark(kept), [&](size_t light) { return removed[light] == 0; });
  std::vector<long long> newIndex(imageCount, -1);
  long long next = 0;
  for (size_t i = 0; i < imageCount; ++i)
    if (!used[i] || kept[i]) newIndex[i] = next++;

  // Drop the lights and renumber the scenes' pointers.
  std::vector<long long> newLight(lights.size(), -1);
  json remaining = json::array();
  for (size_t i = 0; i < lights.size(); ++i)
    if (!removed[i]) {
      newLight[i] = (long long)remaining.size();
      remaining.push_back(std::move(lights[i]));
    }
  lights = std::move(remaining);
  if (doc.contains("scenes") && doc["scenes"].is_array())
    for (json& scene : doc["scenes"]) {
      if (!scene.is_object() || !scene.contains("extensions") || !scene["extensions"].is_object() ||
          !scene["extensions"].contains(kExtLightsImageBased))
        continue;
      json& ref = scene["extensions"][kExtLightsImageBased];
      const long long old = ref.is_object() && ref.contains("light") && ref["light"].is_number_integer()
                                ? ref["light"].get<long long>() : -1;
      if (old >= 0 && size_t(old) < newLight.size() && newLight[size_t(old)] >= 0) {
        ref["light"] = newLight[size_t(old)];
      } else {
        scene["extensions"].erase(kExtLightsImageBased);
        if (scene["extensions"].empty()) scene.erase("extensions");
      }
    }

  // Renumber what still refers to images (the remaining lights included), then drop them.
  forEachImageRef(doc, [&](json& ref) {
    const long long i = ref.get<long long>();
    if (i >= 0 && size_t(i) < newIndex.size()) ref = newIndex[size_t(i)];
  }, [](size_t) { return true; });
  if (imageCount > 0) {
    json images = json::array();
    for (size_t i = 0; i < imageCount; ++i)
      if (newIndex[i] >= 0) images.push_back(std::move(doc["images"][i]));
    doc["images"] = std::move(images);
    if (doc["images"].empty()) doc.erase("images");
  }

  if (lights.empty()) {
    doc["extensions"].erase(kExtLightsImageBased);
    if (doc["extensions"].empty()) doc.erase("extensions");
    if (doc.contains("extensionsUsed") && doc["extensionsUsed"].is_array()) {
      json& extUsed = doc["extensionsUsed"];
      extUsed.erase(std::remove(extUsed.begin(), extUsed.end(), json(kExtLightsImageBased)),
                    extUsed.end());
      if (extUsed.empty()) doc.erase("extensionsUsed");
    }
  }
  return count;
}

}  // namespace afterglow::bakefiles
