#include "afterglow/baker/bake_output.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "afterglow/core/memory.h"
#include "afterglow/runtime/transport_file.h"
#include "afterglow/scenes/gltf.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::baker {

namespace {

float luminance(glm::vec3 c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

float srgbEncode(float x) {
  x = std::clamp(x, 0.0f, 1.0f);
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

Status writeImage(const std::string& path, const std::string& format, const OIIO::ImageSpec& spec,
                  OIIO::TypeDesc dataType, const void* data, AtomicOutput& out) {
  const std::string temp = out.tempPath(path);
  auto writer = OIIO::ImageOutput::create(format);
  if (!writer) return Status::error(path + ": no " + format + " writer in OpenImageIO");
  if (!writer->open(temp, spec) || !writer->write_image(dataType, data) || !writer->close())
    return Status::error(path + ": cannot write: " + writer->geterror());
  return Status::ok();
}

// The glTF written by saveGltf, read back so the lightmaps can be attached.
struct SavedGltf {
  json doc;
  std::string bin;
};

Result<SavedGltf> saveAndReadGltf(const scenes::Scene& scene, const std::string& outDir) {
  // Saved beside the final file so texture URIs come out relative to the right folder; read
  // back and removed at once, then rewritten through the caller's AtomicOutput.
  const std::string tag = ".scene-export" + std::to_string(::getpid());
  const std::string gltfPath = (fs::path(outDir) / (tag + ".gltf")).string();
  const std::string binPath = (fs::path(outDir) / (tag + ".bin")).string();
  std::error_code ec;
  fs::create_directories(outDir, ec);
  Status st = scenes::saveGltf(scene, gltfPath);
  SavedGltf saved;
  Result<std::string> text = st ? readFile(gltfPath) : Result<std::string>(st);
  if (text && fs::exists(binPath)) {
    Result<std::string> bin = readFile(binPath);
    if (bin) saved.bin = std::move(bin.value());
    else text = bin.status();
  }
  fs::remove(gltfPath, ec);
  fs::remove(binPath, ec);
  if (!text) return text.status();
  saved.doc = json::parse(text.value(), nullptr, false);
  if (saved.doc.is_discarded()) return Status::error(gltfPath + ": the exporter wrote bad JSON");
  return saved;
}

// Gives every lightmapped primitive a material of its atlas carrying MOZ_lightmap (materials
// shared by instances in different atlases are duplicated; the originals stay for unlit users).
// Each copy names the material it copies in MOZ_lightmap.extras.afterglow.material (its glTF
// index, -1 for glTF's default material), so `relight` changes the copies with the original.
void attachLightmaps(json& doc, size_t atlasCount, std::vector<std::string>& warnings) {
  json& images = doc["images"];
  if (!images.is_array()) images = json::array();
  json& textures = doc["textures"];
  if (!textures.is_array()) textures = json::array();
  json& samplers = doc["samplers"];
  if (!samplers.is_array()) samplers = json::array();
  json& materials = doc["materials"];
  if (!materials.is_array()) materials = json::array();
  const int sampler = int(samplers.size());
  samplers.push_back({{"magFilter", 9729}, {"minFilter", 9729}, {"wrapS", 33071},
                      {"wrapT", 33071}});  // linear, clamp to edge
  std::vector<int> textureOfAtlas;
  json atlasList = json::array();
  for (size_t a = 0; a < atlasCount; ++a) {
    const std::string png = format("lightmaps/lightmap%zu.png", a);
    const std::string exr = format("lightmaps/lightmap%zu.exr", a);
    images.push_back({{"uri", png}, {"name", format("lightmap%zu", a)}});
    textureOfAtlas.push_back(int(textures.size()));
    textures.push_back({{"source", int(images.size()) - 1}, {"sampler", sampler}});
    atlasList.push_back({{"exr", exr}, {"png", png}});
  }
  doc["extras"]["afterglow"]["lightmaps"] = atlasList;

  std::map<std::pair<int, int>, int> materialFor;  // (material or -1, atlas) -> new index
  std::map<int, int> atlasOfMesh;
  const size_t originalMaterials = materials.size();
  if (!doc.contains("nodes")) return;
  for (const json& node : doc["nodes"]) {
    if (!node.contains("mesh")) continue;
    const json* lm = nullptr;
    if (node.contains("extras") && node["extras"].contains("afterglow") &&
        node["extras"]["afterglow"].contains("lightmap"))
      lm = &node["extras"]["afterglow"]["lightmap"];
    if (!lm || !lm->contains("atlas")) continue;
    const int atlas = (*lm)["atlas"].get<int>();
    if (atlas < 0 || size_t(atlas) >= atlasCount) continue;
    const int mesh = node["mesh"].get<int>();
    auto [it, inserted] = atlasOfMesh.emplace(mesh, atlas);
    if (!inserted) {
      if (it->second != atlas)
        warnings.push_back(format("glTF mesh %d is used by nodes in different atlases; its "
                                  "lightmap comes from atlas %d",
                                  mesh, it->second));
      continue;
    }
    for (json& prim : doc["meshes"][size_t(mesh)]["primitives"]) {
      if (!prim["attributes"].contains("TEXCOORD_1")) continue;
      const int m = prim.contains("material") ? prim["material"].get<int>() : -1;
      auto key = std::make_pair(m, atlas);
      auto found = materialFor.find(key);
      if (found == materialFor.end()) {
        json mat = m >= 0 && size_t(m) < originalMaterials ? materials[size_t(m)] : json::object();
        const std::string base = mat.contains("name") ? mat["name"].get<std::string>()
                                                      : format("material%d", m);
        mat["name"] = base + format("_lightmap%d", atlas);
        mat["extensions"]["MOZ_lightmap"] = {
            {"index", textureOfAtlas[size_t(atlas)]},
            {"texCoord", 1},
            {"intensity", 1.0},
            {"extras",
             {{"afterglow",
               {{"atlas", atlas},
                {"exr", format("lightmaps/lightmap%d.exr", atlas)},
                {"material", m}}}}}};
        found = materialFor.emplace(key, int(materials.size())).first;
        materials.push_back(std::move(mat));
      }
      prim["material"] = found->second;
    }
  }
  json& used = doc["extensionsUsed"];
  if (!used.is_array()) used = json::array();
  if (std::find(used.begin(), used.end(), "MOZ_lightmap") == used.end())
    used.push_back("MOZ_lightmap");
}

}  // namespace

float autoExposure(const std::vector<glm::vec3>& pixels, const std::vector<uint8_t>& mask) {
  std::vector<float> lum;
  lum.reserve(pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i)
    if (mask.empty() || mask[i]) {
      const float l = luminance(pixels[i]);
      if (std::isfinite(l) && l > 0.0f) lum.push_back(l);
    }
  if (lum.empty()) return 1.0f;
  const size_t k = std::min(lum.size() - 1, size_t(double(lum.size()) * 0.99));
  std::nth_element(lum.begin(), lum.begin() + std::ptrdiff_t(k), lum.end());
  // Reinhard x / (1 + x) = 0.8 at x = 4.
  return 4.0f / lum[k];
}

Status writeExr(const std::string& path, int width, int height,
                const std::vector<glm::vec3>& pixels, AtomicOutput& out, ExrPixels pixelType) {
  OIIO::ImageSpec spec(width, height, 3,
                       pixelType == ExrPixels::Float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::HALF);
  spec.attribute("compression", "zip");
  return writeImage(path, "exr", spec, OIIO::TypeDesc::FLOAT, pixels.data(), out);
}

Status writeTonemappedPng(const std::string& path, int width, int height,
                          const std::vector<glm::vec3>& pixels, float exposure,
                          AtomicOutput& out) {
  std::vector<uint8_t> bytes(pixels.size() * 3);
  for (size_t i = 0; i < pixels.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      float x = std::max(0.0f, pixels[i][k] * exposure);
      if (!std::isfinite(x)) x = 0.0f;
      const float mapped = x / (1.0f + x);
      bytes[i * 3 + size_t(k)] = uint8_t(std::lround(srgbEncode(mapped) * 255.0f));
    }
  }
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  return writeImage(path, "png", spec, OIIO::TypeDesc::UINT8, bytes.data(), out);
}

Result<std::vector<std::string>> writeBakeOutputs(const scenes::Scene& scene,
                                                  const BakeResult& result,
                                                  const std::string& outDir,
                                                  const BakeReportInfo& info, AtomicOutput& out) {
  std::vector<std::string> written;
  std::vector<std::string> warnings = info.warnings;
  warnings.insert(warnings.end(), result.warnings.begin(), result.warnings.end());
  const fs::path dir(outDir);
  const TexelSet& texels = result.texels;
  json atlases = json::array();
  for (size_t a = 0; a < result.lightmaps.size(); ++a) {
    const runtime::AtlasLayout& layout = texels.atlases[a];
    const std::vector<glm::vec3>& image = result.lightmaps[a];
    const std::string exr = (dir / "lightmaps" / format("lightmap%zu.exr", a)).string();
    const std::string png = (dir / "lightmaps" / format("lightmap%zu.png", a)).string();
    if (Status s = writeExr(exr, layout.width, layout.height, image, out); !s) return s;
    std::vector<uint8_t> covered(image.size(), 0);
    for (size_t p = 0; p < covered.size() && p < layout.texelOfPixel.size(); ++p)
      covered[p] = layout.texelOfPixel[p] != runtime::kNoTexel;
    const float exposure = autoExposure(image, covered);
    if (Status s = writeTonemappedPng(png, layout.width, layout.height, image, exposure, out); !s)
      return s;
    written.push_back(exr);
    written.push_back(png);
    atlases.push_back({{"width", layout.width},
                       {"height", layout.height},
                       {"exr", format("lightmaps/lightmap%zu.exr", a)},
                       {"png", format("lightmaps/lightmap%zu.png", a)},
                       {"previewExposure", exposure}});
  }

  Result<SavedGltf> saved = saveAndReadGltf(scene, outDir);
  if (!saved) return saved.status();
  json& doc = saved->doc;
  attachLightmaps(doc, result.lightmaps.size(), warnings);
  if (Status s = writeReflectionOutputs(result, outDir, doc, out, written); !s) return s;
  const std::string gltf = (dir / "scene.gltf").string();
  if (!saved->bin.empty()) {
    doc["buffers"][0]["uri"] = "scene.bin";
    const std::string bin = (dir / "scene.bin").string();
    if (Status s = out.write(bin, saved->bin); !s) return s;
    written.push_back(bin);
  }
  if (Status s = out.write(gltf, doc.dump(1) + "\n"); !s) return s;
  written.push_back(gltf);

  // The transport for the relighting runtime (a reference bake has none: it solved nothing).
  json transportInfo = nullptr;
  if (!result.transport.atlases.empty()) {
    const std::string path = (dir / "transport.agt").string();
    const std::string temp = out.tempPath(path);
    std::string error;
    // saveTransport's error starts with the path it wrote: name the final one instead.
    if (!runtime::saveTransport(result.transport, temp, &error))
      return Status::error(path + ": " + error.substr(std::min(error.size(), temp.size() + 2)));
    std::error_code ec;
    const uintmax_t bytes = fs::file_size(temp, ec);
    written.push_back(path);
    transportInfo = {{"file", "transport.agt"},
                     {"bytes", ec ? 0 : bytes},
                     {"bytesPerTexel", ec || texels.size() == 0
                                           ? 0.0
                                           : double(bytes) / double(texels.size())}};
  }

  size_t valid = 0;
  for (uint8_t v : texels.valid) valid += v ? 1 : 0;
  if (texels.valid.empty()) valid = texels.size();
  json stages = json::object();
  double total = 0.0;
  for (const StageTime& s : info.extraStages) {
    stages[s.name] = s.seconds;
    total += s.seconds;
  }
  json stageRays = json::object();
  for (const StageTime& s : result.stages) {
    stages[s.name] = s.seconds;
    total += s.seconds;
    if (s.rays > 0) stageRays[s.name] = s.rays;
  }
  stages["total"] = total;
  size_t lights = 0, emissive = 0;
  for (const runtime::Source& s : result.transport.sources)
    (s.kind == runtime::SourceKind::Light ? lights : emissive) += 1;
  json settings = json::parse(info.settingsJson, nullptr, false);
  json report;
  report["afterglowVersion"] = info.version;
  report["input"] = info.input;
  report["settings"] = settings.is_discarded() ? json::object() : settings;
  report["texels"] = texels.size();
  report["validTexels"] = valid;
  report["clusters"] = result.clusters.size();
  report["gatherPoints"] = result.transport.gatherPointCount;
  report["links"] = result.transport.linkCount();
  report["sources"] = {{"lights", lights}, {"emissiveMaterials", emissive}};
  report["raysTraced"] = result.raysTraced;
  report["stageRays"] = stageRays;
  report["transport"] = transportInfo;
  report["probes"] = {{"count", result.transport.probes.count()},
                      {"tetrahedra", result.transport.probes.mesh.tetrahedra.size()},
                      {"links", result.transport.probes.links.linkCount()},
                      {"transportBytes", result.transport.probeBytes()}};
  report["reflectionProbes"] = {{"count", result.transport.reflections.count()},
                                {"bounces", result.transport.reflections.bounces},
                                {"transportBytes", result.transport.reflectionBytes()}};
  report["stages"] = stages;
  report["peakMemoryBytes"] = peakMemoryBytes();
  report["atlases"] = atlases;
  report["warnings"] = warnings;
  const std::string reportPath = (dir / "report.json").string();
  if (Status s = out.write(reportPath, report.dump(2) + "\n"); !s) return s;
  written.push_back(reportPath);
  return written;
}

}  // namespace afterglow::baker
