#include "afterglow/bakefiles/read.h"

#include <algorithm>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "afterglow/bakefiles/cube_exr.h"
#include "afterglow/bakefiles/layout.h"
#include "afterglow/baker/sky.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/parallel.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "afterglow/runtime/probe_visibility.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::bakefiles {

namespace {

glm::vec3 jsonVec3(const json& v, bool* ok) {
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() ||
      !v[2].is_number()) {
    *ok = false;
    return glm::vec3(0.0f);
  }
  return glm::vec3(v[0].get<float>(), v[1].get<float>(), v[2].get<float>());
}

// Copies report settings[key], a number (count 1) or an array of `count` numbers, into out;
// an absent key keeps the default (reports of older bakes). The error names the report.
Status readNumbers(const json& settings, const char* key, float* out, int count,
                   const std::string& report) {
  if (!settings.contains(key)) return Status::ok();
  const json& v = settings[key];
  const bool ok = count == 1 ? v.is_number()
                             : v.is_array() && v.size() == size_t(count) &&
                                   std::all_of(v.begin(), v.end(),
                                               [](const json& x) { return x.is_number(); });
  if (!ok)
    return Status::error(report + ": settings." + key +
                         (count == 1 ? " is not a number" : format(" is not %d numbers", count)));
  for (int i = 0; i < count; ++i) out[i] = (count == 1 ? v : v[size_t(i)]).get<float>();
  return Status::ok();
}

// A relative skyImage is relative to the folder the bake ran in, which the report does not
// record: use it as written when it exists from here (rendering from where one baked), else
// beside the report, where a moved output folder may have taken it along.
std::string resolveSkyImage(const std::string& recorded, const fs::path& reportDir) {
  const fs::path path(recorded);
  std::error_code ec;
  if (path.is_absolute() || fs::exists(path, ec)) return recorded;
  const fs::path beside = reportDir / path;
  return fs::exists(beside, ec) ? beside.string() : recorded;
}

}  // namespace

Result<std::vector<LightmapImage>> loadBakedLightmaps(const std::string& gltfPath) {
  Result<std::string> text = readFile(gltfPath);
  if (!text) return text.status();
  const json doc = json::parse(text.value(), nullptr, false);
  if (doc.is_discarded()) return Status::error(gltfPath + ": not valid JSON");
  std::vector<std::string> files;  // per atlas, relative to the glTF
  if (doc.contains("extras") && doc["extras"].contains("afterglow") &&
      doc["extras"]["afterglow"].contains("lightmaps")) {
    for (const json& entry : doc["extras"]["afterglow"]["lightmaps"])
      files.push_back(entry.value("exr", std::string()));
  } else if (doc.contains("materials")) {
    for (const json& mat : doc["materials"]) {
      if (!mat.contains("extensions") || !mat["extensions"].contains("MOZ_lightmap")) continue;
      const json& ext = mat["extensions"]["MOZ_lightmap"];
      if (!ext.contains("extras") || !ext["extras"].contains("afterglow")) continue;
      const json& ag = ext["extras"]["afterglow"];
      const int atlas = ag.value("atlas", -1);
      if (atlas < 0 || atlas > 65535) continue;
      if (files.size() <= size_t(atlas)) files.resize(size_t(atlas) + 1);
      files[size_t(atlas)] = ag.value("exr", std::string());
    }
  }
  if (files.empty())
    return Status::error(gltfPath + ": no baked lightmaps (MOZ_lightmap) in this glTF; run "
                         "afterglow bake first");
  const fs::path dir = fs::path(gltfPath).parent_path();
  std::vector<LightmapImage> images;
  for (const std::string& f : files) {
    if (f.empty()) {
      images.emplace_back();
      continue;
    }
    Result<LightmapImage> img = readLinearImage((dir / f).string());
    if (!img) return img.status();
    images.push_back(std::move(img.value()));
  }
  return images;
}

Result<BakedDirectional> loadBakedDirectional(const std::string& gltfPath) {
  Result<std::string> text = readFile(gltfPath);
  if (!text) return text.status();
  const json doc = json::parse(text.value(), nullptr, false);
  if (doc.is_discarded()) return Status::error(gltfPath + ": not valid JSON");
  BakedDirectional out;
  if (!doc.contains("extras") || !doc["extras"].contains("afterglow") ||
      !doc["extras"]["afterglow"].contains("directional"))
    return out;
  const json& d = doc["extras"]["afterglow"]["directional"];
  const std::string where = gltfPath + ": extras.afterglow.directional";
  if (!d.is_object() || !d.contains("atlases") || !d["atlases"].is_array())
    return Status::error(where + " has no list of atlases");
  const json texCoord = d.value("texCoord", json(1));
  if (!texCoord.is_number_integer() || (texCoord.get<int>() != 1 && texCoord.get<int>() != 2))
    return Status::error(where + ": texCoord is not 1 or 2");
  out.texCoord = texCoord.get<int>();
  const fs::path dir = fs::path(gltfPath).parent_path();
  for (const json& entry : d["atlases"]) {
    std::array<LightmapImage, 3>& images = out.atlases.emplace_back();
    for (int axis = 0; axis < 3; ++axis) {
      const std::string key(1, "xyz"[axis]);
      if (!entry.is_object() || !entry.contains(key) || !entry[key].is_string())
        return Status::error(where + ": atlas " + std::to_string(out.atlases.size() - 1) +
                             " names no '" + key + "' image");
      Result<LightmapImage> img = readLinearImage((dir / entry[key].get<std::string>()).string());
      if (!img) return img.status();
      images[size_t(axis)] = std::move(img.value());
    }
  }
  return out;
}

Result<BakedReflections> loadBakedReflections(const std::string& gltfPath) {
  BakedReflections out;
  const std::string dir = fs::path(gltfPath).parent_path().string();
  const std::string path = inProbes(dir, kReflectionProbesJson);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return out;
  Result<std::string> text = readFile(path);
  if (!text) return text.status();
  const json doc = json::parse(text.value(), nullptr, false);
  if (doc.is_discarded() || !doc.is_object() || !doc.contains("probes") ||
      !doc["probes"].is_array() || doc["probes"].empty())
    return Status::error(path + ": not a reflection probes file (no \"probes\" array)");
  const json& probes = doc["probes"];
  for (size_t i = 0; i < probes.size(); ++i) {
    const json& p = probes[i];
    const std::string what = path + ": probes[" + std::to_string(i) + "]";
    if (!p.is_object() || !p.contains("file") || !p["file"].is_string())
      return Status::error(what + " has no file");
    Result<std::vector<runtime::Cubemap>> chain = readCubemapExr(inProbes(dir, p["file"].get<std::string>()));
    if (!chain) return Status::error(what + ": " + chain.message());
    out.chains.push_back(std::move(chain.value()));
    if (i == 0) continue;  // the sky: no box
    bool ok = p.contains("box") && p["box"].is_object() && p.contains("projectionBox") &&
              p["projectionBox"].is_object();
    runtime::ReflectionProbeBox b;
    if (ok) {
      const json& box = p["box"];
      b.centre = jsonVec3(box.value("centre", json()), &ok);
      b.halfSize = jsonVec3(box.value("halfSize", json()), &ok);
      const json axes = box.value("axes", json());
      if (!axes.is_array() || axes.size() != 3) ok = false;
      for (int a = 0; ok && a < 3; ++a) b.axes[a] = jsonVec3(axes[size_t(a)], &ok);
      b.projectionCentre = jsonVec3(p["projectionBox"].value("centre", json()), &ok);
      b.projectionHalfSize = jsonVec3(p["projectionBox"].value("halfSize", json()), &ok);
      b.capturePosition = jsonVec3(p.value("capturePosition", json()), &ok);
      const json blend = p.value("blendDistance", json()), importance = p.value("importance", json()),
                 projection = p.value("boxProjection", json());
      ok = ok && blend.is_number() && importance.is_number_integer() && projection.is_boolean();
      if (ok) {
        b.blendDistance = blend.get<float>();
        b.importance = importance.get<int>();
        b.boxProjection = projection.get<bool>();
      }
    }
    if (!ok)
      return Status::error(what + ": a box, projectionBox, capturePosition, blendDistance, "
                           "importance or boxProjection is missing or malformed");
    out.boxes.push_back(b);
  }
  const std::string dfgPath = inProbes(dir, kDfgExr);
  Result<LightmapImage> dfg = readLinearImage(dfgPath);
  if (!dfg) return dfg.status();
  if (dfg->width != runtime::kDfgSize || dfg->height != runtime::kDfgSize)
    return Status::error(dfgPath + format(": %dx%d, the DFG table is %dx%d", dfg->width,
                                          dfg->height, runtime::kDfgSize, runtime::kDfgSize));
  for (const glm::vec3& v : dfg->pixels) out.dfg.emplace_back(v.x, v.y);
  for (const runtime::CubemapChain& c : out.chains) out.lights.push_back(runtime::probeLight(c));
  return out;
}

namespace {

// The light probes' two files in bake folder `dir`; `missing` follows the error for a file
// that is not there.
Result<LightProbes> readLightProbes(const std::string& dir, const std::string& missing) {
  const std::string jsonPath = inProbes(dir, kLightProbesJson);
  const std::string bin = inProbes(dir, kLightProbesSh);
  std::error_code ec;
  for (const std::string& path : {jsonPath, bin})
    if (!fs::is_regular_file(path, ec)) return Status::error(path + ": no such file" + missing);
  Result<probes::ProbesFile> file = probes::readProbesFile(jsonPath);
  if (!file) return file.status();
  runtime::ProbeShFile sh;
  std::string error;
  if (!runtime::readProbeSh(bin, sh, &error)) return Status::error(error);
  if (sh.sh.size() != file->positions.size())
    return Status::error(format("%s: %zu probes' SH for the %zu probes of %s", bin.c_str(),
                                sh.sh.size(), file->positions.size(), jsonPath.c_str()));
  LightProbes out;
  out.mesh = std::move(file->mesh);
  out.sh = std::move(sh.sh);
  out.directions = std::move(sh.directions);
  out.depth = std::move(sh.depth);
  out.deringWindow = sh.deringWindow;
  return out;
}

}  // namespace

Result<LightProbes> loadLightProbes(const std::string& gltfPath) {
  return readLightProbes(fs::path(gltfPath).parent_path().string(),
                         "; --probe-spheres reads the light probes afterglow bake writes beside "
                         "the scene.gltf (not with --probes none)");
}

Result<baker::Environment> loadBakeEnvironment(const std::string& gltfPath, bool* reportFound) {
  baker::Environment env;  // a black sky, intensities 1: what a bake without options uses
  if (reportFound) *reportFound = false;
  std::error_code ec;
  // A built-in scene (builtin:...) is no file and has no report beside it.
  if (!fs::is_regular_file(gltfPath, ec)) return env;
  const fs::path reportPath = inFolder(fs::path(gltfPath).parent_path().string(), kReport);
  if (!fs::is_regular_file(reportPath, ec)) return env;
  const std::string report = reportPath.string();
  Result<std::string> text = readFile(report);
  if (!text) return text.status();
  const json doc = json::parse(text.value(), nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return Status::error(report + ": not valid JSON");
  const json settings = doc.value("settings", json::object());
  if (!settings.is_object()) return Status::error(report + ": \"settings\" is not an object");
  glm::vec3 sky(0.0f);
  if (Status s = readNumbers(settings, "indirectIntensity", &env.indirectIntensity, 1, report); !s)
    return s;
  if (Status s = readNumbers(settings, "albedoBoost", &env.albedoBoost, 1, report); !s) return s;
  if (Status s = readNumbers(settings, "sky", &sky[0], 3, report); !s) return s;
  const json image = settings.value("skyImage", json(""));
  if (!image.is_string())
    return Status::error(report + ": settings.skyImage is not a string");
  if (const std::string recorded = image.get<std::string>(); !recorded.empty()) {
    Status s = baker::projectEquirectSky(resolveSkyImage(recorded, reportPath.parent_path()), env.skySh);
    if (!s) return Status::error(report + ": settings.skyImage: " + s.message());
  } else {
    runtime::constantSkySh(sky, env.skySh);
  }
  if (reportFound) *reportFound = true;
  return env;
}

runtime::ProbeLighting LightProbes::sample(glm::vec3 p, int hint) const {
  const runtime::ProbeLocation where =
      runtime::weighByVisibility(runtime::locateProbe(mesh, p, hint), mesh.positions, depth, p);
  return runtime::mixProbeLighting(where, sh, directions);
}

const runtime::ProbeTetrahedra& BakedProbes::mesh() const {
  return runtime ? runtime->data().probes.mesh : relit.mesh;
}

runtime::ShL2 BakedProbes::sample(glm::vec3 p, int* hint) const {
  if (!runtime) {
    // The relit SH file is deringed already, and interpolated as the runtime interpolates.
    const runtime::ProbeLocation where = runtime::locateProbe(relit.mesh, p, hint ? *hint : 0);
    if (hint && where.tetrahedron >= 0) *hint = where.tetrahedron;
    return runtime::mixProbes(runtime::weighByVisibility(where, relit.mesh.positions, relit.depth, p),
                              relit.sh);
  }
  const runtime::ShL2 sh = runtime->sampleProbes(p, hint);
  // Deringing scales each band: interpolating deringed probes is deringing the interpolation.
  return deringWindow > 0.0f ? runtime::deringed(sh, deringWindow) : sh;
}

runtime::ProbeLighting BakedProbes::sampleLighting(glm::vec3 p, int* hint) const {
  if (!runtime) {
    const runtime::ProbeLocation where = runtime::locateProbe(relit.mesh, p, hint ? *hint : 0);
    if (hint && where.tetrahedron >= 0) *hint = where.tetrahedron;
    return runtime::mixProbeLighting(
        runtime::weighByVisibility(where, relit.mesh.positions, relit.depth, p), relit.sh,
        relit.directions);
  }
  runtime::ProbeLighting lighting = runtime->sampleProbeLighting(p, hint);
  if (deringWindow > 0.0f) lighting.sh = runtime::deringed(lighting.sh, deringWindow);
  return lighting;
}

Result<int> bakedBounces(const nlohmann::json& settings, const std::string& reportPath) {
  const nlohmann::json bounces = settings.value("bounces", nlohmann::json(0));
  if (!bounces.is_number_integer() || bounces.get<int64_t>() < 0 ||
      bounces.get<int64_t>() > 100000)
    return Status::error(reportPath + ": settings.bounces is not a bounce count: " +
                         bounces.dump());
  return int(bounces.get<int64_t>());
}

Result<BakedProbes> loadBakedProbes(const std::string& outDir) {
  BakedProbes out;
  std::error_code ec;
  if (!fs::exists(inFolder(outDir, kTransport), ec) &&
      fs::is_regular_file(inProbes(outDir, kLightProbesJson), ec)) {
    // `afterglow relight` writes no transport: the relit light is in the probes' SH file.
    Result<LightProbes> relit = readLightProbes(outDir, "");
    if (!relit) return relit.status();
    out.relit = std::move(relit.value());
    return out;
  }
  out.transportPath = inFolder(outDir, kTransport);

  // The bake's settings, when its report is there (an engine's copy of the transport alone is
  // solved with the bake's defaults).
  const std::string reportPath = inFolder(outDir, kReport);
  if (fs::exists(reportPath, ec)) {
    Result<std::string> text = readFile(reportPath);
    if (!text) return text.status();
    const nlohmann::json report = nlohmann::json::parse(text.value(), nullptr, false);
    if (report.is_discarded() || !report.is_object() || !report.contains("settings") ||
        !report["settings"].is_object())
      return Status::error(reportPath + ": not a bake report");
    const nlohmann::json& settings = report["settings"];
    Result<int> bounces = bakedBounces(settings, reportPath);
    if (!bounces) return bounces.status();
    const nlohmann::json dering = settings.value("probeDering", nlohmann::json(0.0));
    if (!dering.is_number() || !(dering.get<double>() >= 0.0) || !(dering.get<double>() < 1e6))
      return Status::error(reportPath + ": settings.probeDering is not a window: " + dering.dump());
    out.bounces = bounces.value();
    out.deringWindow = dering.get<float>();
  }

  std::string error;
  out.runtime = runtime::Runtime::load(out.transportPath, &error);
  if (!out.runtime) return Status::error(error);
  if (out.runtime->probeCount() == 0)
    return Status::error(out.transportPath +
                         ": has no light probes (baked with --probes none, or --reference)");
  out.runtime->setParallelFor(blockRanges());  // results do not depend on it
  runtime::UpdateOptions update;
  update.maxBounces = out.bounces;
  update.fromScratch = true;
  out.runtime->update(update);
  return out;
}

}  // namespace afterglow::bakefiles
