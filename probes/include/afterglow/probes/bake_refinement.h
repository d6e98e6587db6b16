// `afterglow probes place --bake OUT/`: a refinement after placeProbes driven by a bake's light
// rather than by geometry. The octree refines where geometry is, but light also changes fast
// away from it (a shadow's edge in mid-air, the boundary of a lamp's light, a doorway between a
// lit and a dark room), and tetrahedral interpolation smears such a change over a whole edge.
// So every edge of the placement's tetrahedra whose two probes see clearly different irradiance
// in the bake is split at its midpoint, unless the octree already made it as short as its finest
// cells' (the refinement brings the octree's resolution where light rather than geometry asks
// for it, and goes no finer). One pass: the new probes halve those edges, no more (a second
// `--bake` run on a bake of the refined probes refines further).
//
// Edges of the tetrahedra rather than pairs of grid neighbours: they join every probe to the
// ones it is interpolated with, whatever its kind (refined, moved and pinned probes sit off the
// coarse grid), and they are exactly the segments across which interpolation spreads light.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/status.h"
#include "afterglow/probes/placement.h"
#include "afterglow/runtime/probe_tetrahedra.h"

namespace afterglow::probes {

// E/π at a point for the six axis normals, in axisNormal's order: +X −X +Y −Y +Z −Z.
using AxisIrradiance = std::array<glm::vec3, 6>;
glm::vec3 axisNormal(int k);

struct BakeRefinementOptions {
  float threshold = 0.25f;  // relative difference of E/π (irradianceDifference) that splits
  // The absolute floor under the relative difference: this fraction of the brightest E/π any
  // probe sees (over the six normals and the channels). Without it two nearly black probes
  // differ by 100% from a speck of light and dark corners would refine everywhere.
  float floorFraction = 0.01f;
};

// How different two points' light is: the largest, over the six normals, of the largest channel
// difference |a − b| relative to the brighter side's brightest channel (or the floor, if more),
// with negative E/π (SH ringing behind a strong light) taken as 0. 0 for the same light, 1 for
// light against black. A colour's dim channel (a warm lamp's blue) is judged against the
// brightness of the light, not on its own, where a few hundredths would count as a large change.
float irradianceDifference(const AxisIrradiance& a, const AxisIrradiance& b, float floor);

struct BakeRefinement {
  float floor = 0.0f;        // the absolute floor used
  size_t edges = 0;          // edges of the tetrahedra compared
  size_t shortEdges = 0;     // of which too short to split (the finest cells' diagonal)
  size_t overThreshold = 0;  // of which the ends differ by more than the threshold
  size_t added = 0;          // probes added
  size_t rejected = 0;       // midpoints inside geometry, within the margin of a surface, or on
                             // a probe (or on another split edge's midpoint)
  size_t overBudget = 0;     // free midpoints left out by maxProbes (the smallest differences)
};

// irradiance: per probe of `placement`, the bake's E/π at its position (what the bake's probes
// interpolate to there); mesh: the placement's tetrahedra. Edges no longer than the diagonal of
// the finest octree cell (placement.spacing / 2^placementOptions.levels; the first region's,
// with probe volumes) are never split. Appends the new probes to placement.positions and kinds,
// as ProbeKind::Refined (placement.refined keeps counting the octree's alone), in the order of
// their edges (sorted by their probes' indices). Midpoints rejected by freeProbePositions (with
// placement.margin and placementOptions' rays) are not added, and no more than
// placementOptions.maxProbes probes are kept in all: the largest differences first, the rest
// counted, with a warning in placement.warnings. Deterministic for any thread count. Errors:
// irradiance not one per probe, a mesh of other probes.
Result<BakeRefinement> refineByBake(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                    const PlacementOptions& placementOptions,
                                    const runtime::ProbeTetrahedra& mesh,
                                    const std::vector<AxisIrradiance>& irradiance,
                                    const BakeRefinementOptions& options, Placement& placement);

}  // namespace afterglow::probes
