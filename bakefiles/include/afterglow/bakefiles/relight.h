// `afterglow relight`: a bake folder (layout.h) relit from its transport with changed lights,
// sky, materials or bounces, through the runtime an engine links (runtime/runtime.h), without
// tracing a ray, and written as a bake folder of its own: the lightmaps, the bake's scene.gltf
// with the changes (so a fresh bake of it gives the same lightmaps), the relit light probes and
// reflection probes, and the bake's report.json noting the relight. In steps, so that a caller
// can stop between them (on Ctrl-C): openBakeForRelight, applyRelightChanges, relightBake,
// writeRelitFolder.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "afterglow/core/atomic_file.h"
#include "afterglow/runtime/runtime.h"

namespace afterglow::bakefiles {

// Lights and materials are named as the transport names them, or "#INDEX".
struct LightColorChange {
  std::string light;
  glm::vec3 color{1.0f};           // linear
  std::optional<float> intensity;  // changed with the colour when given
};
struct NamedValue {  // a light's intensity or bounce intensity
  std::string name;
  float value = 0.0f;
};
struct NamedColor {  // a material's albedo or emission
  std::string name;
  glm::vec3 value{0.0f};
};

// What a relight changes: each list in its order, the lists in the order below (as the bake
// report's relight.changes records them). Errors name a change by the relight option that asks
// for it (--light, --intensity, ...).
struct RelightChanges {
  std::vector<LightColorChange> lightColors;  // --light
  std::vector<NamedValue> intensities;        // --intensity: lux or candela, as in glTF
  std::vector<NamedValue> bounceIntensities;  // --bounce: the light's share in bounced light
  std::vector<std::string> disabledLights;    // --disable
  std::optional<glm::vec3> sky;               // --sky: a constant radiance, linear
  // --albedo: a bounce albedo, linear; scene.gltf gets the base colour that gives it (or the
  // material is made Lambertian where none does, with a warning).
  std::vector<NamedColor> albedos;
  std::vector<NamedColor> emissions;          // --emission: of materials emissive when baked
  std::optional<float> indirectIntensity;     // --indirect-intensity: scales all bounced light
  std::optional<int> bounces;                 // --bounces: passes (0: until converged)
};

// Why a step failed, which is whose mistake: a change the bake cannot make (a light or material
// it does not have, emission on a material that was not emissive), a bake folder that is missing
// or damaged, or an output that could not be written.
enum class RelightFault { BadChange, BadBake, Output };
struct RelightError {
  RelightFault fault;
  std::string message;
};

// The relit light probes' two files: the bake's probes/light_probes.json (the placement), its
// settings noting the relight, and the runtime's relit SH, deringed as the bake's were.
struct RelitLightProbes {
  std::string json;
  std::string sh;
};

// A bake folder being relit.
struct RelitBake {
  std::string dir;            // the bake folder
  std::string transportPath;  // its transport, loaded into `runtime`
  std::unique_ptr<runtime::Runtime> runtime;
  nlohmann::json report;      // its report.json, the settings changed with the changes
  nlohmann::json gltf;        // its scene.gltf, lights and materials changed
  double loadSeconds = 0.0;   // loading the transport
  int bounces = 0;            // the passes to run: the bake's unless changed
  nlohmann::json changes = nlohmann::json::array();  // as applied, for the report
  std::vector<std::string> warnings;
  runtime::UpdateStats stats;                  // relightBake's solve
  std::optional<RelitLightProbes> lightProbes; // none: the bake has none (or lost its file)

  int lightProbeCount() const { return lightProbes ? runtime->probeCount() : 0; }
  // The level's reflection probes (the sky's cubemap comes besides).
  int reflectionProbeCount() const;
};

// Reads the bake folder's report.json and scene.gltf and loads its transport. Errors are
// BadBake.
std::optional<RelightError> openBakeForRelight(const std::string& dir, RelitBake* bake);

// Applies the changes to the runtime, the glTF and the report's settings. Errors: BadChange,
// or BadBake when scene.gltf does not load (read for --albedo's material factors).
std::optional<RelightError> applyRelightChanges(const RelightChanges& changes, RelitBake& bake);

// Solves from scratch with the bake's stopping rule (the passes a fresh bake with these changes
// runs, so the lightmaps agree with its), then every reflection probe's every capture pass, and
// relights the light probes. Errors (BadBake): a light probes file that does not match the
// transport.
std::optional<RelightError> relightBake(RelitBake& bake);

// Writes the relit folder into `out` (not committed): lightmaps, scene.gltf (its image URIs
// pointing back into the bake folder, except the lightmaps) and its buffers, the light probes'
// files, the reflection probes' files, and report.json. Errors: Output, or BadBake when a
// buffer of the bake cannot be read.
std::optional<RelightError> writeRelitFolder(const RelitBake& bake, const std::string& outDir,
                                             AtomicOutput& out);

}  // namespace afterglow::bakefiles
