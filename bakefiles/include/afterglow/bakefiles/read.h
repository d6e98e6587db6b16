// Reading a bake folder (layout.h) back, as an engine or viewer would: the lightmaps a glTF
// names, the reflection probes, the light probes and their SH, the lighting the bake used, and
// the transport solved as the bake solved it. Errors name the file at fault.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json_fwd.hpp>

#include "afterglow/bakefiles/images.h"
#include "afterglow/baker/reference.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/probe_lights.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/reflection_capture.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/runtime.h"

namespace afterglow::bakefiles {

// Loads the lightmaps `afterglow bake` attached to a glTF: the EXR files listed in the
// document's extras.afterglow.lightmaps (falling back to every MOZ_lightmap extension's
// extras.afterglow.exr), indexed by atlas.
Result<std::vector<LightmapImage>> loadBakedLightmaps(const std::string& gltfPath);

// The directional lightmaps a bake attached (its glTF's extras.afterglow.directional,
// runtime/directional.h): per atlas the bounced light's gradient along world x, y and z, read
// at TEXCOORD_1 (texCoord 1) or an indirect grid's TEXCOORD_2 (texCoord 2). Empty for a bake
// without.
struct BakedDirectional {
  int texCoord = 1;
  std::vector<std::array<LightmapImage, 3>> atlases;
  bool empty() const { return atlases.empty(); }
};
Result<BakedDirectional> loadBakedDirectional(const std::string& gltfPath);

// The reflection probes a bake wrote beside its glTF (probes/reflection_probes.json, the cube
// EXRs and dfg.exr it names), read back as an engine would: probe 0 the sky. Empty (no file)
// for a bake without reflection probes.
struct BakedReflections {
  std::vector<runtime::ReflectionProbeBox> boxes;  // probe i + 1's
  std::vector<runtime::CubemapChain> chains;       // [0] the sky, [i + 1] boxes[i]
  std::vector<glm::vec2> dfg;                      // kDfgSize² (scale, bias)
  std::vector<runtime::ProbeLight> lights;         // per chain, probeLight
  bool empty() const { return chains.empty(); }
  runtime::ReflectionLighting lighting() const { return {&boxes, &lights, &dfg, runtime::kDfgSize}; }
};
Result<BakedReflections> loadBakedReflections(const std::string& gltfPath);

// The light probes a bake wrote beside its glTF: positions and tetrahedra
// (probes/light_probes.json) and one radiance SH per position (light_probes_sh.bin), with
// the small sources each probe reads as a direction (probe_lights.h; none in older files).
struct LightProbes {
  runtime::ProbeTetrahedra mesh;
  std::vector<runtime::ShL2> sh;
  runtime::ProbeDirectionList directions;
  std::vector<uint16_t> depth;  // the probes' depth maps (probe_visibility.h; none in older files)
  float deringWindow = 0.0f;    // how the file's SH were deringed (0: not)

  // The probes' light at p (tetrahedral interpolation from hint weighed by the probes'
  // visibility, as Runtime::sampleProbeLighting).
  runtime::ProbeLighting sample(glm::vec3 p, int hint) const;
};
Result<LightProbes> loadLightProbes(const std::string& gltfPath);

// The lighting a bake used besides the scene's lights and emissive materials: the sky
// (settings.sky, or settings.skyImage projected to SH) and settings.indirectIntensity and
// albedoBoost from the report.json `afterglow bake` wrote beside `gltfPath`. Without a report,
// a black sky and intensities 1, with *reportFound (when given) set false. A relative skyImage
// is read from the working directory as the bake did, or else from beside the report (a moved
// output folder).
Result<baker::Environment> loadBakeEnvironment(const std::string& gltfPath,
                                               bool* reportFound = nullptr);

// A bake folder's light probes read back: `afterglow probes sample` and `probes place --bake`.
// A bake's through the runtime, holding what the bake wrote to probes/light_probes_sh.bin; a
// folder `afterglow relight` wrote has no transport, and its relit light is that file.
struct BakedProbes {
  std::unique_ptr<runtime::Runtime> runtime;  // solved as the bake solved it; null when relit
  std::string transportPath;                  // OUT/transport.agt ("" when relit)
  LightProbes relit;          // a relit folder's probes: its placement and its SH file
  int bounces = 0;            // the bake's bounce passes (report.json; 0: until converged)
  float deringWindow = 0.0f;  // the bake's --probe-dering (0: its SH are as solved)

  // The probes' positions and tetrahedra.
  const runtime::ProbeTetrahedra& mesh() const;
  // The probes' radiance SH at p (tetrahedral interpolation from *hint, as
  // Runtime::sampleProbes), deringed as the bake's SH file is: at a probe's position, that
  // probe's SH in the file.
  runtime::ShL2 sample(glm::vec3 p, int* hint) const;
  // The same with the probes' directions (probe_lights.h): E/π is
  // sampleLighting(p, hint).irradianceOverPi(n, deringWindow).
  runtime::ProbeLighting sampleLighting(glm::vec3 p, int* hint) const;
  float window() const { return runtime ? deringWindow : relit.deringWindow; }
};
// The bounce passes a bake ran, from its report's settings (0: until converged); an error
// naming the report when "bounces" is not a count.
Result<int> bakedBounces(const nlohmann::json& settings, const std::string& reportPath);
// Loads OUT/transport.agt and solves it as `afterglow bake` did: from scratch, with the bake's
// bounce count and tolerance (OUT/report.json's settings; without a report, until converged,
// the bake's default), so the probes equal the bake's bit for bit (the runtime's update() runs
// the solver's loop, and a fresh Runtime is black until its first update). A folder without a
// transport but with probes/light_probes.json is one `afterglow relight` wrote: its probes are
// read from their files. Errors name the file: no or a damaged transport, a report that is not
// one, a transport without light probes, probe files that do not match.
Result<BakedProbes> loadBakedProbes(const std::string& outDir);

}  // namespace afterglow::bakefiles
