#include "afterglow/bakefiles/relight.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "afterglow/bakefiles/layout.h"
#include "afterglow/bakefiles/read.h"
#include "afterglow/bakefiles/write.h"
#include "afterglow/core/timer.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "relight_materials.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::bakefiles {

namespace {

RelightError badBake(std::string message) { return {RelightFault::BadBake, std::move(message)}; }
RelightError badChange(std::string message) {
  return {RelightFault::BadChange, std::move(message)};
}
RelightError failedOutput(const Status& status) { return {RelightFault::Output, status.message()}; }

// "'a', 'b'" from count names, or "none".
template <class Name>
std::string nameList(int count, Name name) {
  std::string names;
  for (int i = 0; i < count; ++i) names += (i ? ", '" : "'") + name(i) + "'";
  return names.empty() ? "none" : names;
}

// NAME or #INDEX into an index, or -1.
int resolve(const std::string& name, int count,
            int (runtime::Runtime::*find)(const std::string&) const, const runtime::Runtime& rt) {
  if (int i = (rt.*find)(name); i >= 0) return i;
  if (name.size() > 1 && name[0] == '#') {
    char* end = nullptr;
    const long i = std::strtol(name.c_str() + 1, &end, 10);
    if (*end == '\0' && i >= 0 && i < count) return int(i);
  }
  return -1;
}

json rgb(glm::vec3 c) { return {c.r, c.g, c.b}; }

// What the relit files note of the relight: the bake, the changes and the solve.
json relightNote(const RelitBake& bake) {
  return {{"from", fs::absolute(bake.dir).string()},
          {"changes", bake.changes},
          {"bounces", bake.stats.bounces},
          {"converged", bake.stats.converged}};
}

// Applies RelightChanges in their order, each to the runtime, the glTF (the bake exports lights
// and materials in the transport's order) and the changes' record.
class Changer {
 public:
  explicit Changer(RelitBake& bake)
      : bake_(bake), rt_(*bake.runtime), materials_(mapMaterials(bake.gltf, rt_.materialCount())) {
    json& gltf = bake.gltf;
    if (gltf.contains("extensions") && gltf["extensions"].contains("KHR_lights_punctual"))
      gltfLights_ = &gltf["extensions"]["KHR_lights_punctual"]["lights"];
  }

  std::optional<RelightError> apply(const RelightChanges& c) {
    for (const LightColorChange& change : c.lightColors)
      if (auto e = lightColor(change)) return e;
    for (const NamedValue& change : c.intensities)
      if (auto e = intensity(change)) return e;
    for (const NamedValue& change : c.bounceIntensities)
      if (auto e = bounceIntensity(change)) return e;
    for (const std::string& light : c.disabledLights)
      if (auto e = disable(light)) return e;
    if (c.sky) sky(*c.sky);
    for (const NamedColor& change : c.albedos)
      if (auto e = albedo(change)) return e;
    for (const NamedColor& change : c.emissions)
      if (auto e = emission(change)) return e;
    if (c.indirectIntensity) indirectIntensity(*c.indirectIntensity);
    if (c.bounces) bake_.bounces = *c.bounces;
    return std::nullopt;
  }

 private:
  json* gltfLight(int i) {
    return gltfLights_ && gltfLights_->is_array() && size_t(i) < gltfLights_->size()
               ? &(*gltfLights_)[size_t(i)]
               : nullptr;
  }

  std::optional<RelightError> findLight(const char* option, const std::string& name, int* light) {
    *light = resolve(name, rt_.lightCount(), &runtime::Runtime::findLight, rt_);
    if (*light >= 0) return std::nullopt;
    return badChange(std::string("--") + option + ": no light '" + name + "' in " +
                     bake_.transportPath + " (lights: " +
                     nameList(rt_.lightCount(), [&](int i) { return rt_.lightName(i); }) + ")");
  }

  std::optional<RelightError> findMaterial(const char* option, const std::string& name,
                                           int* material) {
    *material = resolve(name, rt_.materialCount(), &runtime::Runtime::findMaterial, rt_);
    if (*material >= 0) return std::nullopt;
    return badChange(std::string("--") + option + ": no material '" + name + "' in " +
                     bake_.transportPath + " (materials: " +
                     nameList(rt_.materialCount(), [&](int i) { return rt_.materialName(i); }) +
                     ")");
  }

  std::optional<RelightError> lightColor(const LightColorChange& change) {
    int light = -1;
    if (auto e = findLight("light", change.light, &light)) return e;
    rt_.setLightColor(light, change.color);
    if (json* l = gltfLight(light)) (*l)["color"] = rgb(change.color);
    if (change.intensity) {
      rt_.setLightIntensity(light, *change.intensity);
      if (json* l = gltfLight(light)) (*l)["intensity"] = *change.intensity;
    }
    bake_.changes.push_back({{"light", rt_.lightName(light)},
                             {"color", rgb(change.color)},
                             {"intensity", rt_.lightIntensity(light)}});
    return std::nullopt;
  }

  std::optional<RelightError> intensity(const NamedValue& change) {
    int light = -1;
    if (auto e = findLight("intensity", change.name, &light)) return e;
    rt_.setLightIntensity(light, change.value);
    if (json* l = gltfLight(light)) (*l)["intensity"] = change.value;
    bake_.changes.push_back({{"light", rt_.lightName(light)}, {"intensity", change.value}});
    return std::nullopt;
  }

  std::optional<RelightError> bounceIntensity(const NamedValue& change) {
    int light = -1;
    if (auto e = findLight("bounce", change.name, &light)) return e;
    rt_.setBounceIntensity(light, change.value);
    if (json* l = gltfLight(light)) (*l)["extras"]["afterglow"]["bounceIntensity"] = change.value;
    bake_.changes.push_back({{"light", rt_.lightName(light)}, {"bounceIntensity", change.value}});
    return std::nullopt;
  }

  std::optional<RelightError> disable(const std::string& name) {
    int light = -1;
    if (auto e = findLight("disable", name, &light)) return e;
    rt_.setLightEnabled(light, false);
    if (json* l = gltfLight(light)) (*l)["intensity"] = 0.0f;
    bake_.changes.push_back({{"light", rt_.lightName(light)}, {"enabled", false}});
    return std::nullopt;
  }

  void sky(glm::vec3 radiance) {
    rt_.setSky(radiance);
    json& settings = bake_.report["settings"];
    settings["sky"] = rgb(radiance);
    settings["skyImage"] = "";
    bake_.changes.push_back({{"sky", rgb(radiance)}});
  }

  std::optional<RelightError> albedo(const NamedColor& change) {
    int material = -1;
    if (auto e = findMaterial("albedo", change.name, &material)) return e;
    rt_.setAlbedo(material, change.value);
    json record = {{"material", rt_.materialName(material)}, {"albedo", rgb(change.value)}};
    if (!bakedScene_) {
      Result<scenes::Scene> loaded = loadBakedScene(bake_.dir);
      if (!loaded) return badBake(loaded.message());
      bakedScene_ = std::move(loaded.value());
    }
    const MaterialEdit edit =
        setAlbedo(bake_.gltf, materials_, *bakedScene_, material,
                  "material '" + rt_.materialName(material) + "'", change.value, bake_.warnings);
    if (edit.written) {
      record["baseColorFactor"] = rgb(edit.baseColor);
      record["lambertian"] = edit.lambertian;
    }
    bake_.changes.push_back(record);
    return std::nullopt;
  }

  std::optional<RelightError> emission(const NamedColor& change) {
    int material = -1;
    if (auto e = findMaterial("emission", change.name, &material)) return e;
    if (!rt_.setEmission(material, change.value))
      return badChange("--emission: material '" + rt_.materialName(material) +
                       "' was not emissive when baked, so its light was never traced (bake it "
                       "with some emission to relight it)");
    setEmission(bake_.gltf, materials_, material, "material '" + rt_.materialName(material) + "'",
                change.value, bake_.warnings);
    bake_.changes.push_back(
        {{"material", rt_.materialName(material)}, {"emission", rgb(change.value)}});
    return std::nullopt;
  }

  void indirectIntensity(float scale) {
    rt_.setIndirectIntensity(scale);
    bake_.report["settings"]["indirectIntensity"] = scale;
    bake_.changes.push_back({{"indirectIntensity", scale}});
  }

  RelitBake& bake_;
  runtime::Runtime& rt_;
  const MaterialMap materials_;
  json* gltfLights_ = nullptr;
  std::optional<scenes::Scene> bakedScene_;  // loaded on the first --albedo only
};

// The relit light probes (RelitLightProbes), checked as `bake --probes` checks a probes file,
// and against the transport it was baked with. Without the bake's file: a warning, and none.
Result<std::optional<RelitLightProbes>> relightProbes(RelitBake& bake) {
  const runtime::Runtime& rt = *bake.runtime;
  const std::string path = inProbes(bake.dir, kLightProbesJson);
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    bake.warnings.push_back(format("the transport has %d light probes but %s is missing; the "
                                   "relit probes are not written",
                                   rt.probeCount(), path.c_str()));
    return std::optional<RelitLightProbes>();
  }
  Result<std::string> text = readFile(path);
  if (!text) return text.status();
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
  doc["settings"]["relight"] = relightNote(bake);

  runtime::ProbeShFile shFile;
  shFile.deringWindow = window.get<float>();
  shFile.sh.resize(size_t(rt.probeCount()));
  for (int i = 0; i < rt.probeCount(); ++i) {
    rt.probeSh(i, &shFile.sh[size_t(i)]);
    if (shFile.deringWindow > 0.0f)
      shFile.sh[size_t(i)] = runtime::deringed(shFile.sh[size_t(i)], shFile.deringWindow);
  }
  shFile.directions = rt.probeLights();
  shFile.depth = rt.data().probes.depth;
  const std::vector<uint8_t> bytes = runtime::serializeProbeSh(shFile);
  return std::optional<RelitLightProbes>(RelitLightProbes{
      doc.dump() + "\n", std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size())});
}

// The glTF's own images (the level's textures) stay where they are, referred to from outDir;
// the lightmaps are the relit ones beside it.
void pointImagesBack(json& gltf, const std::string& bakeDir, const std::string& outDir) {
  if (!gltf.contains("images")) return;
  const std::string lightmaps = std::string(kLightmapsDir) + "/";
  for (json& image : gltf["images"]) {
    const std::string uri = image.value("uri", std::string());
    if (uri.empty() || uri.rfind("data:", 0) == 0 || uri.rfind(lightmaps, 0) == 0 ||
        fs::path(uri).is_absolute())
      continue;
    image["uri"] =
        fs::proximate(fs::absolute(inFolder(bakeDir, uri)), fs::absolute(outDir)).generic_string();
  }
}

// The glTF's buffers (scene.bin), copied, so render finds the geometry in outDir.
std::optional<RelightError> copyBuffers(const json& gltf, const std::string& bakeDir,
                                        const std::string& outDir, AtomicOutput& out) {
  if (!gltf.contains("buffers")) return std::nullopt;
  for (const json& b : gltf["buffers"]) {
    const std::string uri = b.value("uri", std::string());
    if (uri.empty() || uri.rfind("data:", 0) == 0) continue;
    Result<std::string> bytes = readFile(inFolder(bakeDir, uri));
    if (!bytes) return badBake(bytes.message());
    if (Status s = out.write(inFolder(outDir, uri), bytes.value()); !s)
      return failedOutput(s);
  }
  return std::nullopt;
}

// Whether the bake wrote directional lightmaps (its glTF names them): the relit folder has them
// too, as the glTF it copies names them.
bool hasDirectional(const RelitBake& bake) {
  const json* extras = bake.gltf.contains("extras") ? &bake.gltf["extras"] : nullptr;
  return extras && extras->contains("afterglow") && (*extras)["afterglow"].contains("directional");
}

// The relit lightmaps (and the indirect grid's atlases, with two resolutions); returns
// report.json's "atlases" and "indirectAtlases".
Result<std::pair<json, json>> writeRelitLightmaps(const runtime::Runtime& rt, bool directional,
                                                  const std::string& outDir, AtomicOutput& out) {
  std::vector<std::vector<glm::vec3>> images(size_t(rt.atlasCount()));
  for (int a = 0; a < rt.atlasCount(); ++a) rt.readAtlas(a, images[size_t(a)]);
  std::vector<std::string> written;
  Result<json> atlases = writeLightmaps(rt.data().lightmapAtlases(), images, outDir, out, written);
  if (!atlases) return atlases.status();
  std::vector<std::vector<glm::vec3>> grid(size_t(rt.indirectAtlasCount()));
  for (int a = 0; a < rt.indirectAtlasCount(); ++a) rt.readIndirectAtlas(a, grid[size_t(a)]);
  json gridAtlases = json::array();
  if (!grid.empty()) {
    Result<json> gridFiles =
        writeLightmaps(rt.data().atlases, grid, outDir, out, written, AtlasKind::Indirect);
    if (!gridFiles) return gridFiles.status();
    gridAtlases = gridFiles.value();
  }
  if (directional) {
    std::vector<std::array<std::vector<glm::vec3>, 3>> images(size_t(rt.directionalAtlasCount()));
    for (int a = 0; a < rt.directionalAtlasCount(); ++a)
      for (int axis = 0; axis < 3; ++axis)
        rt.readDirectionalAtlas(a, axis, images[size_t(a)][size_t(axis)]);
    Result<json> files = writeDirectionalLightmaps(rt.data().atlases, images,
                                                   rt.data().lightmap.active(), outDir, out,
                                                   written);
    if (!files) return files.status();
  }
  return std::make_pair(atlases.value(), gridAtlases);
}

// The relit light probes' files, and the reflection probes' through the bake's own writer (the
// cube EXRs, dfg.exr, reflection_probes.json and the sky's EXT_lights_image_based, replacing
// the bake's in `gltf`).
Status writeRelitProbes(const RelitBake& bake, const std::string& outDir, json& gltf,
                        AtomicOutput& out) {
  if (bake.lightProbes) {
    if (Status s = out.write(inProbes(outDir, kLightProbesJson), bake.lightProbes->json); !s)
      return s;
    if (Status s = out.write(inProbes(outDir, kLightProbesSh), bake.lightProbes->sh); !s) return s;
  }
  const runtime::Runtime& rt = *bake.runtime;
  if (rt.reflectionProbeCount() == 0) return Status::ok();
  std::vector<runtime::CubemapChain> chains;
  for (int p = 0; p < rt.reflectionProbeCount(); ++p) chains.push_back(rt.reflectionChain(p));
  std::vector<std::string> written;
  return writeReflectionOutputs(rt.data(), chains, rt.dfgTable(), outDir, gltf, out, written);
}

// The bake's report with the relight noted and the relit atlases.
json relitReport(const RelitBake& bake, const json& atlases) {
  json report = bake.report;
  json note = relightNote(bake);
  note["probes"] = bake.lightProbeCount();
  note["reflectionProbes"] = bake.reflectionProbeCount();
  note["reflectionPasses"] = bake.stats.reflectionPasses;
  note["reflectionMilliseconds"] = bake.stats.reflectionMilliseconds;
  note["loadSeconds"] = bake.loadSeconds;
  note["updateMilliseconds"] = bake.stats.milliseconds;
  note["warnings"] = bake.warnings;
  report["relight"] = note;
  report["atlases"] = atlases;
  return report;
}

}  // namespace

int RelitBake::reflectionProbeCount() const {
  return std::max(0, runtime->reflectionProbeCount() - 1);
}

std::optional<RelightError> openBakeForRelight(const std::string& dir, RelitBake* bake) {
  bake->dir = dir;
  // The report: how the bake solved (its bounces) and what it recorded, carried into ours.
  const std::string reportPath = inFolder(dir, kReport);
  Result<std::string> reportText = readFile(reportPath);
  if (!reportText) return badBake(reportText.message() + " (is " + dir + " a bake folder?)");
  bake->report = json::parse(reportText.value(), nullptr, false);
  const json& report = bake->report;
  if (report.is_discarded() || !report.is_object() || !report.value("settings", json()).is_object())
    return badBake(reportPath + ": not a bake report");
  const Result<int> baked = bakedBounces(report["settings"], reportPath);
  if (!baked) return badBake(baked.message());
  bake->bounces = baked.value();

  const auto start = Clock::now();
  bake->transportPath = inFolder(dir, kTransport);
  std::string error;
  bake->runtime = runtime::Runtime::load(bake->transportPath, &error);
  if (!bake->runtime) return badBake(error);
  bake->loadSeconds = secondsSince(start);

  const std::string gltfPath = inFolder(dir, kSceneGltf);
  Result<std::string> gltfText = readFile(gltfPath);
  if (!gltfText) return badBake(gltfText.message());
  bake->gltf = json::parse(gltfText.value(), nullptr, false);
  if (bake->gltf.is_discarded() || !bake->gltf.is_object())
    return badBake(gltfPath + ": not valid JSON");
  return std::nullopt;
}

std::optional<RelightError> applyRelightChanges(const RelightChanges& changes, RelitBake& bake) {
  return Changer(bake).apply(changes);
}

std::optional<RelightError> relightBake(RelitBake& bake) {
  // From scratch, with the bake's stopping rule: the same passes a fresh bake with these
  // settings runs, so the lightmaps agree with it. Then every reflection probe's every capture
  // pass (a full round: the bake's solveReflectionProbes, in its order) from those lightmaps,
  // so the cubemaps agree with the bake's too.
  runtime::UpdateOptions update;
  update.maxBounces = bake.bounces;
  update.fromScratch = true;
  update.reflectionPasses = -1;
  update.directional = hasDirectional(bake);
  bake.stats = bake.runtime->update(update);
  if (bake.runtime->probeCount() == 0) return std::nullopt;
  Result<std::optional<RelitLightProbes>> probes = relightProbes(bake);
  if (!probes) return badBake(probes.message());
  bake.lightProbes = std::move(probes.value());
  return std::nullopt;
}

std::optional<RelightError> writeRelitFolder(const RelitBake& bake, const std::string& outDir,
                                             AtomicOutput& out) {
  Result<std::pair<json, json>> atlases =
      writeRelitLightmaps(*bake.runtime, hasDirectional(bake), outDir, out);
  if (!atlases) return failedOutput(atlases.status());
  json gltf = bake.gltf;
  pointImagesBack(gltf, bake.dir, outDir);
  if (auto e = copyBuffers(gltf, bake.dir, outDir, out)) return e;
  if (Status s = writeRelitProbes(bake, outDir, gltf, out); !s) return failedOutput(s);
  if (Status s = out.write(inFolder(outDir, kSceneGltf), gltf.dump(1) + "\n"); !s)
    return failedOutput(s);
  json report = relitReport(bake, atlases->first);
  if (!atlases->second.empty()) report["indirectAtlases"] = atlases->second;
  if (Status s = out.write(inFolder(outDir, kReport), report.dump(2) + "\n"); !s)
    return failedOutput(s);
  return std::nullopt;
}

}  // namespace afterglow::bakefiles
