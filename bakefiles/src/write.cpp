#include "afterglow/bakefiles/write.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include <nlohmann/json.hpp>

#include "afterglow/bakefiles/images.h"
#include "afterglow/bakefiles/layout.h"
#include "afterglow/core/memory.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "afterglow/runtime/transport_file.h"
#include "afterglow/scenes/gltf.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::bakefiles {

namespace {

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
    const std::string png = lightmapPng(a);
    const std::string exr = lightmapExr(a);
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
                {"exr", lightmapExr(size_t(atlas))},
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

Result<json> writeLightmaps(const std::vector<runtime::AtlasLayout>& layouts,
                           const std::vector<std::vector<glm::vec3>>& images,
                           const std::string& outDir, AtomicOutput& out,
                           std::vector<std::string>& written, AtlasKind kind) {
  json atlases = json::array();
  const bool grid = kind == AtlasKind::Indirect;
  for (size_t a = 0; a < images.size() && a < layouts.size(); ++a) {
    const runtime::AtlasLayout& layout = layouts[a];
    const std::vector<glm::vec3>& image = images[a];
    const std::string exrName = grid ? indirectExr(a) : lightmapExr(a);
    const std::string pngName = grid ? indirectPng(a) : lightmapPng(a);
    const std::string exr = inFolder(outDir, exrName);
    const std::string png = inFolder(outDir, pngName);
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
                       {"exr", exrName},
                       {"png", pngName},
                       {"previewExposure", exposure}});
    if (grid) atlases.back()["texCoord"] = 2;
  }
  return atlases;
}

Result<json> writeDirectionalLightmaps(
    const std::vector<runtime::AtlasLayout>& layouts,
    const std::vector<std::array<std::vector<glm::vec3>, 3>>& images, bool grid,
    const std::string& outDir, AtomicOutput& out, std::vector<std::string>& written) {
  json list = json::array();
  for (size_t a = 0; a < images.size() && a < layouts.size(); ++a) {
    json files = json::object();
    for (int axis = 0; axis < 3; ++axis) {
      const std::string name = directionalExr(a, axis, grid);
      const std::string path = inFolder(outDir, name);
      if (Status s = writeExr(path, layouts[a].width, layouts[a].height, images[a][size_t(axis)],
                              out, ExrPixels::Half);
          !s)
        return s;
      written.push_back(path);
      files[std::string(1, "xyz"[axis])] = name;
    }
    list.push_back(files);
  }
  return json{{"atlases", list},
              {"texCoord", grid ? 2 : 1},
              {"decode", "per channel, r = (dx*(n-n0).x + dy*(n-n0).y + dz*(n-n0).z) / lightmap, "
                         "E(n)/pi = lightmap * (r < -0.5 ? exp(2r + 1) / 2 : min(1 + r, 2)): n the shading "
                         "(normal-mapped) normal, n0 the interpolated vertex normal, world axes; "
                         "d* the bounced light's gradient with the normal"}};
}

Status writeLightProbes(const std::string& outDir, const ProbeSet& set,
                        const std::vector<runtime::ShL2>& sh,
                        const runtime::ProbeDirectionList& directions,
                        const std::vector<uint16_t>& depth, float dering,
                        const json& bakeSettings, AtomicOutput& out,
                        std::vector<std::string>& written) {
  probes::Placement placement;
  placement.positions = set.file.positions;
  placement.kinds = set.file.kinds;
  const json settings = {{"probes", bakeSettings.value("probes", "auto")},
                         {"spacing", set.spacing},
                         {"rays", bakeSettings.value("probeRays", 0)},
                         {"regions", bakeSettings.value("probeRegions", 0)},
                         {"emitterSamples", bakeSettings.value("probeEmitterSamples", 0)}};
  const json shInfo = {
      {"file", kLightProbesSh},
      {"format", "afterglow-light-probe-sh"},
      {"version", runtime::kProbeShVersion},
      {"basis", "real SH L2, bands 0-2, orthonormal (Y00 = 0.282095), world axes +Y up"},
      {"stores", "radiance SH L_i = integral of L(w) Y_i(w) dw, RGB; E/pi via the "
                 "clamped-cosine convolution (runtime/probe_sh.h)"},
      {"deringWindow", dering}};
  const std::string text = probes::probesJson(placement, set.file.names, set.file.mesh,
                                              settings.dump(), set.summary.dump(), shInfo.dump());
  runtime::ProbeShFile file;
  file.deringWindow = dering;
  file.sh = sh;
  file.directions = directions;
  file.depth = depth;
  if (dering > 0.0f)
    for (runtime::ShL2& s : file.sh) s = runtime::deringed(s, dering);
  const std::vector<uint8_t> bytes = runtime::serializeProbeSh(file);
  const std::string jsonPath = inProbes(outDir, kLightProbesJson);
  const std::string shPath = inProbes(outDir, kLightProbesSh);
  if (Status st = out.write(jsonPath, text); !st) return st;
  if (Status st = out.write(shPath, std::string(reinterpret_cast<const char*>(bytes.data()),
                                                bytes.size()));
      !st)
    return st;
  written.push_back(jsonPath);
  written.push_back(shPath);
  return Status::ok();
}

Status writeProbeOcclusion(const std::string& outDir, const std::vector<glm::vec4>& occlusion,
                           const json& channels, AtomicOutput& out,
                           std::vector<std::string>& written) {
  json values = json::array();
  for (const glm::vec4& o : occlusion) values.push_back({o.x, o.y, o.z, o.w});
  const json doc = {{"format", "afterglow-light-probe-occlusion"},
                    {"version", 1},
                    {"stores", "per light probe, in light_probes.json's order, the visible "
                               "fraction of the mixed light given each shadowmask channel (1 "
                               "where no light has it)"},
                    {"channels", channels},
                    {"occlusion", values}};
  const std::string path = inProbes(outDir, kLightProbeOcclusion);
  if (Status st = out.write(path, doc.dump() + "\n"); !st) return st;
  written.push_back(path);
  return Status::ok();
}

Result<std::vector<std::string>> writeBakeOutputs(const scenes::Scene& scene,
                                                  const baker::BakeResult& result,
                                                  const std::string& outDir,
                                                  const BakeReportInfo& info, AtomicOutput& out) {
  std::vector<std::string> written;
  std::vector<std::string> warnings = info.warnings;
  warnings.insert(warnings.end(), result.warnings.begin(), result.warnings.end());
  const baker::TexelSet& texels = result.texels;
  Result<json> atlases = writeLightmaps(texels.atlases, result.lightmaps, outDir, out, written);
  if (!atlases) return atlases.status();
  json indirectAtlases = json::array();
  if (!result.indirectLightmaps.empty()) {
    Result<json> grid = writeLightmaps(result.transport.atlases, result.indirectLightmaps, outDir,
                                       out, written, AtlasKind::Indirect);
    if (!grid) return grid.status();
    indirectAtlases = grid.value();
  }

  // Mixed lights' shadowmask: the images, and per light its channel.
  json shadowmask = nullptr;
  if (!result.shadowmasks.empty()) {
    json images = json::array(), channels = json::object();
    for (size_t a = 0; a < result.shadowmasks.size() && a < texels.atlases.size(); ++a) {
      const std::string path = inFolder(outDir, shadowmaskPng(a));
      if (Status s = writeLinearRgbaPng(path, texels.atlases[a].width, texels.atlases[a].height,
                                        result.shadowmasks[a], out);
          !s)
        return s;
      written.push_back(path);
      images.push_back(shadowmaskPng(a));
    }
    for (size_t i = 0; i < result.shadowmaskChannel.size() && i < scene.lights.size(); ++i)
      if (result.shadowmaskChannel[i] >= 0) channels[scene.lights[i].name] = result.shadowmaskChannel[i];
    shadowmask = {{"images", images},
                  {"texCoord", 1},
                  {"encoding", "linear 8-bit: the visible fraction of the light given the "
                               "channel (0 shadowed, 1 lit); 1 where no light has it"},
                  {"channels", channels}};
  }

  json directional = nullptr;
  if (!result.directionalLightmaps.empty()) {
    Result<json> files =
        writeDirectionalLightmaps(result.transport.atlases, result.directionalLightmaps,
                                  result.transport.lightmap.active(), outDir, out, written);
    if (!files) return files.status();
    directional = files.value();
  }

  Result<SavedGltf> saved = saveAndReadGltf(scene, outDir);
  if (!saved) return saved.status();
  json& doc = saved->doc;
  attachLightmaps(doc, result.lightmaps.size(), warnings);
  // An engine composing the lightmap itself: the grid's atlases, read at TEXCOORD_2 (the
  // direct light's layers are in the transport).
  if (!indirectAtlases.empty()) doc["extras"]["afterglow"]["indirectLightmaps"] = indirectAtlases;
  if (!shadowmask.is_null()) doc["extras"]["afterglow"]["shadowmask"] = shadowmask;
  if (!directional.is_null()) doc["extras"]["afterglow"]["directional"] = directional;
  if (Status s = writeReflectionOutputs(result.transport, result.reflectionChains, result.dfg,
                                        outDir, doc, out, written);
      !s)
    return s;
  const std::string gltf = inFolder(outDir, kSceneGltf);
  if (!saved->bin.empty()) {
    doc["buffers"][0]["uri"] = kSceneBin;
    const std::string bin = inFolder(outDir, kSceneBin);
    if (Status s = out.write(bin, saved->bin); !s) return s;
    written.push_back(bin);
  }
  if (Status s = out.write(gltf, doc.dump(1) + "\n"); !s) return s;
  written.push_back(gltf);

  // The transport for the relighting runtime (a reference bake has none: it solved nothing).
  json transportInfo = nullptr;
  if (!result.transport.atlases.empty()) {
    const std::string path = inFolder(outDir, kTransport);
    const std::string temp = out.tempPath(path);
    std::string error;
    // saveTransport's error starts with the path it wrote: name the final one instead.
    if (!runtime::saveTransport(result.transport, temp, &error))
      return Status::error(path + ": " + error.substr(std::min(error.size(), temp.size() + 2)));
    std::error_code ec;
    const uintmax_t bytes = fs::file_size(temp, ec);
    written.push_back(path);
    transportInfo = {{"file", kTransport},
                     {"bytes", ec ? 0 : bytes},
                     {"bytesPerTexel", ec || texels.size() == 0
                                           ? 0.0
                                           : double(bytes) / double(texels.size())}};
    // Where the bytes go (in memory, about the file's): the light probes', the reflection
    // probes', the lightmap layers' (two resolutions), the rest the bounced light's solve.
    const runtime::TransportData& tr = result.transport;
    const size_t layers = tr.lightmap.memoryBytes(), probes = tr.probeBytes(),
                 reflections = tr.reflectionBytes();
    transportInfo["solveBytes"] = tr.memoryBytes() - layers - probes - reflections;
    transportInfo["probeBytes"] = probes;
    transportInfo["reflectionBytes"] = reflections;
    transportInfo["indirectTexels"] = tr.texelCount;
    if (tr.lightmap.active()) {
      const double lightmapTexels = double(tr.lightmap.texelCount);
      const size_t sources = tr.sources.size();
      transportInfo["layers"] = {
          {"bytes", layers},
          {"lightmapTexels", tr.lightmap.texelCount},
          // Each source's direct light, a half float a texel; where each texel reads the grid.
          {"directBytesPerTexelPerSource",
           sources == 0 ? 0.0
                        : double(tr.lightmap.directBytes()) / lightmapTexels / double(sources)},
          {"cornerBytesPerTexel", double(sizeof(runtime::IndirectCorners))},
          {"atlasBytes", layers - tr.lightmap.directBytes() -
                             tr.lightmap.corners.size() * sizeof(runtime::IndirectCorners)}};
    }
  }

  size_t valid = 0;
  for (uint8_t v : texels.valid) valid += v ? 1 : 0;
  if (texels.valid.empty()) valid = texels.size();
  json stages = json::object();
  double total = 0.0;
  for (const baker::StageTime& s : info.extraStages) {
    stages[stageName(s.stage)] = s.seconds;
    total += s.seconds;
  }
  json stageRays = json::object();
  for (const baker::StageTime& s : result.stages) {
    stages[stageName(s.stage)] = s.seconds;
    total += s.seconds;
    if (s.rays > 0) stageRays[stageName(s.stage)] = s.rays;
  }
  stages["total"] = total;
  size_t lights = 0, emissive = 0;
  for (const runtime::Source& s : result.transport.sources)
    (s.kind == runtime::SourceKind::Light ? lights : emissive) += 1;
  json report;
  report["afterglowVersion"] = info.version;
  report["input"] = info.input;
  report["settings"] = info.settings;
  report["texels"] = texels.size();
  report["validTexels"] = valid;
  report["clusters"] = result.clusters.size();
  report["gatherPoints"] = result.transport.gatherPointCount;
  report["links"] = result.transport.linkCount();
  report["sources"] = {{"lights", lights}, {"emissiveMaterials", emissive}};
  report["raysTraced"] = result.raysTraced;
  report["stageRays"] = stageRays;
  report["transport"] = transportInfo;
  if (!shadowmask.is_null()) report["shadowmask"] = shadowmask;
  if (!directional.is_null()) report["directional"] = directional;
  report["probes"] = {{"count", result.transport.probes.count()},
                      {"tetrahedra", result.transport.probes.mesh.tetrahedra.size()},
                      {"links", result.transport.probes.links.linkCount()},
                      {"transportBytes", result.transport.probeBytes()}};
  report["reflectionProbes"] = {{"count", result.transport.reflections.count()},
                                {"bounces", result.transport.reflections.bounces},
                                {"transportBytes", result.transport.reflectionBytes()}};
  report["stages"] = stages;
  report["peakMemoryBytes"] = peakMemoryBytes();
  report["atlases"] = atlases.value();
  if (!indirectAtlases.empty()) report["indirectAtlases"] = indirectAtlases;
  report["warnings"] = warnings;
  const std::string reportPath = inFolder(outDir, kReport);
  if (Status s = out.write(reportPath, report.dump(2) + "\n"); !s) return s;
  written.push_back(reportPath);
  return written;
}

}  // namespace afterglow::bakefiles
