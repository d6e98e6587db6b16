// Whether a level is in metres, as glTF says it is, or was written in centimetres or
// millimetres by an exporter that kept its own unit; and the whole level scaled into metres
// (`--unit-scale`). Texel density, cluster size, probe spacing and the lights' falloff are all
// in metres, so a level in millimetres bakes a thousand times too coarse or too fine.
// `afterglow info`, `bake` and `probes place` share this, and the warning's words are here.
#pragma once

#include <cstddef>
#include <string>

#include "afterglow/scenes/scene.h"

namespace afterglow::scenes {

enum class LengthUnit { Metres, Centimetres, Millimetres };

// What guessUnits saw and made of it.
struct UnitsGuess {
  LengthUnit unit = LengthUnit::Metres;
  size_t objects = 0;        // static instances with a size
  float typicalSize = 0.0f;  // their typical size (units.cpp says which statistic), scene units
  float levelSize = 0.0f;    // the largest edge of the static bounds, scene units
};

// Judges a level's unit by what it holds, not by one threshold: a 0.5-unit door is in metres,
// a 550-unit Cornell box is not. How, and why: units.cpp. Metres when there is nothing static.
UnitsGuess guessUnits(const Scene& scene);

// Metres per unit: 1, 0.01, 0.001.
float metresPerUnit(LengthUnit unit);

// The one-line warning for a level that is not in metres, naming the unit, the sizes that
// gave it away and the fix (a root node scale, or --unit-scale); "" for one in metres.
// `name` names the level (its file).
std::string unitsWarning(const UnitsGuess& guess, const std::string& name);

// Scales the whole level about the origin by `factor`, as a root node scale would: instance,
// probe volume and reflection probe transforms; lights' positions, ranges and radii; cameras'
// positions, clip distances and orthographic extents; probe volumes' spacing and reflection
// probes' blend distances (metres in the world). Directions, intensities (candela, lux) and
// emission (radiance) do not depend on the unit of length and stay.
void scaleScene(Scene& scene, float factor);

}  // namespace afterglow::scenes
