// `afterglow render`: a ray-traced picture of a baked scene, so a person can see the bake. Each
// pixel traces primary rays (a fixed 2×2 grid, deterministic) and shades the first hit with
// diffuse albedo × lightmap (bilinear at TEXCOORD_1) + emission; misses and dynamic instances
// (no lightmap) get no light. When the bake has reflection probes, surfaces are shaded as an
// engine shades them instead: the metallic-roughness BRDF's diffuse colour × lightmap +
// emission + specular from the probes (runtime::ReflectionLighting: blended, box-projected,
// prefiltered, the DFG table), so metal and gloss show. The output is linear HDR; tone mapping
// happens on write.
// `afterglow render --reference` path-traces the same view, shaded the same way but with the
// lightmap replaced by a path-traced E/π at each first hit, to compare against the bake.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/probe_spheres.h"
#include "afterglow/baker/reference.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/reflection_capture.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

class RayTracer;

// A pinhole camera in world space.
struct View {
  glm::vec3 position{0.0f};
  glm::vec3 forward{0.0f, 0.0f, -1.0f};  // unit
  glm::vec3 up{0.0f, 1.0f, 0.0f};        // unit, orthogonal to forward
  float yfov = 0.8f;                     // radians, vertical field of view
};

// The view of a glTF camera (camera to world, looking down −Z with +Y up).
View cameraView(const scenes::Camera& camera);
// A view from `from` toward `at`, +Y up (or +Z when looking straight up or down).
View lookAtView(glm::vec3 from, glm::vec3 at, float yfov);
// A view of the whole scene from above its −Z side, for scenes without cameras.
View defaultView(const scenes::Scene& scene, float yfov);

// The primary ray through picture point (x, y) of a width × height view, in pixels from the
// top-left corner (pixel centres at +0.5): the one camera model of every picture afterglow
// draws.
struct Ray;
Ray cameraRay(const View& view, int width, int height, float x, float y);

struct RenderOptions {
  int width = 640;         // pixels
  int height = 480;        // pixels
  int samplesPerAxis = 2;  // primary rays per pixel = samplesPerAxis²
};

// One atlas's lightmap (linear E/π), row 0 at v = 0.
struct LightmapImage {
  int width = 0;
  int height = 0;
  std::vector<glm::vec3> pixels;
};

// A linear image (a lightmap EXR, or a rendered view) as RGB, row 0 first; one channel is read
// as grey. Errors name the file.
Result<LightmapImage> readLinearImage(const std::string& path);

// Loads the lightmaps `afterglow bake` attached to a glTF: the EXR files listed in the
// document's extras.afterglow.lightmaps (falling back to every MOZ_lightmap extension's
// extras.afterglow.exr), indexed by atlas. Errors name the file.
Result<std::vector<LightmapImage>> loadBakedLightmaps(const std::string& gltfPath);

// The reflection probes a bake wrote beside its glTF (OUT/probes/reflection_probes.json, the
// cube EXRs and dfg.exr it names), read back as an engine would: probe 0 the sky. Empty (no
// file) for a bake without reflection probes. Errors name the file at fault.
struct BakedReflections {
  std::vector<runtime::ReflectionProbeBox> boxes;  // probe i + 1's
  std::vector<runtime::CubemapChain> chains;       // [0] the sky, [i + 1] boxes[i]
  std::vector<glm::vec2> dfg;                      // kDfgSize² (scale, bias)
  std::vector<runtime::ProbeLight> lights;         // per chain, probeLight
  bool empty() const { return chains.empty(); }
  runtime::ReflectionLighting lighting() const { return {&boxes, &lights, &dfg, runtime::kDfgSize}; }
};
Result<BakedReflections> loadBakedReflections(const std::string& gltfPath);

// Renders the scene; returns width*height linear RGB, row 0 at the top of the picture. With
// `spheres` (probe_spheres.h), each is drawn lit by its probes, in front of or behind the scene
// as it lies, without shadows on the scene.
Result<std::vector<glm::vec3>> renderBaked(const scenes::Scene& scene, const RayTracer& tracer,
                                           const std::vector<LightmapImage>& lightmaps,
                                           const View& view, const RenderOptions& options = {},
                                           Progress& progress = nullProgress(),
                                           const std::vector<ProbeSphere>& spheres = {},
                                           const BakedReflections* reflections = nullptr);

// The same view path-traced (reference.h): every pixel averages `samplesPerPixel` camera rays
// through stratified jittered points of the pixel, each shaded as a bake is rendered (emission +
// diffuse albedo × one path's E/π at the first hit, with the given sky and intensities), so it
// differs from renderBaked only by the bake's error and its own noise. Deterministic whatever
// the thread count: every sample is seeded from (pixel, sample). options.samplesPerAxis is
// not used.
Result<std::vector<glm::vec3>> renderReference(const scenes::Scene& scene,
                                               const RayTracer& tracer,
                                               const Environment& environment, const View& view,
                                               const RenderOptions& options, int samplesPerPixel,
                                               Progress& progress = nullProgress());

// The lighting a bake used besides the scene's lights and emissive materials: the sky
// (settings.sky, or settings.skyImage projected to SH) and settings.indirectIntensity and
// albedoBoost from the report.json `afterglow bake` wrote beside `gltfPath`. Without a report,
// a black sky and intensities 1, with *reportFound (when given) set false. A relative skyImage
// is read from the working directory as the bake did, or else from beside the report (a moved
// output folder). Errors (unreadable report or sky image) name the file.
Result<Environment> loadBakeEnvironment(const std::string& gltfPath, bool* reportFound = nullptr);

// Writes a tone-mapped sRGB PNG atomically. exposureStops NaN = automatic (the 99th percentile
// maps to 0.8 after the tone curve); otherwise the image is scaled by 2^exposureStops.
Status writeRenderPng(const std::string& path, int width, int height,
                      const std::vector<glm::vec3>& image, float exposureStops);
// Writes the linear picture as it is (radiance: albedo x E/pi + emission, the lightmaps'
// units; no exposure, tone map or sRGB) to a 32-bit float RGB EXR atomically, row 0 at the top
// as in the PNG: what other renderers (e.g. Blender Cycles) write for the same view.
Status writeRenderExr(const std::string& path, int width, int height,
                      const std::vector<glm::vec3>& image);

}  // namespace afterglow::baker
