// Scenes and bake settings shared by the bake tests (the lightmaps' and the light probes').
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "afterglow/baker/bake.h"
#include "afterglow/baker/reference.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

// Few rays and samples: tests that need precision raise what they need.
BakeOptions draftOptions();
// Lightmap UVs as `afterglow bake` makes them (bakefiles::unwrapForBake) at this many texels
// per unit (a test failure when unwrapping fails).
void unwrapAt(scenes::Scene& scene, float texelsPerUnit);
// ... or at the most texels per unit that fit one atlasSize² atlas; returns the atlases made (0
// and a test failure when unwrapping fails).
size_t unwrapIntoAtlas(scenes::Scene& scene, int atlasSize);
// The bake's result, or an empty one and a test failure.
BakeResult bakeOrDie(const scenes::Scene& scene, const BakeOptions& options);
// The reference path tracer's light at `subset` of the texels, `samples` paths each under
// `environment`, or an empty one and a test failure.
ReferenceTexels referenceOrDie(const scenes::Scene& scene, const TexelSet& texels,
                               const Environment& environment, int samples,
                               const std::vector<uint32_t>& subset);
// A horizontal square of side 2 × halfSize at y = 0, facing +Y, of one material (a dielectric,
// metallic 0: glTF's default is a metal) with this base colour and specularFactor.
// The built-in Cornell box lit by `lamp` alone (its ceiling lamp's emission off), the lamp
// placed at `where` (fractions of the box's bounds), unwrapped at 60 texels per metre; with
// `grid`, an indirect grid at 20.
scenes::Scene lampLitCornell(scenes::Light lamp, glm::vec3 where, bool grid);
scenes::Scene groundQuad(const std::string& name, float halfSize, float baseColor,
                         float specularFactor = 1.0f);
// Appends the quad a b c d (counter-clockwise seen from the side it faces) with normal n.
void addQuad(scenes::Primitive& p, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 n);
// The four walls of a room over the floor |x|, |z| <= half, `height` high, facing in.
void addRoomWalls(scenes::Primitive& p, float half, float height);
// An axis-aligned closed box from lo to hi, outward normals, one primitive of `material`.
scenes::Primitive box(glm::vec3 lo, glm::vec3 hi, int material);
// Adds such a box to `scene` as a mesh and a static instance, both called `name`.
void addBox(scenes::Scene& scene, const std::string& name, glm::vec3 lo, glm::vec3 hi,
            int material);
// A directional light of no angular size (hard shadows) called "sun", shining along
// `direction`.
scenes::Light hardSun(glm::vec3 direction);
// A 4 × 4 m floor (albedo 0.8) under the noon sun (hardSun), under a roof of two 10 cm thick
// boxes 1 m up with a slit of `width` metres from x = `from` between them (without a roof
// when `roof` is false). Not unwrapped.
scenes::Scene floorUnderASlit(bool roof, float from, float width);
// The white furnace as a level: the procedural box (emission 1, base colour `baseColor`)
// written through the exporter, its one material's KHR_materials_specular put into the JSON by
// hand (when `specular` is not null), loaded back from the file and unwrapped at 4 texels/unit.
scenes::Scene furnaceLevel(const std::string& name, float baseColor, const nlohmann::json& specular);
// McGuire's Cornell box from `path`, as the accuracy tests bake it: unwrapped into one 256²
// atlas, the lamp emitting downwards only. By glTF the double-sided lamp's back lights the
// 1 cm cavity above it, whose light a path tracer finds only through the slit around the lamp
// (at 32768 paths its own indirect noise is 5.6%, too much to judge a 3% error by); the
// cavity's light is checked by its power balance (baker_emission_test.cpp) and against Cycles
// (README). A test failure (and an empty scene) when loading or unwrapping fails.
scenes::Scene cornellForAccuracy(const std::string& path);
// Prints one line of a comparison with the reference: what was compared, the total's relative
// RMSE and bias, direct's and indirect's, and the reference's own noise.
void printComparison(const std::string& what, const ReferenceComparison& c);

}  // namespace afterglow::baker
