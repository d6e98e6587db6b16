// Directional lightmaps: how the bounced light a texel receives changes with the shading
// normal, so normal-mapped surfaces respond to it (Enlighten's directional irradiance, the SH L1
// modes of Godot's and Bakery's lightmaps). Relit like the rest: computed from the solver's
// current solution.
//
// Per texel, three RGB vectors: gradient.axis[a] = ∂(E/π)/∂n_a, the change of the texel's
// bounced light (E/π, as the lightmap holds it) with the a-th world component of the shading
// normal. At a normal n near the surface's own n0 (the interpolated vertex normal):
//
//     E(n)/π ≈ lightmap + Σ_a axis[a] · (n − n0)_a
//
// to first order (shadeDirectional saturates it smoothly: never below 0, at most twice the
// lightmap's light)
// which has the form of SH L1 irradiance (L1 = the gradient, L0 = lightmap − gradient · n0, so
// the surface's own normal reads the lightmap exactly).
//
// The gradient is E's own at n0: of E(n) = ∫ L(ω) max(0, n·ω) dω it is ∫ L(ω) ω dω over the
// hemisphere. A link carries the cosine-weighted share w of its target's radiance R (E/π =
// Σ w R), a solid angle of π w / cos θ, so ∂(E/π)/∂n = Σ w R ω / cos θ: ω the direction from the
// gather point to the link's target (TransportData::clusterPosition, ...), θ its angle to the
// point's normal (clamped at kMinCosine: a target at the horizon would weigh without bound).
// An SH L1 projection of the radiance is half as steep (its fit spans every normal on the
// sphere); normal maps tilt normals by tens of degrees, where E's own gradient follows the
// reference: on a wall lit from below at normals tilted 20 and 35 degrees, 6.7% relative RMSE
// against the SH projection's 19% and the flat lightmap's 42% (baker_directional_test.cpp).
//
// Only the bounced light is directional: the sky's light and each source's direct light stay as
// the lightmap holds them.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/solver.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

struct LightGradient {
  glm::vec3 axis[3] = {glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f)};  // ∂(E/π)/∂n_x, _y, _z
};

// The lightmap's light at shading normal n, from its value at the surface's normal n0 and its
// gradient: per channel, with r = the first-order change over the lightmap's value,
// lightmap × min(1 + r, 2) for r >= -1/2 and lightmap × e^(2r + 1) / 2 below.
glm::vec3 shadeDirectional(glm::vec3 lightmap, const LightGradient& g, glm::vec3 n, glm::vec3 n0);

class DirectionalLight {
 public:
  // The smallest cosine a link's direction counts with (see above).
  static constexpr float kMinCosine = 0.2f;

  // Keeps a reference to `data` (its directions must be present: hasDirections()) and works
  // out each link's direction once. Allocates everything texels() and upsample() need.
  explicit DirectionalLight(const TransportData& data);
  void setParallelFor(ParallelFor parallelFor) { parallelFor_ = std::move(parallelFor); }

  // Per texel of the transport (texelCount: the indirect grid's with two resolutions), the
  // gradient of its bounced light in the solver's current solution, scaled by
  // indirectIntensity; smoothed and interpolated as Solver::indirectTexels does the light.
  void texels(const Solver& solver, LightGradient* out) const;
  // Two resolutions: per lightmap texel, the gradients of its grid texels mixed as
  // Solver::upsampleIndirect mixes their light (lightmap.texelCount values).
  void upsample(const LightGradient* grid, LightGradient* lightmap) const;

 private:
  template <class Body>
  void forRange(size_t items, const Body& body) const;

  const TransportData& data_;
  ParallelFor parallelFor_;
  // Per entry of the gather points' rows of links: w ω / cos θ (zero for padding and for the
  // link to a shared far field, which pointShared_ carries).
  std::vector<glm::vec3> linkFactor_;
  // Per entry of the shared far fields' rows, the same seen from the mean of their points.
  std::vector<glm::vec3> sharedFactor_;
  // Per gather point, its shared far field (kNoTexel: none) and that link's weight.
  std::vector<uint32_t> pointShared_;
  std::vector<float> pointSharedWeight_;
  // Scratch: per shared far field and per gather point (twice, for the smoothing passes),
  // three 16-byte aligned vectors each (directional.cpp's Gradient4).
  mutable std::vector<glm::vec4> shared_, points_, filtered_;
};

}  // namespace afterglow::runtime
