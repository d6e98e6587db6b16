// The whole `afterglow probes place` job on a loaded level: light probes placed (placeProbes)
// and tetrahedralised, refined where a bake's light changes (refineByBake) and tetrahedralised
// again, reflection probes proposed (placeReflectionProbes), the pinned probes named, and what
// PROBES.json and its picture hold. The bake's light comes from the caller as a function: this
// library places probes from geometry and does not read bake folders (bakefiles::BakedProbes
// does, and links this library).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/probes/bake_refinement.h"
#include "afterglow/probes/placement.h"
#include "afterglow/probes/reflection_placement.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::probes {

// Everything a placement is asked to do.
struct PlacementJob {
  std::string input;            // the SCENE argument, for messages and the settings
  std::string userProbesFile;   // where placement.userProbes came from, for the settings
  float unitScale = 1.0f;       // metres per unit the scene was scaled by, for the settings
  PlacementOptions placement;
  std::string bake;             // the bake whose light refines (bakeLight), for the settings
  BakeRefinementOptions refinement;
  bool reflection = false;      // propose reflection probes too
  ReflectionPlacementOptions reflectionOptions;
  int width = 960;              // the picture's size
  int height = 600;
  // Time spent before the job, for the summary: loading the scene and the user's probes (the
  // placement's), loading the bake (the refinement's).
  double loadSeconds = 0.0;
  double bakeLoadSeconds = 0.0;
};

// A bake's light: its probes' radiance SH at each point. It must give the same answer on any
// thread count (the placement's output does not depend on it).
using BakeLight = std::function<std::vector<runtime::ShL2>(const std::vector<glm::vec3>&)>;

// What the job made.
struct PlacedProbes {
  Placement placement;
  runtime::ProbeTetrahedra mesh;
  std::vector<std::string> names;   // per probe: the pinned ones' from the user's file, else ""
  size_t pinned = 0;
  BakeRefinement refinement;        // refined by a bake's light (none without one)
  ReflectionPlacement reflections;  // proposed (none without job.reflection)
  std::string probesJson;           // PROBES.json: probesJson with the settings and summary
  std::vector<glm::vec3> picture;   // job.width × job.height, placementPicture
  double placeSeconds = 0.0;        // loading included
  double tetrahedraSeconds = 0.0;
  double bakeSeconds = 0.0;         // loading the bake included
  double reflectionSeconds = 0.0;
};

// Runs the job; refines by bakeLight when it is given. Errors name job.input (the placement's,
// the tetrahedralisation's, the refinement's, the reflection placement's); "cancelled" when
// `progress` is.
Result<PlacedProbes> runPlacementJob(const scenes::Scene& scene, const PlacementJob& job,
                                     const BakeLight* bakeLight,
                                     Progress& progress = nullProgress());

}  // namespace afterglow::probes
