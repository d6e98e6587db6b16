// The light probes' ray directions (probe_transfer.cpp): one ray at the centre of each cell
// of an equal-area octahedral grid over the sphere, turned by a fixed rotation, grouped in
// square regions of cells, with the weights that turn the regions' mean radiances into SH L2.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/transport.h"

namespace afterglow::baker {

// Clarberg's equal-area octahedral map from [-1, 1]² to the unit sphere (z up on the square's
// centre): equal areas of the square map to equal solid angles (dω = π du dv).
glm::vec3 equalAreaOctahedral(glm::vec2 square);

// A probe ray's direction for a point of the octahedral square: the map turned by a fixed,
// generic rotation (see probe_directions.cpp).
glm::vec3 probeDirection(glm::vec2 square);

// Every probe's rays: side² directions in region order (the cells of region 0, then of region
// 1, ...: regions are regionsSide² blocks of the grid, square when regionsSide divides side,
// else with sides that differ by a cell), and per direction its region,
// its SH basis and the products Ω Y_i Y_j the sky's transfer sums (upper triangle,
// runtime::probeSkyIndex), Ω = 4π / side² each.
struct ProbeDirections {
  ProbeDirections(uint32_t side, uint32_t regionsSide);
  uint32_t rays = 0, regions = 0;
  float omega = 0.0f;
  std::vector<glm::vec3> direction;
  std::vector<uint32_t> region;
  std::vector<uint32_t> raysOfRegion;  // per region, how many rays (cells) it has
  std::vector<float> basis;     // rays × kShCount
  std::vector<float> products;  // rays × kProbeSkyCount
  double allProducts[runtime::kProbeSkyCount] = {};  // their sum over every ray (≈ I)
  // Per region b and coefficient i, the weight of the region's mean radiance in L_i: the
  // least-squares SH L2 fit to the region means (regionWeights in probe_directions.cpp).
  std::vector<float> regionSh;  // regions × kShCount
};

}  // namespace afterglow::baker
