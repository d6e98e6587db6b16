// Writing a bake folder (layout.h): lightmaps (EXR data + PNG preview), the glTF with the
// lightmaps attached through MOZ_lightmap, the transport, report.json, the light probes' files
// and the reflection probes'. Everything goes through one AtomicOutput that the caller commits,
// so a failed or interrupted bake leaves nothing behind.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "afterglow/baker/bake.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/status.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/runtime/probe_lights.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::bakefiles {

// What the report records besides the bake itself.
struct BakeReportInfo {
  std::string version;                        // afterglow version string
  std::string input;                          // the SCENE argument
  nlohmann::json settings = nlohmann::json::object();  // the effective settings
  std::vector<baker::StageTime> extraStages;  // the pipeline's stages around the bake (load,
                                              //   uv, probe placement), seconds
  std::vector<std::string> warnings;          // scene loading and unwrap warnings
};

// Writes OUT/lightmaps/lightmap<i>.exr and .png, OUT/scene.gltf (+ scene.bin), the transport,
// the reflection probes' files and OUT/report.json into `out` (not committed). Returns the
// final paths.
Result<std::vector<std::string>> writeBakeOutputs(const scenes::Scene& scene,
                                                  const baker::BakeResult& result,
                                                  const std::string& outDir,
                                                  const BakeReportInfo& info, AtomicOutput& out);

// The lightmap's atlases, or (two resolutions) the indirect grid's.
enum class AtlasKind { Lightmap, Indirect };

// Each atlas as OUT/lightmaps/lightmap<i>.exr (indirect<i>.exr for the grid's; linear half
// float) and .png (tone mapped, exposed for the atlas's covered texels), appending the paths to
// `written`. Returns report.json's "atlases" (or "indirectAtlases"): per atlas its size, files
// and the PNG's exposure (and the grid's UV set, texCoord 2).
Result<nlohmann::json> writeLightmaps(const std::vector<runtime::AtlasLayout>& layouts,
                                      const std::vector<std::vector<glm::vec3>>& images,
                                      const std::string& outDir, AtomicOutput& out,
                                      std::vector<std::string>& written,
                                      AtlasKind kind = AtlasKind::Lightmap);

// Directional lightmaps (runtime/directional.h): per atlas of the transport (`layouts`), its
// three gradient images as OUT/lightmaps/lightmap<i>_dx.exr, _dy, _dz (indirect<i>_d*.exr on an
// indirect grid, `grid`), linear half float, appending the paths to `written`. Returns the
// glTF's and report.json's "directional": the files, their UV set and how to decode them.
Result<nlohmann::json> writeDirectionalLightmaps(
    const std::vector<runtime::AtlasLayout>& layouts,
    const std::vector<std::array<std::vector<glm::vec3>, 3>>& images, bool grid,
    const std::string& outDir, AtomicOutput& out, std::vector<std::string>& written);

// The light probes a bake used, and how they came about (placed or read from a file).
struct ProbeSet {
  probes::ProbesFile file;
  float spacing = 0.0f;  // of an automatic placement (0 for a file)
  nlohmann::json summary = nlohmann::json::object();
};
// OUT/probes/light_probes.json (the placement's format, with the SH file named, `settings`'s
// probe options recorded) and OUT/probes/light_probes_sh.bin (the SH, deringed with `dering`
// when positive, the probes' directions and depth maps), appending the paths to `written`.
Status writeLightProbes(const std::string& outDir, const ProbeSet& set,
                        const std::vector<runtime::ShL2>& sh,
                        const runtime::ProbeDirectionList& directions,
                        const std::vector<uint16_t>& depth, float dering,
                        const nlohmann::json& settings, AtomicOutput& out,
                        std::vector<std::string>& written);
// OUT/probes/light_probe_occlusion.json: per probe (in light_probes.json's order) its
// occlusion of the mixed lights by shadowmask channel, and each mixed light's channel.
Status writeProbeOcclusion(const std::string& outDir, const std::vector<glm::vec4>& occlusion,
                           const nlohmann::json& channels, AtomicOutput& out,
                           std::vector<std::string>& written);

// The reflection probes' files (when the bake has any): OUT/probes/reflection_sky.exr and
// reflection_<i>.exr (OpenEXR cube environment maps, the prefiltered mips as mip levels),
// OUT/probes/dfg.exr, OUT/probes/reflection_probes.json, and the sky as EXT_lights_image_based
// in `gltf` (its face images beside it), replacing a light of that name `gltf` already has
// (detachImageBasedLights). From a transport's reflection probes (their boxes, names, bounces
// and the sky SH) and chains: [0] the sky, [i + 1] transport.reflections.probes[i], as
// BakeResult and runtime::Runtime::reflectionChain have them; dfg is the kDfgSize² table. A
// bake and `afterglow relight` both write through it, so their files agree for the same
// cubemaps. Nothing is written without probes (no chains); chains not matching the probes are
// an error. Paths written are appended to `written`.
Status writeReflectionOutputs(const runtime::TransportData& transport,
                              const std::vector<runtime::CubemapChain>& chains,
                              const std::vector<glm::vec2>& dfg, const std::string& outDir,
                              nlohmann::json& gltf, AtomicOutput& out,
                              std::vector<std::string>& written);

}  // namespace afterglow::bakefiles
