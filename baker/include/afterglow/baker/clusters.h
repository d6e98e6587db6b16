// Stage clusters: texels grouped into clusters, the nodes of the radiosity system.
//
// A cluster holds texels of one instance and one material within a normal cone, at most about
// clusterSize across. Where the texels' gather rays travel short distances (corners, gaps,
// under furniture) light changes over short distances too, so clusters there are kept smaller
// than adaptiveScale × the harmonic mean ray distance, and texels whose distances differ by
// more than maxDistanceRatio are not averaged together: the ceiling inside the 1 cm gap above
// the Cornell box's lamp must not share a cluster with the ceiling the room sees, or the room
// would be lit by the gap's trapped light.
//
// Double-sided surfaces have two sides but texels on the front only. Where the gather saw their
// back, their texels are clustered a second time for the back side (reversed normals, the ray
// distances seen from behind), into clusters that take part in the bounces and are never
// written to a lightmap.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/options.h"
#include "afterglow/baker/texels.h"

namespace afterglow::trace {
class RayTracer;
}  // namespace afterglow::trace

namespace afterglow::baker {

struct TexelGather;

// The options of far cluster level `level` (1 = the first above the clusters): the clusters'
// sizes scaled by farScale^level.
ClusterOptions farClusterOptions(const ClusterOptions& options, int level = 1);

struct Clusters {
  std::vector<uint32_t> texelCluster;  // per texel: its (front) cluster (kNoTexel for invalid)
  std::vector<uint32_t> texelBackCluster;  // per texel: its back-side cluster (kNoTexel for
                                           //   invalid texels and single-sided surfaces)
  // Per cluster:
  std::vector<glm::vec3> position;     // area-weighted centre
  std::vector<glm::vec3> normal;       // area-weighted mean normal (unit); reversed for backs
  std::vector<float> area;             // m²
  std::vector<uint32_t> material;      // index into Scene::materials (of its texels); ~0u for
                                       //   glTF's default material (primitive material -1)
  std::vector<glm::vec3> albedo;       // mean diffuse albedo (texture × factor), linear
  std::vector<glm::vec3> emission;     // mean emitted radiance, linear
  std::vector<uint8_t> back;           // 1 for the back side of a double-sided surface
  std::vector<uint32_t> firstTexel;    // texels of cluster c: memberTexels[firstTexel[c] ..
  std::vector<uint32_t> memberTexels;  //   firstTexel[c+1])

  uint32_t size() const { return uint32_t(area.size()); }
};

// Groups the valid texels into clusters: front sides first, then the back sides of
// double-sided surfaces. With a gather, its harmonic ray distances drive the adaptive
// subdivision and only backs it saw get clusters (without one, every double-sided texel's
// back does); with a tracer, texels that a wall separates from the rest of their cluster are
// split off. Deterministic.
Clusters computeClusters(const scenes::Scene& scene, const trace::RayTracer* tracer,
                         const TexelSet& texels, const TexelGather* gather = nullptr,
                         const ClusterOptions& options = {});

}  // namespace afterglow::baker
