// The sky a texel sees through glass, sampled through the glass as well as by its rays (issue
// 28): windows are the sky's way into a room, as emissive surfaces are lights.
//
// Why: a room lit by the sky through its windows gets its sky from the few of a gather point's
// 128 cosine rays that leave through a window, and which ones do is chance: on the gas
// station's shop (../shared/scenes) the sky each texel saw was 18% off the reference path
// tracer's with the rays alone, most of the bake's error there (the total 7.6%; with the glass
// samples 4.9%, afterglow_bench glass). Points on the glass, chosen by area, each with a
// sight line to it and the glass's transmittance beyond, know a window's size and place. Alone
// they fail next to the glass (a window frame's texel sees points a millimetre away with weights
// of 1/d²), where the cosine rays do well; so the two are combined by multiple importance
// sampling (the balance heuristic, as direct.cpp combines an emitter's area samples with cosine
// rays): along a direction whose first surface is glass a cosine ray weighs
// n_c p_c / (n_c p_c + n_g p_g) and a point on the glass the rest, p_c = cosθ/π the rays'
// density, p_g the glass samples' (a pane's chance × 1/its area × d²/cosθ at the glass), n_c
// and n_g their numbers. Along any other direction the rays alone see the sky. The weights
// count fixed numbers (the texel's first-pass rays, LinkOptions::glassSkySamples), whatever
// each pass casts and each texel samples: every estimator stays unbiased for its share of every
// direction, and the shares sum to one.
//
// A point on the glass counts only when its triangle is the first surface the texel sees that
// way, so a direction through two panes counts once, at the first (of two coplanar faces of
// glass, at the one the ray tracer reports: the rays' weights use the same). A triangle of
// glass is chosen by how much of the texel's view it may fill, its area × the cosines at both
// ends over its squared distance (softened within its own size; 0 for one behind the texel's
// surface), then a point on it by area. Per texel that is a pass over every triangle of glass:
// right for windows (the gas station has 193 triangles of glass), slow for a level of glass
// towers.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"
#include "shading/emitters.h"

namespace afterglow::trace {
class RayTracer;
struct Hit;
}  // namespace afterglow::trace

namespace afterglow::baker {

class GlassSky {
 public:
  GlassSky() = default;  // no glass
  // Every triangle of every transmissive primitive of every instance (scenes::transmissive).
  explicit GlassSky(const scenes::Scene& scene);
  bool empty() const { return glass_.triangles.empty(); }

  // The triangle of glass a hit landed on, or -1.
  int triangleOf(const trace::Hit& hit) const;
  // Each triangle's chance of being chosen from p, unit shading normal n (the same for the
  // rays' weights and the samples). Returns how much glass p sees: Σ over the triangles of
  // area × cosθ at both ends / d² (softened), about the projected solid angle of the glass.
  float chances(glm::vec3 p, glm::vec3 n, std::vector<float>& out) const;
  // How many points on glass a texel samples, of `most`: `view` the glass it sees (chances'
  // total), `open` the share of a white sky its rays saw (the open sky, and their share of the
  // sky through glass). All of them where the sky comes through glass alone (a room), fewer in
  // proportion to the glass's share of the sky (outdoors the open sky dwarfs the glass's, and
  // so does the noise of its own rays), at least 4; none without glass in view. The balance
  // heuristic's weights count `most` whatever the number taken (each estimator stays unbiased
  // for its share of every direction), so the rays' weights need not know it.
  static uint32_t samplesFor(float view, float open, uint32_t most);
  // The glass samples' density per steradian along a direction whose first surface is glass
  // triangle k, at distance d, cosQ the cosine there; `chances` from chances(p, n).
  float density(const std::vector<float>& chances, int k, float d, float cosQ) const;

  // The balance heuristic's weight of one of `rays` cosine rays from p (unit shading normal
  // n) along `direction`, whose first surface is glass triangle k at distance d, cosQ the
  // cosine there, against `samples` points on the glass; `chances` from chances(p, n).
  float rayWeight(const std::vector<float>& chances, glm::vec3 n, glm::vec3 direction, int k,
                  float d, float cosQ, uint32_t rays, uint32_t samples) const;

  // Adds to sky[] the glass samples' share of the sky through glass that the texel at p (unit
  // shading normal n, geometric normal ng) sees: the estimate of (1/π) ∫ Y(ω) T(ω) cosθ dω, T
  // the grey transmittance to the sky (trace::RayTracer::greyTransmittance), from
  // samplesFor(its view, open, most) points on the glass weighed against `rays` cosine rays
  // (rayWeight takes the rest, with `most` samples). Seeded from `item`.
  void addTo(const trace::RayTracer& tracer, glm::vec3 p, glm::vec3 n, glm::vec3 ng,
             uint64_t item, uint32_t most, uint32_t rays, float open,
             double (&sky)[runtime::kShCount]) const;

 private:
  Emitter glass_;                        // every triangle of glass (its CDF unused)
  std::vector<glm::vec3> centres_;        // per triangle
  std::vector<uint32_t> firstPrimitive_;  // per instance, its primitives' entries in firstTriangle_
  std::vector<int> firstTriangle_;        // per primitive of an instance: its first triangle's
                                          //   index in a table of its triangles, or -1
  std::vector<int> triangleOf_;           // that table: per source triangle, glass_'s or -1
};

}  // namespace afterglow::baker
