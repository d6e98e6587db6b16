// How bright `afterglow render`'s picture is and why: the exposure it chose, and whether the
// lightmaps it shows are essentially black for the light the level has, which auto exposure
// would otherwise hide by brightening noise into a picture (a closed room lit by a sky only).
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/bakefiles/images.h"
#include "afterglow/baker/reference.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::preview {

// The scale a PNG's linear picture is multiplied by before the tone curve.
struct Exposure {
  float scale = 1.0f;
  float stops = 0.0f;      // log2(scale)
  bool automatic = false;  // chosen from the picture (bakefiles::autoExposure)
};
// exposureStops NaN = automatic (the 99th percentile maps to 0.8 after the tone curve);
// otherwise 2^exposureStops. What writeRenderPng applies.
Exposure chooseExposure(const std::vector<glm::vec3>& image, float exposureStops);
// "+3.17 stops (x9.02), automatic: the 99th percentile maps to 0.8 after the tone curve".
std::string describeExposure(const Exposure& exposure);

// The lights' scale: the brightest E/π one of the level's sources gives, unshadowed, a surface
// facing it across the level (at half the static bounds' largest edge, `reach`): a directional
// light's illuminance / π; a point or spot light's intensity / (π reach²); an emissive
// material's radiance × its area / (π reach²), at most its radiance (a surface it surrounds);
// the sky's E/π on the best lit of the six axis directions. Luminance, linear. Sources this
// way are compared with what the bake's lightmaps hold, not modelled: a number within a few
// orders of magnitude of a lit bake's bright texels, for any level's size and light units.
float lightsScale(const scenes::Scene& scene, const baker::Environment& environment);

// The q-quantile (0..1) of the luminance of every lightmap texel, the atlases' padding
// included (packing leaves little of it).
float lightmapQuantile(const std::vector<bakefiles::LightmapImage>& lightmaps, double q);

// The warning for lightmaps whose 99th percentile E/π is below 1e-4 of the lights' scale ("" for
// lightmaps that are not): a bake that is black but for noise, as a closed room under a sky
// only is. `name` names the scene.
std::string blackLightmapsWarning(const scenes::Scene& scene,
                                  const std::vector<bakefiles::LightmapImage>& lightmaps,
                                  const baker::Environment& environment, const std::string& name);

}  // namespace afterglow::preview
