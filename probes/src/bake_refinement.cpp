// Splitting the tetrahedra's edges across which a bake's light changes (bake_refinement.h).
#include "afterglow/probes/bake_refinement.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <set>

namespace afterglow::probes {

glm::vec3 axisNormal(int k) {
  glm::vec3 n(0.0f);
  n[k / 2] = k % 2 == 0 ? 1.0f : -1.0f;
  return n;
}

float irradianceDifference(const AxisIrradiance& a, const AxisIrradiance& b, float floor) {
  float worst = 0.0f;
  for (size_t k = 0; k < a.size(); ++k) {
    const glm::vec3 x = glm::max(a[k], glm::vec3(0.0f)), y = glm::max(b[k], glm::vec3(0.0f));
    const glm::vec3 d = glm::abs(x - y);
    const float scale = std::max({x.r, x.g, x.b, y.r, y.g, y.b, floor});
    if (scale > 0.0f) worst = std::max(worst, std::max({d.r, d.g, d.b}) / scale);
  }
  return worst;
}

Result<BakeRefinement> refineByBake(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                    const PlacementOptions& placementOptions,
                                    const runtime::ProbeTetrahedra& mesh,
                                    const std::vector<AxisIrradiance>& irradiance,
                                    const BakeRefinementOptions& options, Placement& placement) {
  const size_t n = placement.positions.size();
  if (irradiance.size() != n)
    return Status::error(format("bake refinement: %zu irradiance values for %zu probes",
                                irradiance.size(), n));
  if (mesh.positions.size() != n)
    return Status::error(format("bake refinement: tetrahedra over %zu probes for a placement "
                                "of %zu", mesh.positions.size(), n));
  if (!(options.threshold >= 0.0f) || !(options.floorFraction >= 0.0f))
    return Status::error("bake refinement: the threshold and floor must not be negative");

  BakeRefinement out;
  float brightest = 0.0f;
  for (const AxisIrradiance& e : irradiance)
    for (const glm::vec3& v : e)
      for (int c = 0; c < 3; ++c)
        if (std::isfinite(v[c])) brightest = std::max(brightest, v[c]);
  out.floor = options.floorFraction * brightest;

  // The edges, each once, as (lower, higher) probe index, sorted.
  std::vector<uint64_t> edges;
  edges.reserve(mesh.tetrahedra.size() * 6);
  for (const glm::ivec4& t : mesh.tetrahedra)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const uint32_t a = uint32_t(std::min(t[i], t[j])), b = uint32_t(std::max(t[i], t[j]));
        if (b < n) edges.push_back((uint64_t(a) << 32) | b);
      }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  out.edges = edges.size();

  // No shorter than the finest cells' diagonal (a little slack for the float lattice).
  const float finest = placement.spacing / float(1 << std::clamp(placementOptions.levels, 0, 30));
  const float shortest = std::sqrt(3.0f) * finest * 1.001f;

  // The edges to split, and their midpoints: not on a probe, nor twice (a square's diagonals).
  struct Split {
    glm::vec3 midpoint;
    float difference;
  };
  std::vector<Split> splits;
  std::set<std::array<float, 3>> taken;
  for (const glm::vec3& p : placement.positions) taken.insert({p.x, p.y, p.z});
  for (uint64_t e : edges) {
    const size_t a = size_t(e >> 32), b = size_t(e & 0xffffffffu);
    if (glm::distance(placement.positions[a], placement.positions[b]) <= shortest) {
      ++out.shortEdges;
      continue;
    }
    const float d = irradianceDifference(irradiance[a], irradiance[b], out.floor);
    if (!(d > options.threshold)) continue;
    ++out.overThreshold;
    const glm::vec3 m = 0.5f * (placement.positions[a] + placement.positions[b]);
    if (!taken.insert({m.x, m.y, m.z}).second) {
      ++out.rejected;
      continue;
    }
    splits.push_back({m, d});
  }

  // The placement's own tests, one slot per midpoint.
  std::vector<glm::vec3> midpoints;
  for (const Split& s : splits) midpoints.push_back(s.midpoint);
  const std::vector<uint8_t> clear =
      freeProbePositions(scene, tracer, midpoints, placement.margin, placementOptions);
  std::vector<size_t> kept;
  for (size_t i = 0; i < splits.size(); ++i) {
    if (clear[i]) kept.push_back(i);
    else ++out.rejected;
  }

  // The budget: the largest differences first (ties in edge order), then back to edge order.
  const size_t room = placementOptions.maxProbes > n ? placementOptions.maxProbes - n : 0;
  if (kept.size() > room) {
    std::stable_sort(kept.begin(), kept.end(), [&](size_t x, size_t y) {
      return splits[x].difference > splits[y].difference;
    });
    out.overBudget = kept.size() - room;
    kept.resize(room);
    std::sort(kept.begin(), kept.end());
    placement.warnings.push_back(format(
        "bake refinement: %zu of the %zu probes it would add exceed the budget of %zu "
        "(--max-probes) and were left out, those where the light differs least",
        out.overBudget, out.overBudget + kept.size(), placementOptions.maxProbes));
  }
  for (size_t i : kept) {
    placement.positions.push_back(splits[i].midpoint);
    placement.kinds.push_back(ProbeKind::Refined);
  }
  out.added = kept.size();
  return out;
}

}  // namespace afterglow::probes
