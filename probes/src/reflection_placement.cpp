// Reflection probe proposals (see reflection_placement.h): a coarse grid of candidates, each
// measuring its room by rays, then a greedy choice of well-fitting boxes that do not overlap.
#include "afterglow/probes/reflection_placement.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "afterglow/trace/raytracer.h"
#include "afterglow/core/math.h"
#include "afterglow/core/parallel.h"
#include "afterglow/core/stages.h"
#include "afterglow/probes/placement.h"
#include "inside_test.h"

namespace afterglow::probes {

namespace {

constexpr float kWallQuantile = 0.8f;    // as baker::fitReflectionProbeBox: walls behind furniture
constexpr float kConeDegrees = 30.0f;    // rays counted toward an axis direction
constexpr float kFitTolerance = 0.1f;    // a ray ends "on" its box within this × its exit distance
constexpr float kEnclosed = 0.5f;        // fewer rays on surfaces' fronts: not a room
constexpr float kThin = 0.5f;            // a box thinner than this × the spacing is a gap
constexpr float kMostlyKept = 0.5f;      // a box this much inside kept boxes adds nothing
constexpr float kCentreMargin = 0.05f;   // the capture point stays this × spacing off surfaces

float quantile(std::vector<float>& values, float q) {
  const size_t k = std::min(values.size() - 1, size_t(q * float(values.size())));
  std::nth_element(values.begin(), values.begin() + long(k), values.end());
  return values[k];
}

// What one candidate's rays found.
struct Measure {
  bool inside = false;
  float enclosed = 0.0f;         // rays that hit a front face (or a double-sided surface)
  glm::vec3 lo{0.0f}, hi{0.0f};  // the fitted box
  float score = 0.0f;            // rays ending on the box's faces
};

float volume(glm::vec3 lo, glm::vec3 hi) {
  const glm::vec3 e = glm::max(hi - lo, glm::vec3(0.0f));
  return e.x * e.y * e.z;
}

bool contains(glm::vec3 lo, glm::vec3 hi, glm::vec3 p) {
  return glm::all(glm::greaterThanEqual(p, lo)) && glm::all(glm::lessThanEqual(p, hi));
}

class RoomMeter {
 public:
  RoomMeter(const scenes::Scene& scene, const trace::RayTracer& tracer, int rays,
            float insideFraction, const scenes::Bounds& bounds)
      : tracer_(tracer), test_(scene, tracer, insideFraction), directions_(sphereDirections(rays)),
        bounds_(bounds) {}

  Measure measure(glm::vec3 p) const {
    const size_t n = directions_.size();
    std::vector<trace::Hit> hits;
    test_.firstHits(p, directions_, hits);
    Measure m;
    m.inside = test_.inside(test_.judge(p, hits));
    if (m.inside) return m;
    std::vector<float> t(n, -1.0f);  // hit distances; -1 for a miss
    size_t front = 0;
    for (size_t i = 0; i < n; ++i) {
      const trace::Hit& hit = hits[i];
      if (!hit.valid()) continue;
      if (hit.frontFace || tracer_.material(hit).doubleSided) ++front;
      t[i] = hit.t;
    }
    m.enclosed = float(front) / float(n);

    // The box: per axis direction, the wall quantile of the distances along it.
    const float cone = std::cos(kConeDegrees * kPi / 180.0f);
    bool open[3][2];
    std::vector<float> along;
    for (int a = 0; a < 3; ++a)
      for (int s = 0; s < 2; ++s) {
        const float sign = s == 0 ? -1.0f : 1.0f;
        along.clear();
        for (size_t i = 0; i < n; ++i) {
          const float c = directions_[i][a] * sign;
          if (c >= cone && t[i] >= 0.0f) along.push_back(t[i] * c);
        }
        const float bound = s == 0 ? p[a] - bounds_.min[a] : bounds_.max[a] - p[a];
        open[a][s] = along.empty();
        const float reach = std::max(along.empty() ? bound : quantile(along, kWallQuantile), 1e-3f);
        if (s == 0) m.lo[a] = p[a] - reach;
        else m.hi[a] = p[a] + reach;
      }

    // The fit: rays that end on the box's faces, or leave through an open one into the sky.
    const glm::vec3 extent = m.hi - m.lo;
    const float slack = 0.01f * std::min({extent.x, extent.y, extent.z});
    size_t fit = 0;
    for (size_t i = 0; i < n; ++i) {
      const glm::vec3 d = directions_[i];
      float exit = 1e30f;
      int face = 0, side = 0;
      for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0f) continue;
        const float e = ((d[a] > 0.0f ? m.hi[a] : m.lo[a]) - p[a]) / d[a];
        if (e < exit) exit = e, face = a, side = d[a] > 0.0f ? 1 : 0;
      }
      if (t[i] < 0.0f) fit += open[face][side];
      else fit += std::abs(t[i] - exit) <= kFitTolerance * exit + slack;
    }
    m.score = float(fit) / float(n);
    return m;
  }

 private:
  const trace::RayTracer& tracer_;
  InsideTest test_;
  std::vector<glm::vec3> directions_;
  scenes::Bounds bounds_;
};

// Rounds to a quantum a person reads easily (a millimetre for a room, a centimetre for a
// level), so an edited file stays tidy; the written decimal reads back to the same float.
float tidy(float v, double quantum) { return float(std::round(double(v) / quantum) * quantum); }

}  // namespace

scenes::ReflectionProbe toSceneReflectionProbe(const ReflectionProbeEntry& entry) {
  scenes::ReflectionProbe probe;
  probe.name = entry.name;
  probe.node = -1;  // from the probes file, not a node of the scene
  probe.transform = glm::mat4(1.0f);
  probe.transform[3] = glm::vec4(entry.position, 1.0f);
  probe.size = entry.size;
  probe.projectionSize = entry.projectionSize;
  probe.blendDistance = entry.blendDistance;
  probe.importance = entry.importance;
  probe.boxProjection = entry.boxProjection;
  probe.resolution = entry.resolution;
  return probe;
}

Result<ReflectionPlacement> placeReflectionProbes(const scenes::Scene& scene,
                                                  const trace::RayTracer& tracer,
                                                  const ReflectionPlacementOptions& options,
                                                  Progress& progress) {
  if (!(options.spacing >= 0.0f) || !std::isfinite(options.spacing))
    return Status::error("reflection probe placement: spacing must be a positive number");
  if (options.rays < 64)
    return Status::error("reflection probe placement: rays must be at least 64");
  if (options.maxProbes == 0)
    return Status::error("reflection probe placement: maxProbes must be at least 1");
  ReflectionPlacement out;
  const scenes::Bounds bounds = scene.staticBounds();
  if (bounds.empty()) {
    out.warnings.push_back("reflection probe placement: no static geometry, no proposals");
    return out;
  }

  // The candidates: cell centres of a grid over the bounds, coarse enough for the budget.
  const glm::vec3 e = bounds.size();
  float spacing = options.spacing > 0.0f ? options.spacing : autoSpacing(scene);
  glm::ivec3 cells(1);
  for (int guard = 0; guard < 200; ++guard, spacing *= 1.25f) {
    for (int a = 0; a < 3; ++a)
      cells[a] = std::max(1, int(std::min(1e6f, std::round(e[a] / spacing))));
    if (double(cells.x) * double(cells.y) * double(cells.z) <= double(options.maxCandidates))
      break;
  }
  out.spacing = spacing;
  std::vector<glm::vec3> points;
  for (int z = 0; z < cells.z; ++z)
    for (int y = 0; y < cells.y; ++y)
      for (int x = 0; x < cells.x; ++x)
        points.push_back(bounds.min + (glm::vec3(x, y, z) + 0.5f) * e / glm::vec3(cells));
  out.candidates = points.size();

  const RoomMeter meter(scene, tracer, options.rays, options.insideFraction, bounds);
  std::vector<Measure> measures(points.size());
  progress.begin(stageStep(Stage::ProbePlacement, "reflection probes"), points.size());
  parallelForBlocks(points.size(), [&](size_t begin, size_t end, int) {
    if (progress.cancelled()) return;
    for (size_t i = begin; i < end; ++i) measures[i] = meter.measure(points[i]);
    progress.advance(end - begin);
  }, 4);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");

  // Room-like candidates, then their boxes' centres (where the probes capture) checked free by
  // the light probes' own test, all at once.
  std::vector<size_t> viable;
  std::vector<glm::vec3> centres;
  for (size_t i = 0; i < points.size(); ++i) {
    const Measure& m = measures[i];
    const glm::vec3 extent = m.hi - m.lo;
    if (m.inside) ++out.inside;
    else if (m.enclosed < kEnclosed) ++out.open;
    else if (std::min({extent.x, extent.y, extent.z}) < kThin * spacing) ++out.thin;
    else {
      viable.push_back(i);
      centres.push_back(0.5f * (m.lo + m.hi));
    }
  }
  PlacementOptions freeOptions;
  freeOptions.insideFraction = options.insideFraction;
  const std::vector<uint8_t> free =
      freeProbePositions(scene, tracer, centres, kCentreMargin * spacing, freeOptions);

  // Best fit first; equal scores (the same room seen from several cells) by volume, then index.
  std::vector<size_t> order;
  for (size_t k = 0; k < viable.size(); ++k) {
    if (free[k]) order.push_back(k);
    else ++out.centreBlocked;
  }
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const Measure& ma = measures[viable[a]];
    const Measure& mb = measures[viable[b]];
    if (ma.score != mb.score) return ma.score > mb.score;
    return volume(ma.lo, ma.hi) > volume(mb.lo, mb.hi);
  });

  const double quantum = std::pow(10.0, std::floor(std::log10(double(spacing) / 100.0)));
  std::vector<std::pair<glm::vec3, glm::vec3>> kept;
  for (size_t k : order) {
    const Measure& m = measures[viable[k]];
    const glm::vec3 centre = centres[k];
    bool covered = false;
    float shared = 0.0f;
    for (const auto& [lo, hi] : kept) {
      covered = covered || contains(lo, hi, points[viable[k]]) || contains(lo, hi, centre);
      shared += volume(glm::max(lo, m.lo), glm::min(hi, m.hi));
    }
    if (covered || shared > kMostlyKept * volume(m.lo, m.hi)) {
      ++out.overlapping;
      continue;
    }
    // Past the budget a region still counts as kept, so its other candidates are not counted
    // as further regions.
    kept.emplace_back(m.lo, m.hi);
    if (out.probes.size() >= options.maxProbes) {
      ++out.overBudget;
      continue;
    }
    ReflectionProbeEntry probe;
    probe.name = format("reflection_probe_%zu", out.probes.size());
    const glm::vec3 size = m.hi - m.lo;
    // A quarter of the room's smallest side, at most a metre (the glTF default), so the weight
    // fades in near the walls without a small room fading everywhere.
    probe.blendDistance =
        tidy(std::min(1.0f, 0.25f * std::min({size.x, size.y, size.z})), quantum);
    // The walls are the projection box; the influence box reaches past them by the blend
    // distance and a quarter more (the walls stand up to a few millimetres beyond the measured
    // box), so the walls, and what stands on the floor, get the probe's full weight (a box that
    // ended on the walls faded to 0 there, and a rough metal wall rendered black).
    for (int a = 0; a < 3; ++a) {
      probe.position[a] = tidy(centre[a], quantum);
      probe.projectionSize[a] = std::max(tidy(size[a], quantum), float(quantum));
      probe.size[a] = tidy(probe.projectionSize[a] + 2.5f * probe.blendDistance, quantum);
    }
    probe.importance = 1;
    probe.boxProjection = true;
    probe.resolution = options.resolution;
    out.probes.push_back(probe);
  }
  if (out.overBudget > 0)
    out.warnings.push_back(format(
        "reflection probe placement: %zu more room-like regions than --max-reflection-probes %zu "
        "were left out (the worst fitting)",
        out.overBudget, options.maxProbes));
  return out;
}

}  // namespace afterglow::probes
