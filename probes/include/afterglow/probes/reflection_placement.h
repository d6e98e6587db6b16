// `afterglow probes place --reflection`: reflection probes proposed automatically, one per
// room-like region, each box fitted to the walls around it by ray distances, for a person to
// review and edit in PROBES.json before `afterglow bake --probes PROBES.json` captures them.
//
// Candidates sit at the centres of a coarse grid's cells over the static geometry's bounds. Each
// casts rays in every direction and measures its room as the bake measures a size-less probe's
// (baker::fitReflectionProbeBox): along each of the six axis directions, the 80th percentile of
// the distances, measured along that axis, of the rays within 30° of it that hit static geometry
// (walls stand behind furniture); a direction whose rays all miss reaches the static bounds. A
// candidate is dropped when it is inside geometry (the light probes' test: a quarter of its rays
// see the backs of single-sided surfaces, or half those of one double-sided shell), open (fewer than half of its rays hit the fronts of
// surfaces: outdoors, above the roofs), its box is thinner than half the grid's spacing (a gap
// between a column and a wall), or the box's centre, where the probe captures, is not clearly
// free (freeProbePositions).
//
// A box fits when the rays end on its faces: a candidate's score is the fraction of its rays
// that hit within 10% of where they leave its box (or miss through a face that reached the
// bounds). A candidate facing a door fits a box that spills into the next room and scores low,
// since its rays toward the door's wall stop well inside that box. Candidates are taken by score
// (then by volume), skipping any whose point or box centre lies in a box already kept or whose
// box lies mostly (half its volume) in kept boxes, up to maxProbes. Deterministic for any thread
// count.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::trace {
class RayTracer;
}  // namespace afterglow::trace

namespace afterglow::probes {

// A reflection probe as PROBES.json holds it (`"reflectionProbes"`): an axis-aligned box
// centred on `position`, which is also where the bake captures it, as a glTF node translated
// there with extras.afterglow.reflectionProbe = {size, blendDistance, importance,
// boxProjection, resolution} (scenes::ReflectionProbe).
struct ReflectionProbeEntry {
  std::string name;
  glm::vec3 position{0.0f};  // metres, world (glTF axes)
  glm::vec3 size{1.0f};      // metres along the world axes, each > 0: the influence box
  glm::vec3 projectionSize{0.0f};  // the box projection's box, centred with it (the room's
                                   //   walls); 0: the influence box
  float blendDistance = 1.0f;
  int importance = 1;
  bool boxProjection = true;
  int resolution = 128;      // a power of two from 8 to 2048
};

// The scene's reflection probe for an entry: a node translated to its position, untransformed.
scenes::ReflectionProbe toSceneReflectionProbe(const ReflectionProbeEntry& entry);

struct ReflectionPlacementOptions {
  size_t maxProbes = 32;       // proposals kept at most (the best fitting first)
  float spacing = 0.0f;        // metres between candidates; 0: autoSpacing(scene)
  size_t maxCandidates = 4096; // the spacing grows until the grid holds no more
  int rays = 1024;             // per candidate (~70 within 30° of each axis)
  float insideFraction = 0.25f; // as the light probes' PlacementOptions
  int resolution = 128;        // of every proposal
};

struct ReflectionPlacement {
  std::vector<ReflectionProbeEntry> probes;
  float spacing = 0.0f;         // the candidates' grid spacing used
  // The summary `probes place --reflection` prints.
  size_t candidates = 0;
  size_t inside = 0;            // inside geometry
  size_t open = 0;              // under half the rays on surfaces' fronts
  size_t thin = 0;              // a box thinner than half the spacing
  size_t centreBlocked = 0;     // the box's centre inside geometry or on a surface
  size_t overlapping = 0;       // in or mostly in a kept box
  size_t overBudget = 0;        // good but past maxProbes
  std::vector<std::string> warnings;
};

// Errors: a non-positive or non-finite spacing, fewer than 64 rays, maxProbes 0.
Result<ReflectionPlacement> placeReflectionProbes(const scenes::Scene& scene,
                                                  const trace::RayTracer& tracer,
                                                  const ReflectionPlacementOptions& options = {},
                                                  Progress& progress = nullProgress());

}  // namespace afterglow::probes
