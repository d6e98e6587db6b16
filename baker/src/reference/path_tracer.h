// The reference integrator behind reference.h: unidirectional path tracing with next-event
// estimation for punctual lights and emissive triangles (multiple importance sampling with the
// cosine-sampled continuation), Russian roulette from the third bounce. Glass in colour: a path
// passes a transmissive surface with probability open, its throughput times the tint per
// channel, or stops there and reflects (the precompute carries the grey of it), and shadow
// rays take the RGB product of the glass they cross (trace::RayTracer::transmittance).
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/reference.h"
#include "shading/emitters.h"
#include "shading/sampling.h"

namespace afterglow::baker {

class PathTracer {
 public:
  PathTracer(const scenes::Scene& scene, const trace::RayTracer& tracer, const Environment& environment,
             int maxDepth);

  // One path's estimate of E/π at a surface point, split into light that arrives directly and
  // light that bounced. n (shading) and ng (geometric) are unit normals on the lit side; p is
  // already off the surface. u places the first direction (stratified by the caller).
  struct Estimate {
    glm::vec3 direct{0.0f};
    glm::vec3 indirect{0.0f};  // already scaled by indirectIntensity
  };
  Estimate irradiance(glm::vec3 p, glm::vec3 n, glm::vec3 ng, glm::vec2 u,
                      sampling::Rng& rng) const;

  // Radiance toward the camera along a primary ray, as `afterglow render` shades a bake:
  // emission (where Material::emitsFrom says) plus diffuse albedo × one path's E/π at the first
  // hit that stops the ray (glass lets it through by chance, tinted: throughGlass; glass shows
  // its emission where it stops the ray, as the baked render blends it). Misses, back faces of
  // single-sided geometry and dynamic instances are black.
  glm::vec3 cameraRadiance(const trace::Ray& ray, glm::vec2 u, sampling::Rng& rng) const;

  // Radiance along a ray as a reflection probe's capture shades it (reflection_capture.h), with
  // the specular part integrated by GGX sampling instead of prefiltered probes: emission, plus
  // the metallic-roughness BRDF's diffuse colour × one path's E/π, plus, while specularDepth >
  // 0, one sampled specular reflection's radiance (this again, one level shallower; the sky on
  // a miss). The BRDF (GGX, Smith height-correlated, Schlick) is sampled by its distribution of
  // normals, written here apart from the runtime's prefilter so the two check each other.
  // Glass as for cameraRadiance.
  glm::vec3 probeRadiance(const trace::Ray& ray, int specularDepth, sampling::Rng& rng) const;
  // Radiance toward the camera as `afterglow render` shades a bake with reflection probes: as
  // probeRadiance (the specular reflections followed specularDepth deep), but a miss is black as
  // the render's is.
  glm::vec3 cameraRadianceWithSpecular(const trace::Ray& ray, int specularDepth,
                                       sampling::Rng& rng) const;

 private:
  // Light arriving at a path vertex by next-event estimation, as E/π (lights scaled by
  // bounceIntensity when `bounced`).
  glm::vec3 nextEvent(glm::vec3 p, glm::vec3 n, glm::vec3 ng, bool bounced,
                      sampling::Rng& rng) const;
  // Solid-angle pdf with which nextEvent picks the emissive point of `hit` seen from distance t.
  float emitterPdf(const trace::Hit& hit, glm::vec3 direction) const;
  float offset(glm::vec3 p) const;
  // Follows `ray` through glass: met(hit) sees every surface it meets, the glass it passes
  // included (whose emission lights as any surface's does: the precompute's direct light
  // counts it whole); at a transmissive one the path passes with probability open,
  // `throughput` times the tint, else it stops there. Returns where it stopped (invalid: it
  // escaped). A pass is no bounce: the ray keeps its origin, so hit.t is the distance from it
  // (the emitters' MIS pdf needs that).
  template <class Met>
  trace::Hit throughGlass(trace::Ray ray, glm::vec3& throughput, sampling::Rng& rng,
                          Met&& met) const {
    for (;;) {
      const trace::Hit hit = tracer_.intersect(ray);
      if (!hit.valid()) return hit;
      met(hit);
      const scenes::Transmission t = tracer_.transmission(hit);
      if (!(t.open > 0.0f) || rng.next() >= t.open) return hit;
      throughput *= t.tint;
      ray.tnear = std::nextafter(hit.t, std::numeric_limits<float>::infinity());
    }
  }

  const scenes::Scene& scene_;
  const trace::RayTracer& tracer_;
  Environment env_;
  int maxDepth_;
  std::vector<Emitter> emitters_;
  std::vector<float> emitterCdf_;     // by power (area × brightest emitted channel)
  std::vector<float> emitterPick_;    // probability of choosing each emitter
  std::vector<int> emitterOfMaterial_;
};

}  // namespace afterglow::baker
