// The files of `afterglow bake`: lightmaps (EXR data + PNG preview), the glTF with the lightmaps
// attached through MOZ_lightmap, and report.json. Everything goes through one AtomicOutput that
// the caller commits, so a failed or interrupted bake leaves nothing behind.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "afterglow/baker/bake.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/status.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

// What the report records besides the bake itself.
struct BakeReportInfo {
  std::string version;                   // afterglow version string
  std::string input;                     // the SCENE argument
  std::string settingsJson = "{}";       // the effective settings, a JSON object
  std::vector<StageTime> extraStages;    // stages before the bake (load, uv), seconds
  std::vector<std::string> warnings;     // scene loading and unwrap warnings
};

// Writes OUT/lightmaps/lightmap<i>.exr and .png, OUT/scene.gltf (+ scene.bin) and
// OUT/report.json into `out` (not committed). Returns the final paths.
Result<std::vector<std::string>> writeBakeOutputs(const scenes::Scene& scene,
                                                  const BakeResult& result,
                                                  const std::string& outDir,
                                                  const BakeReportInfo& info, AtomicOutput& out);

// How an EXR stores its channels: half floats (lightmaps) or 32-bit floats (renders compared
// with other renderers' float EXRs).
// The reflection probes' files (when the bake has any): OUT/probes/reflection_sky.exr and
// reflection_<i>.exr (OpenEXR cube environment maps, the prefiltered mips as mip levels),
// OUT/probes/dfg.exr, OUT/probes/reflection_probes.json, and the sky as EXT_lights_image_based
// in `gltf` (its face images beside it), replacing a light of that name `gltf` already has
// (detachImageBasedLights). Paths written are appended to `written`.
Status writeReflectionOutputs(const BakeResult& result, const std::string& outDir,
                              nlohmann::json& gltf, AtomicOutput& out,
                              std::vector<std::string>& written);
// The same from a transport's reflection probes (their boxes, names, bounces and the sky SH)
// and chains: [0] the sky, [i + 1] transport.reflections.probes[i], as BakeResult and
// runtime::Runtime::reflectionChain have them; dfg is the kDfgSize² table. What `afterglow
// relight` writes from the runtime, so its files are the bake's for the same cubemaps. Nothing
// is written without probes (no chains); chains not matching the probes are an error.
Status writeReflectionOutputs(const runtime::TransportData& transport,
                              const std::vector<runtime::CubemapChain>& chains,
                              const std::vector<glm::vec2>& dfg, const std::string& outDir,
                              nlohmann::json& gltf, AtomicOutput& out,
                              std::vector<std::string>& written);

enum class ExrPixels { Half, Float };
// Linear RGB EXR (zip compressed), row 0 = v 0 (glTF's image orientation; the top row).
Status writeExr(const std::string& path, int width, int height,
                const std::vector<glm::vec3>& pixels, AtomicOutput& out,
                ExrPixels pixelType = ExrPixels::Half);
// 8-bit sRGB PNG from linear RGB: pixels × exposure, Reinhard tone map, sRGB encode.
Status writeTonemappedPng(const std::string& path, int width, int height,
                          const std::vector<glm::vec3>& pixels, float exposure,
                          AtomicOutput& out);
// The exposure that maps the 99th percentile luminance of the given pixels (those with a
// non-zero mask entry, or all when the mask is empty) to 0.8 after the Reinhard curve.
float autoExposure(const std::vector<glm::vec3>& pixels, const std::vector<uint8_t>& mask = {});

}  // namespace afterglow::baker
