// The reference path tracer: brute-force Monte Carlo for the same quantities the bake computes,
// to validate it (`afterglow bake --reference`, `afterglow render --reference`, the accuracy
// tests and the benchmark). It shares nothing with the precompute but the ray tracer, the
// material functions (diffuseAlbedo, emittedRadiance) and the light models, so an error in
// texels, clusters, links or the solver shows up as a difference.
//
// Light transport is the bake's: Lambertian surfaces with the baker's diffuse albedo (boosted by
// albedoBoost at bounces), punctual lights as KHR_lights_punctual defines them with the bake's
// soft-shadow sizes, emissive surfaces as area lights (next-event estimation with multiple
// importance sampling), the sky as the same SH L2 radiance the bake uses (so both see the same
// sky), back faces of single-sided geometry and dynamic instances absorb. Each light's
// bounceIntensity scales it at bounces, indirectIntensity scales all bounced light.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/options.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"
#include "afterglow/trace/camera.h"
#include "afterglow/trace/raytracer.h"

namespace afterglow::baker {

// What lights the scene besides its lights and emissive materials.
struct Environment {
  glm::vec3 skySh[runtime::kShCount] = {};  // sky radiance as SH L2 (runtime::constantSkySh)
  float indirectIntensity = 1.0f;           // Unity's meaning, as in BakeOptions
  float albedoBoost = 1.0f;                 // Unity's meaning, as in BakeOptions
};

// Per texel E/π split by how the light arrived, and the variance of each estimate (of the
// mean, per channel), so a comparison can tell the reference's own noise from a real error.
struct ReferenceTexels {
  std::vector<uint32_t> texels;       // the texels estimated (indices into the TexelSet)
  std::vector<glm::vec3> direct;      // lights, emissive surfaces and sky seen directly
  std::vector<glm::vec3> indirect;    // light that bounced at least once
  std::vector<glm::vec3> directVariance;
  std::vector<glm::vec3> indirectVariance;
};

// Estimates the given texels (all valid texels when `which` is empty). Deterministic whatever
// the thread count: every path is seeded from (texel, sample).
Result<ReferenceTexels> referenceTexels(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                        const TexelSet& texels, const Environment& environment,
                                        const ReferenceOptions& options,
                                        const std::vector<uint32_t>& which = {},
                                        Progress& progress = nullProgress());

// E/π at free points in space for a normal each (what a light probe's irradiance gives there):
// path-traced radiance over cosine-distributed directions from the point, with the variance of
// each mean. Seeded from (point index, sample).
struct ReferencePoints {
  std::vector<glm::vec3> irradiance;  // E/π, direct and bounced light together
  std::vector<glm::vec3> variance;    // of the mean, per channel
};
Result<ReferencePoints> referenceIrradiance(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                            const Environment& environment,
                                            const std::vector<glm::vec3>& points,
                                            const std::vector<glm::vec3>& normals,
                                            const ReferenceOptions& options,
                                            Progress& progress = nullProgress());

// The radiance arriving at free points projected onto SH L2 (what a light probe stores, without
// any binning or links): path-traced radiance along `samples` stratified directions over the
// sphere per point (emission plus albedo × one path's E/π at the first hit, as the camera sees
// a bake). Seeded from (point index, sample).
Result<std::vector<runtime::ShL2>> referenceRadianceSh(const scenes::Scene& scene,
                                                       const trace::RayTracer& tracer,
                                                       const Environment& environment,
                                                       const std::vector<glm::vec3>& points,
                                                       const ReferenceOptions& options,
                                                       Progress& progress = nullProgress());

// The radiance arriving along rays (what a reflection probe's texel shows in its mirror mip):
// per ray, the mean of `samples` paths (emission plus the metallic-roughness BRDF's diffuse
// colour × one path's E/π at the first hit, plus options.specularDepth sampled GGX reflections,
// as reflection_capture.h shades with that many bounces; misses show the sky), with the
// variance of that mean in ReferencePoints::variance. Seeded from (ray index, sample).
Result<ReferencePoints> referenceRadiance(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                          const Environment& environment,
                                          const std::vector<trace::Ray>& rays,
                                          const ReferenceOptions& options,
                                          Progress& progress = nullProgress());

// A view path-traced: every pixel of a width × height picture averages `samplesPerPixel` camera
// rays through stratified jittered points of the pixel, each shaded as a bake is rendered
// (emission + diffuse albedo × one path's E/π at the first hit, with the given sky and
// intensities), so it differs from preview::renderBaked only by the bake's error and its own
// noise. With specularDepth > 0, as a bake with reflection probes renders instead: the
// metallic-roughness BRDF's diffuse colour × E/π plus its specular reflection, path-traced
// (GGX-sampled) specularDepth reflections deep, so a mirror shows what it really reflects where
// the render shows a box-projected probe. Row 0 at the top. Deterministic whatever the thread
// count: every sample is seeded from (pixel, sample).
Result<std::vector<glm::vec3>> renderReference(const scenes::Scene& scene,
                                               const trace::RayTracer& tracer,
                                               const Environment& environment,
                                               const trace::View& view, int width, int height,
                                               int samplesPerPixel, int specularDepth = 0,
                                               Progress& progress = nullProgress());

// How far a bake's texels are from the reference, as errors relative to each texel's own
// reference value (so a dim corner counts as much as a texel next to a lamp, and a texel 100×
// as bright as the rest can neither hide everyone else's error nor dominate it). Per texel,
// over the three channels: e_t = ‖bake − ref‖ / max(‖ref‖, floor) and the signed
// s_t = (Σ bake − Σ ref) / max(Σ ref, floor), where the floor, 10% of the mean over texels,
// keeps near-black texels from turning tiny absolute differences into huge relative ones (the
// role of ε in the relMSE of the denoising literature, (x − y)² / (y² + 0.01) for images of
// order 1). Then:
//   relativeRmse   = √mean(e_t²)       the typical error of one texel
//   bias           = mean(s_t)          systematic over- or under-estimation
//   referenceNoise = √mean(σ_t² / max(‖ref‖, floor)²), the reference's own noise, an upper
//                    bound; it adds to relativeRmse in quadrature
struct ErrorStats {
  double relativeRmse = 0.0;
  double bias = 0.0;
  double referenceNoise = 0.0;
  double referenceMean = 0.0;  // mean of Σ ref over texels (RGB summed), for scale
};
struct ReferenceComparison {
  ErrorStats direct;
  ErrorStats indirect;
  ErrorStats total;
  size_t texels = 0;
};
ReferenceComparison compareToReference(const ReferenceTexels& reference,
                                       const std::vector<glm::vec3>& bakedDirect,
                                       const std::vector<glm::vec3>& bakedIndirect);

}  // namespace afterglow::baker
