// Light probes' visibility, so interpolation does not carry light through walls (GLM only).
//
// A point's four probes (locateProbe) may stand on both sides of a wall: a tetrahedron of a
// Delaunay mesh does not know about walls, and probes on the lit side would light a point on
// the dark side. Unity's probe volumes and DDGI both weigh each probe by whether it sees the
// point; this is DDGI's way (Majercik et al., "Dynamic Diffuse Global Illumination with
// Ray-Traced Irradiance Fields", 2019), since the runtime has no ray tracer of its own: each
// probe keeps, per direction, the mean distance μ of what its rays hit and its deviation σ (an
// 8 × 8 octahedral map, two half floats a texel, 256 bytes a probe), filtered from its own 256
// rays with a narrow lobe (cos^200 about the texel's centre, relative to its nearest ray: in
// effect the few rays nearest the texel), read bilinearly. In the two-room test (a 1 m probe
// grid across a 10 cm wall) the light leaking through the wall, as a share of the light beside
// it: 25% as located, with DDGI's cos^50 read at the nearest texel 4.3%, cos^100 2%, cos^200
// 0.5%, read bilinearly 0.01%. A point at distance d from the probe in that direction is
//
//     seen fully when d ≤ μ + bias,   else with weight (σ² / (σ² + (d − μ − bias)²))³
//
// (Chebyshev's bound on the chance that the probe's rays reach d, cubed as DDGI does to close
// the door faster); bias = 2% of μ plus 1 cm keeps a point just in front of a wall seen. Each
// probe's interpolation weight is multiplied by its visibility (at least 1e-6, so a point no
// probe sees keeps its tetrahedral weights) and the four renormalised. The price of a narrow
// lobe on a coarse map: a point seen past a surface's grazing edge (a probe just above a
// floor, a point level with it metres away) may count as hidden; its other probes carry it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

constexpr int kProbeDepthSide = 8;
constexpr int kProbeDepthTexels = kProbeDepthSide * kProbeDepthSide;
constexpr size_t kProbeDepthValues = 2 * kProbeDepthTexels;  // per probe: μ, σ per texel
// What a ray that escapes counts as (metres; the largest half float is 65,504).
constexpr float kProbeDepthFar = 60000.0f;

// The texel of the octahedral map (x, y of the octahedron's upper half on the square, the lower
// half folded out) a unit direction falls in, and a texel's centre direction.
int probeDepthTexel(glm::vec3 direction);
glm::vec3 probeDepthTexelDirection(int texel);

// The filter from a probe's rays (the same unit directions for every probe) to its map: per
// texel, the rays within its lobe (weight above 1e-3) and their weights.
struct ProbeDepthFilter {
  std::vector<uint32_t> start;  // kProbeDepthTexels + 1
  std::vector<uint32_t> ray;
  std::vector<float> weight;
};
ProbeDepthFilter probeDepthFilter(const glm::vec3* directions, size_t rays);
// A probe's map from its rays' hit distances (misses at kProbeDepthFar): kProbeDepthValues
// half floats, per texel μ then σ.
void probeDepthMoments(const ProbeDepthFilter& filter, const float* distances, uint16_t* out);

// How much a probe with that map sees the point `offset` away from it (0..1, formula above).
float probeVisibility(const uint16_t* depth, glm::vec3 offset);

// The location's weights multiplied by each probe's visibility of `point` and renormalised;
// unchanged without maps (depth empty).
ProbeLocation weighByVisibility(const ProbeLocation& where, const std::vector<glm::vec3>& positions,
                                const std::vector<uint16_t>& depth, glm::vec3 point);
inline ProbeLocation weighByVisibility(const ProbeLocation& where, const ProbeTransport& probes,
                                       glm::vec3 point) {
  return weighByVisibility(where, probes.mesh.positions, probes.depth, point);
}

}  // namespace afterglow::runtime
