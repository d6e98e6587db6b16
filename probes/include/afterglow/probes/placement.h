// `afterglow probes place`: where light probes go. A grid over the static geometry's bounds (or
// over the probe volumes authored on glTF nodes), refined on an octree in cells that hold or
// touch geometry, never inside geometry: a candidate is inside when more than a quarter of its
// rays see the backs of single-sided surfaces (DDGI's and Unity's probe validity), or more than
// half the backs of one double-sided shell (a closed object, whatever its sidedness; an open
// sheet never covers half: curtains and leaves stay thin). Such a candidate is moved to a free
// spot within its cell (Unity's virtual offset) or dropped; probes nearer than a margin to a
// surface are pushed off it. The user's own probes are pinned and never moved.
#pragma once

#include <cstdint>
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

struct PlacementOptions {
  float spacing = 0.0f;        // metres between grid probes; 0: chosen from the level's size
  int levels = 2;              // finer octree levels in cells that hold or touch geometry
  float margin = 0.0f;         // metres kept from surfaces; 0: a tenth of the finest spacing
  size_t maxProbes = 100000;   // more is refused, with the count and how to lower it
  int rays = 64;               // rays per candidate for the inside-geometry test
  float insideFraction = 0.25f; // a candidate whose rays see more single-sided backs is inside
  std::vector<glm::vec3> userProbes;  // pinned: kept as given, never moved
  std::vector<std::string> userNames; // names for the user probes' warnings ("" = index)
};

enum class ProbeKind : uint8_t {
  Grid = 0,     // a grid probe where it was placed
  Refined = 1,  // added by the octree refinement near geometry
  Moved = 2,    // moved out of geometry, or pushed off a surface by the margin
  Pinned = 3,   // the user's own (--add)
};
const char* probeKindName(ProbeKind kind);  // "grid", "refined", "moved", "pinned"

struct Placement {
  std::vector<glm::vec3> positions;
  std::vector<ProbeKind> kinds;
  float spacing = 0.0f;  // the coarse grid's spacing used
  float margin = 0.0f;   // the margin used
  // The summary `probes place` prints.
  size_t candidates = 0;  // grid and refinement candidates tested
  size_t rejected = 0;    // dropped inside geometry
  size_t moved = 0;       // moved out of geometry or off a surface
  size_t refined = 0;     // placed by the refinement
  std::vector<std::string> warnings;  // e.g. a pinned probe inside geometry, named
};

// The spacing `spacing = 0` picks for a level: its static bounds' size, so a room and a city
// block both get a few thousand grid points.
float autoSpacing(const scenes::Scene& scene);

// Deterministic for any thread count. Errors: a probe volume with a non-positive size or
// spacing (naming its node), more probes than maxProbes (with the count and the spacing that
// would fit), non-finite user probes.
Result<Placement> placeProbes(const scenes::Scene& scene, const trace::RayTracer& tracer,
                              const PlacementOptions& options = {},
                              Progress& progress = nullProgress());

// The placement's own tests for probes added after it (`probes place --bake` splits edges),
// none moved: 1 where a probe at points[i] is clearly outside geometry (its options.rays rays see
// back faces less often than a moved candidate may) and at least `margin` off every surface its
// rays find, else 0. Deterministic for any thread count.
std::vector<uint8_t> freeProbePositions(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                        const std::vector<glm::vec3>& points, float margin,
                                        const PlacementOptions& options = {});

}  // namespace afterglow::probes
