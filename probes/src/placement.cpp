// Probe placement (see placement.h): lattices over regions, octree refinement near geometry by
// triangle-box tests, and the inside/margin ray tests per candidate.
#include "afterglow/probes/placement.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <string>

#include "afterglow/trace/raytracer.h"
#include "afterglow/core/math.h"
#include "afterglow/core/parallel.h"
#include "afterglow/core/stages.h"
#include "inside_test.h"
#include "triangle_box.h"

namespace afterglow::probes {

namespace {

constexpr int kKeyBits = 21;                   // lattice coordinates packed in a uint64_t
constexpr int64_t kKeyLimit = (int64_t(1) << kKeyBits) - 1;
constexpr float kTouch = 0.01f;                // a cell "touches" geometry this far (× its size)
constexpr float kMove = 0.45f;                 // moves stay within this fraction of the cell
constexpr float kMarginReach = 3.0f;           // hits within this × margin can be the nearest

using Triangle = std::array<glm::vec3, 3>;

std::vector<Triangle> staticTriangles(const scenes::Scene& scene) {
  std::vector<Triangle> out;
  for (const scenes::Instance& inst : scene.instances) {
    if (!inst.isStatic) continue;
    scenes::forEachWorldTriangle(scene, inst, [&](size_t, size_t, glm::vec3 a, glm::vec3 b,
                                                  glm::vec3 c) {
      if (finite(a) && finite(b) && finite(c)) out.push_back({a, b, c});
    });
  }
  return out;
}

// Rounds to 1, 1.25, 1.5, 2, 2.5, 3, 4, 5, 6 or 8 times a power of ten (nearest in ratio).
float niceNumber(float x) {
  static const float kSteps[] = {1.0f, 1.25f, 1.5f, 2.0f, 2.5f, 3.0f, 4.0f, 5.0f, 6.0f, 8.0f, 10.0f};
  const float decade = std::pow(10.0f, std::floor(std::log10(x)));
  float best = decade, bestError = 1e30f;
  for (float s : kSteps) {
    const float error = std::abs(std::log(x / (s * decade)));
    if (error < bestError) { bestError = error; best = s * decade; }
  }
  return best;
}

// A lattice over a box: point (i, j, k) sits at origin + axes · (i, j, k) · unit.
struct Region {
  std::string name;          // the probe volume's, or "" for the level's bounds
  glm::vec3 origin{0.0f};
  glm::mat3 axes{1.0f};      // orthonormal columns
  glm::ivec3 cells{0};       // coarse cells per axis (0: one layer of points)
  float spacing = 0.0f;
  float unit = 0.0f;         // metres per lattice unit: spacing / 2^levels
  float margin = 0.0f;
  glm::vec3 boxLo{0.0f}, boxHi{0.0f};  // the region in lattice units
  bool keepInside = false;   // probe volumes: moved probes stay in the box

  glm::vec3 world(glm::vec3 lattice) const { return origin + axes * (lattice * unit); }
  glm::vec3 local(glm::vec3 w) const { return glm::transpose(axes) * (w - origin) / unit; }
  bool contains(glm::vec3 w) const {
    const glm::vec3 l = local(w);
    const float slack = 1e-3f;  // lattice units: a thousandth of the finest cell
    return glm::all(glm::greaterThanEqual(l, boxLo - slack)) &&
           glm::all(glm::lessThanEqual(l, boxHi + slack));
  }
};

uint64_t packKey(glm::ivec3 c) {
  return uint64_t(c.x) | (uint64_t(c.y) << kKeyBits) | (uint64_t(c.z) << (2 * kKeyBits));
}
glm::ivec3 unpackKey(uint64_t k) {
  const uint64_t mask = uint64_t(kKeyLimit);
  return glm::ivec3(int(k & mask), int((k >> kKeyBits) & mask), int((k >> (2 * kKeyBits)) & mask));
}

// What a candidate's rays see.
struct Look {
  Sight sight;                // whether it is inside geometry (inside_test.h)
  float nearest = 1e30f;      // distance to the plane of the nearest hit surface
  glm::vec3 normal{0.0f};     // that surface's normal, on the candidate's side
  glm::vec3 freeDir{0.0f};    // the mean direction of the rays that saw no surface's back
};

class Prober {
 public:
  Prober(const scenes::Scene& scene, const trace::RayTracer& tracer, int rays, float insideFraction)
      : test_(scene, tracer, insideFraction), directions_(sphereDirections(std::max(rays, 1))) {}

  bool inside(const Look& look) const { return test_.inside(look.sight); }
  bool clearlyOutside(const Look& look) const { return test_.clearlyOutside(look.sight); }

  // marginReach: hits further than this along a ray cannot be the nearest surface of interest.
  Look look(glm::vec3 p, float marginReach) const {
    std::vector<trace::Hit> hits;
    test_.firstHits(p, directions_, hits);
    Look out;
    out.sight = test_.judge(p, hits);
    glm::vec3 free(0.0f);
    for (size_t i = 0; i < hits.size(); ++i) {
      const trace::Hit& hit = hits[i];
      const glm::vec3 d = directions_[i];
      if (!hit.valid() || hit.frontFace) free += d;
      if (!hit.valid() || hit.t > marginReach) continue;
      const float cosine = glm::dot(d, hit.geometricNormal);
      const float planeDistance = hit.t * std::abs(cosine);
      if (planeDistance < out.nearest) {
        out.nearest = planeDistance;
        out.normal = cosine < 0.0f ? hit.geometricNormal : -hit.geometricNormal;
      }
    }
    const float len = glm::length(free);
    if (len > 1e-6f) out.freeDir = free / len;
    return out;
  }

 private:
  InsideTest test_;
  std::vector<glm::vec3> directions_;
};

// One candidate's fate.
struct Outcome {
  glm::vec3 position{0.0f};
  bool kept = false;
  bool moved = false;
};

// Moves a candidate out of geometry within its cell (cellSize: metres) and off surfaces by the
// margin, or drops it.
Outcome settle(const Prober& prober, const Region& region, glm::vec3 p, float cellSize) {
  const float reach = kMarginReach * region.margin;
  Outcome out;
  Look look = prober.look(p, reach);
  if (prober.inside(look)) {
    // Toward where the free rays went first, then along the cell's axes.
    std::vector<glm::vec3> offsets;
    if (look.freeDir != glm::vec3(0.0f)) {
      offsets.push_back(look.freeDir * (0.25f * cellSize));
      offsets.push_back(look.freeDir * (kMove * cellSize));
    }
    for (int a = 0; a < 3; ++a)
      for (float sign : {1.0f, -1.0f}) offsets.push_back(region.axes[a] * (sign * kMove * cellSize));
    bool found = false;
    for (const glm::vec3& o : offsets) {
      const glm::vec3 q = p + o;
      if (region.keepInside && !region.contains(q)) continue;
      const Look l = prober.look(q, reach);
      if (prober.clearlyOutside(l)) {
        p = q;
        look = l;
        found = true;
        out.moved = true;
        break;
      }
    }
    if (!found) return out;
  }
  for (int push = 0; push < 4 && look.nearest < region.margin; ++push) {
    p += look.normal * (1.02f * (region.margin - look.nearest) + 1e-6f * (1.0f + glm::length(p)));
    look = prober.look(p, reach);
    out.moved = true;
    if (prober.inside(look)) return out;
  }
  if (look.nearest < 0.999f * region.margin) return out;
  out.position = p;
  out.kept = true;
  return out;
}

// The lattice points of one region: the coarse grid, and 27 points per refined cell.
class Refiner {
 public:
  Refiner(const Region& region, int levels, const std::vector<Triangle>& world)
      : region_(region), levels_(levels), step_(1 << levels) {
    const glm::ivec3 n = glm::max(region.cells, glm::ivec3(0));
    const float touch = kTouch * float(step_);
    const glm::vec3 lo = region.boxLo - touch, hi = region.boxHi + touch;
    if (n.x == 0 || n.y == 0 || n.z == 0 || levels <= 0) return;
    bins_.resize(size_t(n.x) * size_t(n.y) * size_t(n.z));
    for (const Triangle& w : world) {
      Triangle t;
      glm::vec3 mn(1e30f), mx(-1e30f);
      for (size_t k = 0; k < 3; ++k) {
        t[k] = region.local(w[k]);
        mn = glm::min(mn, t[k]);
        mx = glm::max(mx, t[k]);
      }
      if (glm::any(glm::greaterThan(mn, hi)) || glm::any(glm::lessThan(mx, lo))) continue;
      const uint32_t index = uint32_t(triangles_.size());
      triangles_.push_back(t);
      glm::ivec3 a, b;
      for (int i = 0; i < 3; ++i) {
        a[i] = std::clamp(int(std::floor((mn[i] - touch) / float(step_))), 0, n[i] - 1);
        b[i] = std::clamp(int(std::floor((mx[i] + touch) / float(step_))), 0, n[i] - 1);
      }
      for (int z = a.z; z <= b.z; ++z)
        for (int y = a.y; y <= b.y; ++y)
          for (int x = a.x; x <= b.x; ++x)
            bins_[(size_t(z) * size_t(n.y) + size_t(y)) * size_t(n.x) + size_t(x)].push_back(index);
    }
  }

  size_t coarseCells() const { return bins_.size(); }

  // The refinement points inside coarse cell `cell` (index into the bins).
  void refineCoarse(size_t cell, std::vector<uint64_t>& out) const {
    const glm::ivec3 n = region_.cells;
    const glm::ivec3 c(int(cell % size_t(n.x)), int(cell / size_t(n.x) % size_t(n.y)),
                       int(cell / (size_t(n.x) * size_t(n.y))));
    refine(c * step_, 0, bins_[cell], out);
  }

 private:
  void refine(glm::ivec3 cellMin, int level, const std::vector<uint32_t>& candidates,
              std::vector<uint64_t>& out) const {
    const int size = step_ >> level;
    glm::vec3 lo(cellMin), hi(cellMin + size);
    for (int i = 0; i < 3; ++i) {
      // Cells on the lattice's border reach to the region's: geometry there refines them.
      if (cellMin[i] == 0) lo[i] = std::min(lo[i], region_.boxLo[i]);
      if (cellMin[i] + size == region_.cells[i] * step_) hi[i] = std::max(hi[i], region_.boxHi[i]);
    }
    lo -= kTouch * float(size);
    hi += kTouch * float(size);
    std::vector<uint32_t> here;
    for (uint32_t t : candidates) {
      const Triangle& tri = triangles_[t];
      if (triangleOverlapsBox(tri[0], tri[1], tri[2], lo, hi)) here.push_back(t);
    }
    if (here.empty() || flat(here, float(size))) return;
    const int half = size / 2;
    for (int z = 0; z <= 2; ++z)
      for (int y = 0; y <= 2; ++y)
        for (int x = 0; x <= 2; ++x) out.push_back(packKey(cellMin + half * glm::ivec3(x, y, z)));
    if (level + 1 >= levels_) return;
    for (int child = 0; child < 8; ++child)
      refine(cellMin + half * glm::ivec3(child & 1, child >> 1 & 1, child >> 2 & 1), level + 1,
             here, out);
  }

  // All the cell's triangles in one plane (a stretch of floor or wall): light varies slowly
  // along a plane, so the refinement is spent on edges, corners and objects instead.
  bool flat(const std::vector<uint32_t>& here, float size) const {
    glm::vec3 n(0.0f), o(0.0f);
    for (uint32_t t : here) {
      const Triangle& tri = triangles_[t];
      const glm::vec3 c = glm::cross(tri[1] - tri[0], tri[2] - tri[0]);
      const float len = glm::length(c);
      if (len > 1e-12f) {
        n = c / len;
        o = tri[0];
        break;
      }
    }
    if (n == glm::vec3(0.0f)) return true;  // only degenerate triangles
    const float tolerance = 1e-3f * size;
    for (uint32_t t : here)
      for (const glm::vec3& v : triangles_[t])
        if (std::abs(glm::dot(v - o, n)) > tolerance) return false;
    return true;
  }

  const Region& region_;
  int levels_;
  int step_;
  std::vector<Triangle> triangles_;            // in lattice units
  std::vector<std::vector<uint32_t>> bins_;    // per coarse cell
};

int levelOf(glm::ivec3 c, int levels) {
  for (int l = 0; l < levels; ++l) {
    const int step = 1 << (levels - l);
    if (c.x % step == 0 && c.y % step == 0 && c.z % step == 0) return l;
  }
  return levels;
}

// The next of niceNumber's values above x.
float nextNice(float x) {
  float s = niceNumber(x);
  for (float f = 1.05f; s <= x * 1.001f; f *= 1.05f) s = niceNumber(x * f);
  return s;
}

std::string budgetMessage(size_t count, size_t maxProbes, float spacing, float fit, int levels) {
  return format("probe placement: %zu probes exceed the budget of %zu (maxProbes, --max-probes): "
                "use a larger --spacing (%.3g m now; %.3g m fits) or fewer --levels (%d now)",
                count, maxProbes, double(spacing), double(fit), levels);
}

struct Candidate {
  uint32_t region;
  uint8_t level;
  glm::vec3 position;
};

// The regions: the probe volumes, else the static bounds. spacingOverride > 0 replaces every
// spacing (the budget's search for one that fits).
Result<std::vector<Region>> makeRegions(const scenes::Scene& scene, const PlacementOptions& options,
                                        float spacingOverride) {
  const int step = 1 << options.levels;
  std::vector<Region> regions;
  auto finishRegion = [&](Region& r) {
    r.unit = r.spacing / float(step);
    r.margin = options.margin > 0.0f ? options.margin : 0.1f * r.unit;  // of the finest spacing
  };
  auto spacingFor = [&](float own) {
    return spacingOverride > 0.0f ? spacingOverride
           : options.spacing > 0.0f ? options.spacing
           : own > 0.0f             ? own
                                    : autoSpacing(scene);
  };
  for (const scenes::ProbeVolume& v : scene.probeVolumes) {
    const std::string where = format("probe volume '%s' (node %d)", v.name.c_str(), v.node);
    if (!finite(v.size) || !(v.size.x > 0.0f && v.size.y > 0.0f && v.size.z > 0.0f))
      return Status::error(format("%s: size (%g, %g, %g) is not positive", where.c_str(),
                                  double(v.size.x), double(v.size.y), double(v.size.z)));
    if (!(v.spacing >= 0.0f) || !std::isfinite(v.spacing))
      return Status::error(where + ": spacing is not a positive number");
    Region r;
    r.name = v.name;
    r.keepInside = true;
    r.spacing = spacingFor(v.spacing);
    glm::vec3 extent;
    glm::mat3 axes;
    for (int i = 0; i < 3; ++i) {
      glm::vec3 c(v.transform[i]);
      for (int j = 0; j < i; ++j) c -= glm::dot(c, axes[j]) * axes[j];  // Gram-Schmidt
      const float len = glm::length(glm::vec3(v.transform[i]));
      const float ortho = glm::length(c);
      if (!(ortho > 1e-12f) || !std::isfinite(ortho))
        return Status::error(where + ": its node's transform has no volume");
      axes[i] = c / ortho;
      extent[i] = v.size[i] * len;
    }
    r.axes = axes;
    for (int i = 0; i < 3; ++i)
      r.cells[i] = int(std::min(1e9f, std::floor(extent[i] / r.spacing + 1e-4f)));
    finishRegion(r);
    const glm::vec3 span = glm::vec3(r.cells) * r.spacing;
    r.origin = glm::vec3(v.transform[3]) - axes * (0.5f * span);
    r.boxLo = (0.5f * span - 0.5f * extent) / r.unit;
    r.boxHi = (0.5f * span + 0.5f * extent) / r.unit;
    regions.push_back(r);
  }
  if (regions.empty()) {
    const scenes::Bounds b = scene.staticBounds();
    if (b.empty()) return regions;
    Region r;
    r.spacing = spacingFor(0.0f);
    const glm::vec3 e = b.size();
    // The lattice sits inside the bounds, a tenth of a cell or more from them, so no grid point
    // lies on the walls of a closed room or just outside them.
    for (int i = 0; i < 3; ++i)
      r.cells[i] = std::max(1, int(std::min(1e9f, std::floor((e[i] - 0.2f * r.spacing) / r.spacing))));
    finishRegion(r);
    const glm::vec3 span = glm::vec3(r.cells) * r.spacing;
    r.origin = 0.5f * (b.min + b.max) - 0.5f * span;
    r.boxLo = (b.min - r.origin) / r.unit;
    r.boxHi = (b.max - r.origin) / r.unit;
    regions.push_back(r);
  }
  return regions;
}

// Coarse grid points over the regions; +infinity when a lattice outgrows its coordinates.
double coarseCount(const std::vector<Region>& regions, int levels) {
  double count = 0.0;
  for (const Region& r : regions) {
    for (int i = 0; i < 3; ++i)
      if (double(r.cells[i]) * double(1 << levels) > double(kKeyLimit - 1))
        return std::numeric_limits<double>::infinity();
    count += double(r.cells.x + 1) * double(r.cells.y + 1) * double(r.cells.z + 1);
  }
  return count;
}

// The candidates: per region, the coarse grid and the refinement's points, deduplicated on the
// lattice and sorted by (level, z, y, x). Call only when coarseCount() is finite and small.
// false when cancelled.
bool makeCandidates(const std::vector<Region>& regions, int levels,
                    const std::vector<Triangle>& triangles, Progress& progress,
                    std::vector<Candidate>& candidates) {
  const int step = 1 << levels;
  candidates.clear();
  for (size_t ri = 0; ri < regions.size(); ++ri) {
    const Region& r = regions[ri];
    std::vector<uint64_t> keys;
    for (int z = 0; z <= r.cells.z; ++z)
      for (int y = 0; y <= r.cells.y; ++y)
        for (int x = 0; x <= r.cells.x; ++x) keys.push_back(packKey(glm::ivec3(x, y, z) * step));
    const Refiner refiner(r, levels, triangles);
    std::vector<std::vector<uint64_t>> perCell(refiner.coarseCells());
    parallelFor(perCell.size(), [&](size_t c) {
      if (!progress.cancelled()) refiner.refineCoarse(c, perCell[c]);
    }, 1);
    if (progress.cancelled()) return false;
    for (const auto& cell : perCell) keys.insert(keys.end(), cell.begin(), cell.end());
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    std::vector<std::pair<int, uint64_t>> ordered;
    ordered.reserve(keys.size());
    for (uint64_t k : keys) ordered.emplace_back(levelOf(unpackKey(k), levels), k);
    std::sort(ordered.begin(), ordered.end());
    for (const auto& [level, k] : ordered)
      candidates.push_back(Candidate{uint32_t(ri), uint8_t(level), r.world(glm::vec3(unpackKey(k)))});
  }
  return true;
}

// The smallest of niceNumber's spacings above `from` whose candidates number at most `limit`
// (0 when none up to a kilometre does, or when cancelled).
float fittingSpacing(const scenes::Scene& scene, const PlacementOptions& options,
                     const std::vector<Triangle>& triangles, float from, double coarse,
                     size_t limit, Progress& progress) {
  // Start where the coarse grid alone fits.
  float s = from;
  if (coarse > double(limit))
    s = std::max(s, float(double(from) * std::cbrt(std::min(coarse, 1e30) / double(limit))) * 0.9f);
  std::vector<Candidate> candidates;
  for (s = nextNice(s); s < 1000.0f; s = nextNice(s)) {
    Result<std::vector<Region>> regions = makeRegions(scene, options, s);
    if (!regions) return 0.0f;
    if (!(coarseCount(*regions, options.levels) <= double(limit))) continue;
    if (!makeCandidates(*regions, options.levels, triangles, progress, candidates)) return 0.0f;
    if (candidates.size() <= limit) return s;
  }
  return 0.0f;
}

}  // namespace

float autoSpacing(const scenes::Scene& scene) {
  const scenes::Bounds b = scene.staticBounds();
  if (b.empty()) return 1.0f;
  const glm::vec3 e = b.size();
  const float longest = std::max({e.x, e.y, e.z});
  if (!(longest > 0.0f) || !std::isfinite(longest)) return 1.0f;
  // A flat level counts as an eighth of its length thick.
  const glm::vec3 d = glm::max(e, glm::vec3(longest / 8.0f));
  const float size = std::cbrt(d.x * d.y * d.z);
  // 0.25 m for a 2 m room, growing slower than the level so a large level gets more points
  // (36 × 15 × 22 m: 1.5 m; Sponza.gltf, with its roofs: 2 m; a few thousand grid points).
  return niceNumber(0.25f * std::pow(size / 2.0f, 0.75f));
}

Result<Placement> placeProbes(const scenes::Scene& scene, const trace::RayTracer& tracer,
                              const PlacementOptions& options, Progress& progress) {
  if (options.levels < 0 || options.levels > 8)
    return Result<Placement>::error(format("probe placement: levels %d is outside [0, 8]",
                                           options.levels));
  if (!(options.spacing >= 0.0f) || !std::isfinite(options.spacing))
    return Result<Placement>::error("probe placement: spacing must be a positive number");
  if (!(options.margin >= 0.0f) || !std::isfinite(options.margin))
    return Result<Placement>::error("probe placement: margin must be a non-negative number");
  if (options.rays < 1)
    return Result<Placement>::error("probe placement: rays must be at least 1");
  for (size_t i = 0; i < options.userProbes.size(); ++i)
    if (!finite(options.userProbes[i])) {
      const std::string name = i < options.userNames.size() && !options.userNames[i].empty()
                                   ? "'" + options.userNames[i] + "'"
                                   : format("%zu", i);
      return Result<Placement>::error("probe placement: user probe " + name + " is not finite");
    }

  const int levels = options.levels;
  const int step = 1 << levels;
  Placement placement;

  Result<std::vector<Region>> made = makeRegions(scene, options, 0.0f);
  if (!made) return made.status();
  std::vector<Region> regions = std::move(*made);
  if (regions.empty())
    placement.warnings.push_back("probe placement: no static geometry and no probe volumes; "
                                 "only the user's probes are placed");
  placement.spacing = regions.empty() ? options.spacing : regions[0].spacing;
  placement.margin = regions.empty() ? options.margin : regions[0].margin;

  // The budget: the coarse grids first, before allocating anything, then the refinement.
  const size_t limit = options.maxProbes > options.userProbes.size()
                           ? options.maxProbes - options.userProbes.size()
                           : 0;
  const std::vector<Triangle> triangles =
      levels > 0 ? staticTriangles(scene) : std::vector<Triangle>();
  std::vector<Candidate> candidates;
  double coarse = coarseCount(regions, levels);
  size_t over = 0;
  if (coarse > double(limit)) {
    over = size_t(std::min(coarse, 1e18)) + options.userProbes.size();
  } else {
    if (!makeCandidates(regions, levels, triangles, progress, candidates))
      return Result<Placement>::error("cancelled");
    if (candidates.size() > limit) over = candidates.size() + options.userProbes.size();
  }
  if (over > 0) {
    const float fit = fittingSpacing(scene, options, triangles, placement.spacing, coarse, limit,
                                     progress);
    if (progress.cancelled()) return Result<Placement>::error("cancelled");
    bool authored = options.spacing > 0.0f;
    for (const scenes::ProbeVolume& v : scene.probeVolumes) authored = authored || v.spacing > 0.0f;
    if (authored || !(fit > 0.0f))
      return Result<Placement>::error(
          budgetMessage(over, options.maxProbes, placement.spacing, fit, levels));
    // The spacing was ours to choose: choose one that fits.
    placement.warnings.push_back(format(
        "probe placement: the automatic spacing %.3g m gives %zu probes, over the budget of %zu; "
        "%.3g m used",
        double(placement.spacing), over, options.maxProbes, double(fit)));
    made = makeRegions(scene, options, fit);
    if (!made) return made.status();
    regions = std::move(*made);
    placement.spacing = regions[0].spacing;
    placement.margin = regions[0].margin;
    if (!makeCandidates(regions, levels, triangles, progress, candidates))
      return Result<Placement>::error("cancelled");
  }
  placement.candidates = candidates.size();

  // The ray tests, one slot per candidate.
  const Prober prober(scene, tracer, options.rays, options.insideFraction);
  std::vector<Outcome> outcomes(candidates.size());
  progress.begin(stageName(Stage::ProbePlacement), candidates.size());
  parallelForBlocks(candidates.size(), [&](size_t begin, size_t end, int) {
    if (progress.cancelled()) return;
    for (size_t i = begin; i < end; ++i) {
      const Candidate& c = candidates[i];
      const Region& r = regions[c.region];
      outcomes[i] = settle(prober, r, c.position, r.unit * float(step >> c.level));
    }
    progress.advance(end - begin);
  }, 64);
  progress.end();
  if (progress.cancelled()) return Result<Placement>::error("cancelled");

  // A placed probe exactly where the user pinned one gives way to it (a PROBES.json added back
  // with --add pins every probe it holds), so no two probes share a position.
  std::set<std::array<float, 3>> pinnedAt;
  for (const glm::vec3& p : options.userProbes) pinnedAt.insert({p.x, p.y, p.z});
  for (size_t i = 0; i < candidates.size(); ++i) {
    const Outcome& o = outcomes[i];
    if (!o.kept) {
      ++placement.rejected;
      continue;
    }
    if (pinnedAt.count({o.position.x, o.position.y, o.position.z})) continue;
    ProbeKind kind = candidates[i].level == 0 ? ProbeKind::Grid : ProbeKind::Refined;
    if (o.moved) {
      kind = ProbeKind::Moved;
      ++placement.moved;
    } else if (kind == ProbeKind::Refined) {
      ++placement.refined;
    }
    placement.positions.push_back(o.position);
    placement.kinds.push_back(kind);
  }

  // The user's probes, as given.
  for (size_t i = 0; i < options.userProbes.size(); ++i) {
    const glm::vec3 p = options.userProbes[i];
    const Look look = prober.look(p, 0.0f);
    if (prober.inside(look)) {
      const std::string name = i < options.userNames.size() && !options.userNames[i].empty()
                                   ? "'" + options.userNames[i] + "'"
                                   : format("%zu", i);
      placement.warnings.push_back(format(
          "user probe %s at (%g, %g, %g) is inside geometry (%.0f%% of its rays see the backs of "
          "single-sided surfaces; a double-sided object winds %.2f times around it); kept where "
          "it is",
          name.c_str(), double(p.x), double(p.y), double(p.z),
          100.0 * double(look.sight.backFraction), double(look.sight.winding)));
    }
    placement.positions.push_back(p);
    placement.kinds.push_back(ProbeKind::Pinned);
  }
  return placement;
}

std::vector<uint8_t> freeProbePositions(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                        const std::vector<glm::vec3>& points, float margin,
                                        const PlacementOptions& options) {
  const Prober prober(scene, tracer, std::max(options.rays, 1), options.insideFraction);
  std::vector<uint8_t> clear(points.size(), 0);
  // As settle() keeps a candidate: outside (by the clear margin a move needs: these points lie
  // between probes, often near the geometry that made their light differ) and off surfaces.
  parallelFor(points.size(), [&](size_t i) {
    if (!finite(points[i])) return;
    const Look look = prober.look(points[i], kMarginReach * margin);
    clear[i] = prober.clearlyOutside(look) && look.nearest >= 0.999f * margin;
  }, 64);
  return clear;
}

}  // namespace afterglow::probes
