// `afterglow render`: a ray-traced picture of a baked scene, so a person can see the bake. Each
// pixel traces primary rays (a fixed 2×2 grid, deterministic) and shades the first hit with
// diffuse albedo × lightmap (bilinear at TEXCOORD_1) + emission; misses and dynamic instances
// (no lightmap) get no light. When the bake has reflection probes, surfaces are shaded as an
// engine shades them instead: the metallic-roughness BRDF's diffuse colour × lightmap +
// emission + specular from the probes (runtime::ReflectionLighting: blended, box-projected,
// prefiltered, the DFG table), so metal and gloss show. Glass (alphaMode BLEND,
// KHR_materials_transmission) is blended as an engine blends it: (1 − open) of the glass as
// shaded over open × tint of what lies behind it (scenes::transmission). The output is linear
// HDR; tone mapping happens on write. With directional lightmaps (bakefiles::BakedDirectional,
// read at TEXCOORD_1), a material's normal texture tilts the normal the bounced light is read
// at (runtime::shadeDirectional), as an engine shading with them does.
// `afterglow render --reference` path-traces the same view instead (baker::renderReference),
// shaded the same way but with the lightmap replaced by a path-traced E/π at each first hit.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/bakefiles/images.h"
#include "afterglow/bakefiles/read.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/preview/probe_spheres.h"
#include "afterglow/scenes/scene.h"
#include "afterglow/trace/camera.h"

namespace afterglow::preview {

struct RenderOptions {
  int width = 640;         // pixels
  int height = 480;        // pixels
  int samplesPerAxis = 2;  // primary rays per pixel = samplesPerAxis²
};

// Renders the scene; returns width*height linear RGB, row 0 at the top of the picture. With
// `spheres` (probe_spheres.h), each is drawn lit by its probes, in front of or behind the scene
// as it lies, without shadows on the scene.
Result<std::vector<glm::vec3>> renderBaked(const scenes::Scene& scene,
                                           const trace::RayTracer& tracer,
                                           const std::vector<bakefiles::LightmapImage>& lightmaps,
                                           const trace::View& view,
                                           const RenderOptions& options = {},
                                           Progress& progress = nullProgress(),
                                           const std::vector<ProbeSphere>& spheres = {},
                                           const bakefiles::BakedReflections* reflections = nullptr,
                                           const bakefiles::BakedDirectional* directional = nullptr);

// Writes a tone-mapped sRGB PNG atomically. exposureStops NaN = automatic (the 99th percentile
// maps to 0.8 after the tone curve); otherwise the image is scaled by 2^exposureStops.
Status writeRenderPng(const std::string& path, int width, int height,
                      const std::vector<glm::vec3>& image, float exposureStops);
// Writes the linear picture as it is (radiance: albedo x E/pi + emission, the lightmaps'
// units; no exposure, tone map or sRGB) to a 32-bit float RGB EXR atomically, row 0 at the top
// as in the PNG: what other renderers (e.g. Blender Cycles) write for the same view.
Status writeRenderExr(const std::string& path, int width, int height,
                      const std::vector<glm::vec3>& image);

}  // namespace afterglow::preview
