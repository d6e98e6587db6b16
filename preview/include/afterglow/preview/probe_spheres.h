// Probe spheres: white diffuse spheres that `afterglow render --probe-spheres` draws into the
// baked view, each lit by the light probes sampled at its centre, so that anyone can see what a
// dynamic object would receive there (its colour, how bright it is, from which side).
//
// A sphere is shaded as kProbeSphereAlbedo × E(n)/π, E/π from the probes' radiance SH
// (runtime::irradianceOverPi) with the sphere's own normal n: the lightmaps' unit, so a sphere
// and a white wall beside it compare directly. The probes are sampled once per sphere, at its
// centre (runtime::locateProbe and its tetrahedral weights), as an engine lights a character.
// The spheres are not in the bake: they cast no shadow and bounce no light into the scene, and
// the scene behind them is hidden (nearest hit wins, scene or sphere).
//
// Which probes get spheres, and how big (chooseProbeSpheres):
// - every probe (count 0, `all`): radius a fifth of the median nearest-neighbour distance
//   between probes, so neighbouring spheres stay apart;
// - a handful (count N): radius two fifths of the distance from its probe to the nearest other
//   (a coarse grid probe in the open gets a sphere that shows, a refined one by a wall a small
//   one), at probes picked so that they spread over the picture. Eligible are the probes whose
//   centre the camera sees (no surface in between) and whose sphere lies wholly inside the
//   picture with a radius of at most an eighth of its height (nearer ones would fill it).
//   Those at least a thirtieth of the height in radius go first; smaller ones, down to 2
//   pixels, fill up only when there are too few. The first pick is the one nearest the
//   picture's centre, each next one the farthest, on the picture, from those already picked
//   and from the picture's edges (at half weight: a grid's cells have their centres half a
//   step from its border), skipping spheres that would overlap a picked one. Ties go to the
//   larger sphere on the picture, then to the lower probe index: the choice depends on nothing
//   but the inputs.
// Either way a sphere is shrunk to 0.9 × the nearest surface that 26 rays from its centre (the
// axes, the face and the corner diagonals) find, so it does not sink into a wall next to its
// probe (it may still touch thin geometry between those rays).
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "afterglow/bakefiles/read.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/probe_lights.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/reflection_capture.h"

namespace afterglow::trace {
class RayTracer;
struct Ray;
struct View;
}  // namespace afterglow::trace

namespace afterglow::preview {

constexpr float kProbeSphereAlbedo = 0.8f;

// What a sphere is made of. With reflection probes (render.h), the spheres cycle through the
// three: a white diffuse one (the light probes alone), a mirror and a rough metal (the
// reflection probes blended at the hit, normalised by the light probes' irradiance there as
// engines light a dynamic object's reflections).
enum class SphereFinish { Diffuse, Mirror, RoughMetal };
constexpr glm::vec3 kMetalSphereF0{0.95f, 0.93f, 0.88f};  // silver's specular colour
constexpr float kRoughMetalRoughness = 0.4f;

struct ProbeSphere {
  glm::vec3 centre{0.0f};
  float radius = 0.0f;
  int probe = -1;     // the probe it stands at
  runtime::ShL2 sh;   // the probes' radiance SH interpolated at the centre
  // ... and their small sources read as directions (probe_lights.h), with the SH's deringing
  std::vector<runtime::ProbeDirection> directions;
  float window = 0.0f;
  SphereFinish finish = SphereFinish::Diffuse;
};

// A sphere of `radius` at `centre` lit by the probes there (probe -1: at no probe in particular).
ProbeSphere sphereAt(const bakefiles::LightProbes& probes, glm::vec3 centre, float radius);

// Per probe, the distance to the nearest other probe, taken along the tetrahedra's edges (a
// Delaunay mesh holds every probe's nearest neighbour among its edges), or over all pairs when
// there are no tetrahedra; infinity for a probe without neighbours.
std::vector<float> nearestProbeDistances(const runtime::ProbeTetrahedra& mesh);
// Their median (over probes that have a neighbour at a positive distance); 0 when none has.
float medianProbeSpacing(const runtime::ProbeTetrahedra& mesh);

// The spheres for a width × height picture of `view` (see the header comment): count 0 = one
// at every probe, otherwise at most `count`. Deterministic for any thread count. Errors: the SH
// count differs from the probe count.
Result<std::vector<ProbeSphere>> chooseProbeSpheres(const trace::RayTracer& tracer,
                                                    const bakefiles::LightProbes& probes, const trace::View& view,
                                                    int width, int height, int count);

// The spheres of one view binned into screen tiles, so that a primary ray tests only the few
// spheres whose outline covers its pixel (thousands of spheres with `all`).
class ProbeSphereIndex {
 public:
  ProbeSphereIndex(const std::vector<ProbeSphere>& spheres, const trace::View& view, int width,
                   int height);
  bool empty() const { return spheres_.empty(); }
  // The radiance along a primary ray (unit direction) through pixel (px, py) when a sphere is
  // hit before `tMax` (the scene's hit, a distance), in *radiance; false otherwise. Spheres
  // holding the ray's origin are seen through (a camera inside a sphere sees the scene).
  bool shade(const trace::Ray& ray, int px, int py, float tMax, glm::vec3* radiance) const;
  // The reflection probes that light mirror and metal spheres (null: they are black, as an
  // engine without reflection probes shows a metal).
  void setReflections(const runtime::ReflectionLighting* reflections) { reflections_ = reflections; }

 private:
  const runtime::ReflectionLighting* reflections_ = nullptr;
  static constexpr int kTile = 16;  // pixels
  std::vector<ProbeSphere> spheres_;
  int tilesX_ = 0, tilesY_ = 0;
  std::vector<std::vector<uint32_t>> tiles_;  // sphere indices per tile, ascending
};

}  // namespace afterglow::preview
