// The reflection-probe outputs of a bake and of `afterglow relight` (docs/runtime.md):
// each probe's prefiltered chain as an OpenEXR cube environment map, the split sum's DFG table,
// their description in probes/reflection_probes.json, and the sky as EXT_lights_image_based in
// the glTF.
#include <filesystem>

#include <nlohmann/json.hpp>

#include "afterglow/bakefiles/cube_exr.h"
#include "afterglow/bakefiles/ext_lights_image_based.h"
#include "afterglow/bakefiles/layout.h"
#include "afterglow/bakefiles/write.h"
#include "afterglow/runtime/reflection_prefilter.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::bakefiles {

namespace {

json vec3Json(glm::vec3 v) { return json::array({v.x, v.y, v.z}); }

// The mips an OpenEXR cube level chain holds: level m must be size >> m (a 32² probe's file
// holds mips 0..5; the runtime and reflection_probes.json still count 7).
std::vector<runtime::Cubemap> fileMips(const runtime::CubemapChain& chain) {
  std::vector<runtime::Cubemap> mips;
  for (const runtime::Cubemap& m : chain) {
    if (mips.empty() ? m.size < 1 : m.size != mips.back().size / 2 || m.size < 1) break;
    mips.push_back(m);
  }
  return mips;
}

}  // namespace

Status writeReflectionOutputs(const runtime::TransportData& transport,
                              const std::vector<runtime::CubemapChain>& chains,
                              const std::vector<glm::vec2>& dfg, const std::string& outDir,
                              json& gltf, AtomicOutput& out, std::vector<std::string>& written) {
  const runtime::ReflectionTransport& refl = transport.reflections;
  if (chains.empty() && refl.count() == 0) return Status::ok();
  // A caller's mistake, not the user's: say so rather than write a partial set.
  if (chains.size() != refl.count() + 1)
    return Status::error(format("%s: internal error: %zu reflection chains for %zu probes and the sky",
                                outDir.c_str(), chains.size(), refl.count()));
  const std::string dfgPath = inProbes(outDir, kDfgExr);
  if (Status s = writeDfgExr(dfgPath, dfg, runtime::kDfgSize, out); !s) return s;
  written.push_back(dfgPath);

  json probes = json::array();
  for (size_t i = 0; i < chains.size(); ++i) {
    const std::string file = reflectionExr(i);
    const std::vector<runtime::Cubemap> mips = fileMips(chains[i]);
    const std::string path = inProbes(outDir, file);
    if (Status s = writeCubemapExr(path, mips, out); !s) return s;
    written.push_back(path);
    json p = {{"index", i},
              {"file", file},
              {"faceSize", chains[i].empty() ? 0 : chains[i][0].size},
              {"fileMips", mips.size()}};
    if (i == 0) {
      p["name"] = "sky";
    } else {
      const runtime::ReflectionProbeCapture& c = refl.probes[i - 1];
      const runtime::ReflectionProbeBox& b = c.box;
      p["name"] = c.name;
      p["capturePosition"] = vec3Json(b.capturePosition);
      p["box"] = {{"centre", vec3Json(b.centre)},
                  {"axes", json::array({vec3Json(b.axes[0]), vec3Json(b.axes[1]), vec3Json(b.axes[2])})},
                  {"halfSize", vec3Json(b.halfSize)}};
      const bool own = b.projectionHalfSize.x > 0.0f && b.projectionHalfSize.y > 0.0f &&
                       b.projectionHalfSize.z > 0.0f;
      p["projectionBox"] = {{"centre", vec3Json(own ? b.projectionCentre : b.centre)},
                            {"halfSize", vec3Json(own ? b.projectionHalfSize : b.halfSize)}};
      p["blendDistance"] = b.blendDistance;
      p["importance"] = b.importance;
      p["boxProjection"] = b.boxProjection;
    }
    probes.push_back(p);
  }
  json roughness = json::array();
  for (int m = 0; m < runtime::kReflectionMipCount; ++m)
    roughness.push_back(runtime::roughnessOfMip(float(m), runtime::kReflectionMipCount));
  const json doc = {
      {"format", "afterglow-reflection-probes"},
      {"version", 1},
      {"axes", "glTF world: right-handed, +Y up; cube faces +X -X +Y -Y +Z -Z as OpenEXR's envmap"},
      {"units", "linear RGB radiance, the lightmaps' scale"},
      {"mipCount", runtime::kReflectionMipCount},
      {"mipOfRoughness", "mip = r (1.7 - 0.7 r) (mipCount - 1), r perceptual roughness (Unity's)"},
      {"mipRoughness", roughness},
      {"dfg", {{"file", kDfgExr},
               {"size", runtime::kDfgSize},
               {"layout", "x: NdotV, y: perceptual roughness, row 0 the smoothest; R scale, G bias"}}},
      {"bounces", refl.bounces},
      {"blend", "probe 0 is the sky; weights by importance and smoothstep fades within "
                "blendDistance inside each box (runtime/reflection_probes.h)"},
      {"probes", probes}};
  const std::string jsonPath = inProbes(outDir, kReflectionProbesJson);
  if (Status s = out.write(jsonPath, doc.dump(1) + "\n"); !s) return s;
  written.push_back(jsonPath);

  // The sky for standard viewers, replacing the one the glTF may already have (a relight's
  // document is the bake's scene.gltf, its sky the baked one; the bake's own export has none).
  runtime::ShL2 sky;
  for (int k = 0; k < runtime::kShCount; ++k) sky.c[k] = transport.skySh[k];
  const ImageBasedLightOptions iblOptions;
  detachImageBasedLights(gltf, iblOptions.name);
  Result<std::vector<std::string>> images =
      attachImageBasedLight(gltf, outDir, sky, fileMips(chains[0]), out, iblOptions);
  if (!images) return images.status();
  written.insert(written.end(), images->begin(), images->end());
  return Status::ok();
}

}  // namespace afterglow::bakefiles
