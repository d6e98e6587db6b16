// afterglow uv: charts per unique mesh, one packing over every static instance, then a mesh of its
// own for each static instance carrying its lightmap UVs.
#include "afterglow/uv/unwrap.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <cmath>
#include <numeric>

#include "afterglow/core/check.h"
#include "afterglow/core/timer.h"
#include "afterglow/core/parallel.h"
#include "afterglow/core/stages.h"

namespace afterglow::uv {

namespace {

using scenes::Instance;
using scenes::Mesh;
using scenes::Primitive;
using scenes::Scene;
std::string sceneName(const Scene& scene) {
  return scene.sourcePath.empty() ? std::string("scene") : scene.sourcePath;
}

// Relative tolerance on AᵀA = s²I below which a transform counts as a similarity.
constexpr double kSimilarityTolerance = 1e-3;

// Returns true when the linear part of `m` is a rotation (or reflection) times a uniform scale,
// and that scale (cbrt|det|) in *scale. Charts of such instances can be shared with the mesh's
// object-space charts; anything else distorts them and needs its own.
bool similarityScale(const glm::mat4& m, double* scale) {
  const glm::dmat3 a = glm::dmat3(glm::mat3(m));
  double det = glm::determinant(a);
  double s = std::cbrt(std::abs(det));
  *scale = s;
  if (!std::isfinite(s) || s <= 0.0) return false;
  glm::dmat3 ata = glm::transpose(a) * a;
  double s2 = s * s;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (std::abs(ata[i][j] - (i == j ? s2 : 0.0)) > kSimilarityTolerance * s2) return false;
  return true;
}

Mesh worldCopy(const Mesh& mesh, const glm::mat4& transform) {
  Mesh out = mesh;
  glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(transform)));
  for (Primitive& p : out.primitives) {
    for (glm::vec3& v : p.positions) v = glm::vec3(transform * glm::vec4(v, 1.0f));
    for (glm::vec3& n : p.normals) {
      glm::vec3 t = normalMatrix * n;
      float len = glm::length(t);
      n = len > 0.0f && std::isfinite(len) ? t / len : n;
    }
  }
  return out;
}

bool staticWithGeometry(const Scene& scene, const Instance& inst) {
  return inst.isStatic && inst.mesh >= 0 && inst.mesh < int(scene.meshes.size()) &&
         scene.meshes[inst.mesh].triangleCount() > 0;
}

// Drops meshes no instance references and renumbers Instance::mesh.
void dropUnusedMeshes(Scene& scene) {
  std::vector<int> remap(scene.meshes.size(), -1);
  for (const Instance& inst : scene.instances)
    if (inst.mesh >= 0 && inst.mesh < int(scene.meshes.size())) remap[inst.mesh] = 0;
  std::vector<Mesh> kept;
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    if (remap[m] < 0) continue;
    remap[m] = int(kept.size());
    kept.push_back(std::move(scene.meshes[m]));
  }
  scene.meshes = std::move(kept);
  for (Instance& inst : scene.instances)
    if (inst.mesh >= 0 && inst.mesh < int(remap.size())) inst.mesh = remap[inst.mesh];
}

// Where one instance's charts begin in the flat list of PackCharts, and the scale from chart
// units to texels.
struct InstancePack {
  int instance = -1;
  int job = -1;
  size_t firstChart = 0;        // index of its first chart in the flat chart list
  double texelsPerChartUnit = 0.0;
};

// Packs groups of instances so that each instance's charts land in one atlas, since an instance
// has a single LightmapLocation. The whole set is tried first; a group whose charts spill over
// several atlases is halved until every group fits one atlas.
Status packPerInstanceAtlas(const std::vector<InstancePack>& instances,
                            const std::vector<PackChart>& charts, size_t chartCount,
                            const std::vector<size_t>& chartEnd, const PackOptions& options,
                            const Scene& scene, PackResult* out) {
  // chartEnd[k] = one past the last chart of instances[k].
  auto packRange = [&](size_t first, size_t last, PackResult* result) {
    size_t begin = instances[first].firstChart, end = chartEnd[last - 1];
    std::vector<PackChart> subset(charts.begin() + begin, charts.begin() + end);
    *result = packCharts(subset, options);
  };
  struct Range {
    size_t first, last;
  };
  std::vector<Range> pending{{0, instances.size()}};
  out->atlasSizes.clear();
  out->placements.assign(chartCount, ChartPlacement{});
  while (!pending.empty()) {
    if (options.cancelled && options.cancelled()) return Status::error("cancelled");
    Range r = pending.front();
    pending.erase(pending.begin());
    PackResult result;
    packRange(r.first, r.last, &result);
    if (options.cancelled && options.cancelled()) return Status::error("cancelled");
    size_t begin = instances[r.first].firstChart;
    bool oneAtlasEach = true;
    for (size_t k = r.first; k < r.last && oneAtlasEach; ++k) {
      int atlas = -2;
      for (size_t c = instances[k].firstChart; c < chartEnd[k]; ++c) {
        int a = result.placements[c - begin].atlas;
        if (a < 0) {
          const Instance& inst = scene.instances[instances[k].instance];
          return Status::error(format(
              "%s: instance '%s' has a chart that does not fit in a %d texel atlas; lower "
              "--texels-per-unit or its lightmapScale",
              sceneName(scene).c_str(), inst.name.c_str(), options.maxAtlasSize));
        }
        if (atlas == -2) atlas = a;
        if (a != atlas) oneAtlasEach = false;
      }
    }
    if (!oneAtlasEach && r.last - r.first > 1) {
      size_t mid = (r.first + r.last) / 2;
      // Keep the order of ranges so atlas numbering follows instance order.
      pending.insert(pending.begin(), {{r.first, mid}, {mid, r.last}});
      continue;
    }
    if (!oneAtlasEach) {
      const Instance& inst = scene.instances[instances[r.first].instance];
      return Status::error(format(
          "%s: instance '%s' needs more than one %d texel atlas; lower --texels-per-unit or its "
          "lightmapScale",
          sceneName(scene).c_str(), inst.name.c_str(), options.maxAtlasSize));
    }
    int atlasBase = int(out->atlasSizes.size());
    out->atlasSizes.insert(out->atlasSizes.end(), result.atlasSizes.begin(),
                           result.atlasSizes.end());
    for (size_t c = begin; c < chartEnd[r.last - 1]; ++c) {
      ChartPlacement p = result.placements[c - begin];
      p.atlas += atlasBase;
      out->placements[c] = p;
    }
  }
  return Status::ok();
}

Result<UnwrapResult> generate(Scene& scene, const UnwrapOptions& options, Progress& progress) {
  UnwrapResult result;
  const PackOptions& pack = options.pack;

  // Jobs: one per mesh used by a similarity-transformed static instance, one per other static
  // instance (charted on its world geometry).
  struct Job {
    int mesh = -1;
    std::unique_ptr<Mesh> world;  // set for non-similarity instances
    MeshCharts charts;
    size_t triangles = 0;
  };
  std::vector<Job> jobs;
  std::vector<int> jobOfMesh(scene.meshes.size(), -1);
  std::vector<InstancePack> packs;
  size_t distorted = 0;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    Instance& inst = scene.instances[i];
    if (!staticWithGeometry(scene, inst)) continue;
    if (!(inst.lightmapScale > 0.0f) || !std::isfinite(inst.lightmapScale)) {
      result.warnings.push_back(format("instance '%s': lightmapScale %g is not positive; using 1",
                                       inst.name.c_str(), double(inst.lightmapScale)));
      inst.lightmapScale = 1.0f;
    }
    InstancePack ip;
    ip.instance = int(i);
    double scale = 1.0;
    if (similarityScale(inst.transform, &scale)) {
      if (jobOfMesh[inst.mesh] < 0) {
        jobOfMesh[inst.mesh] = int(jobs.size());
        Job job;
        job.mesh = inst.mesh;
        job.triangles = scene.meshes[inst.mesh].triangleCount();
        jobs.push_back(std::move(job));
      }
      ip.job = jobOfMesh[inst.mesh];
    } else {
      Job job;
      job.mesh = inst.mesh;
      job.world = std::make_unique<Mesh>(worldCopy(scene.meshes[inst.mesh], inst.transform));
      job.triangles = job.world->triangleCount();
      ip.job = int(jobs.size());
      jobs.push_back(std::move(job));
      scale = 1.0;  // already in world units
      ++distorted;
    }
    ip.texelsPerChartUnit = double(pack.texelsPerUnit) * double(inst.lightmapScale) * scale;
    packs.push_back(ip);
  }
  if (distorted > 0)
    result.warnings.push_back(format(
        "%zu instance(s) with non-uniform scale or shear were charted on their own world "
        "geometry", distorted));

  // Stage 1: charts, biggest meshes first so the last thread is not left with a giant.
  auto t0 = Clock::now();
  size_t totalTriangles = 0;
  for (const Job& j : jobs) totalTriangles += j.triangles;
  std::vector<size_t> order(jobs.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return jobs[a].triangles > jobs[b].triangles; });
  progress.begin(stageStep(Stage::Uv, "charts"), totalTriangles);
  parallelFor(
      order.size(),
      [&](size_t k) {
        if (progress.cancelled()) return;
        Job& job = jobs[order[k]];
        const Mesh& mesh = job.world ? *job.world : scene.meshes[job.mesh];
        job.charts = computeCharts(mesh, options.charts);
        progress.advance(job.triangles);
      },
      1);
  progress.end();
  result.timings.charts = secondsSince(t0);
  if (progress.cancelled()) return Status::error("cancelled");

  // Stage 2: one packing over every instance's copy of its charts, in instance order.
  t0 = Clock::now();
  std::vector<PackChart> charts;
  std::vector<size_t> chartEnd(packs.size());
  std::vector<std::vector<int>> chartSlots(packs.size());
  for (size_t k = 0; k < packs.size(); ++k) {
    InstancePack& ip = packs[k];
    const MeshCharts& mc = jobs[ip.job].charts;
    ip.firstChart = charts.size();
    const float s = float(ip.texelsPerChartUnit);
    chartSlots[k].assign(mc.charts.size(), -1);
    for (size_t c = 0; c < mc.charts.size(); ++c) {
      const Chart& chart = mc.charts[c];
      if (chart.triangles.empty()) continue;
      AG_CHECK(chart.primitive >= 0 && chart.primitive < int(mc.primitives.size()),
               "chart primitive out of range");
      const ChartedPrimitive& cp = mc.primitives[chart.primitive];
      PackChart pc;
      pc.triangles.reserve(chart.triangles.size() * 3);
      for (uint32_t t : chart.triangles)
        for (int v = 0; v < 3; ++v) pc.triangles.push_back(cp.chartUv[cp.indices[3 * t + v]] * s);
      chartSlots[k][c] = int(charts.size());
      charts.push_back(std::move(pc));
    }
    chartEnd[k] = charts.size();
  }
  progress.begin(stageStep(Stage::Uv, "packing"), 1);
  PackResult packed;
  if (!packs.empty()) {
    PackOptions cancellable = pack;
    cancellable.cancelled = [&progress]() { return progress.cancelled(); };
    Status st =
        packPerInstanceAtlas(packs, charts, charts.size(), chartEnd, cancellable, scene, &packed);
    if (progress.cancelled()) return Status::error("cancelled");
    if (!st) return st;
  }
  progress.advance(1);
  progress.end();
  result.timings.pack = secondsSince(t0);
  if (progress.cancelled()) return Status::error("cancelled");

  // Stage 3: a mesh of its own for every static instance, vertices split along chart seams.
  t0 = Clock::now();
  std::vector<Mesh> added(packs.size());
  parallelFor(
      packs.size(),
      [&](size_t k) {
        const InstancePack& ip = packs[k];
        const Instance& inst = scene.instances[ip.instance];
        const Mesh& source = scene.meshes[inst.mesh];
        const MeshCharts& mc = jobs[ip.job].charts;
        AG_CHECK(mc.primitives.size() == source.primitives.size(),
                 "computeCharts returned a different primitive count");
        const float s = float(ip.texelsPerChartUnit);
        Mesh& mesh = added[k];
        mesh.name = source.name;
        mesh.primitives.resize(source.primitives.size());
        for (size_t p = 0; p < source.primitives.size(); ++p) {
          const Primitive& src = source.primitives[p];
          const ChartedPrimitive& cp = mc.primitives[p];
          Primitive& dst = mesh.primitives[p];
          dst.material = src.material;
          dst.indices = cp.indices;
          const size_t n = cp.vertexRemap.size();
          dst.positions.resize(n);
          dst.normals.resize(src.normals.empty() ? 0 : n);
          dst.uv0.resize(src.uv0.empty() ? 0 : n);
          dst.uv1.resize(n);
          for (size_t v = 0; v < n; ++v) {
            uint32_t o = cp.vertexRemap[v];
            AG_CHECK(o < src.positions.size(), "vertexRemap out of range");
            dst.positions[v] = src.positions[o];
            if (!dst.normals.empty()) dst.normals[v] = src.normals[o];
            if (!dst.uv0.empty()) dst.uv0[v] = src.uv0[o];
            uint32_t c = cp.vertexChart[v];
            int slot = c < chartSlots[k].size() ? chartSlots[k][c] : -1;
            if (slot < 0) {
              dst.uv1[v] = glm::vec2(0.0f);
              continue;
            }
            const ChartPlacement& pl = packed.placements[slot];
            glm::vec2 size(packed.atlasSizes[pl.atlas]);
            dst.uv1[v] = (pl.rotation * (cp.chartUv[v] * s) + pl.offset) / size;
          }
        }
      },
      1);
  size_t firstNew = scene.meshes.size();
  for (size_t k = 0; k < packs.size(); ++k) {
    Instance& inst = scene.instances[packs[k].instance];
    int atlas = -1;
    for (size_t c = packs[k].firstChart; c < chartEnd[k] && atlas < 0; ++c)
      atlas = packed.placements[c].atlas;
    inst.mesh = int(firstNew + k);
    if (atlas >= 0)
      inst.lightmap = {atlas, packed.atlasSizes[atlas].x, packed.atlasSizes[atlas].y};
    scene.meshes.push_back(std::move(added[k]));
  }
  dropUnusedMeshes(scene);
  result.timings.apply = secondsSince(t0);

  t0 = Clock::now();
  progress.begin(stageStep(Stage::Uv, "metrics"), 1);
  result.metrics = computeMetrics(scene, pack.padding);
  progress.advance(1);
  progress.end();
  result.timings.metrics = secondsSince(t0);
  return result;
}

// Atlas side for authored UVs: the instance's world area at its texel density, divided by the
// share of the unit square its UVs cover, so texels per metre match generated UVs whether the
// authored layout fills the square or (say, a previous afterglow run) only part of it.
int keepAtlasSide(double worldArea, double uvArea, double texelsPerUnit, int maxAtlasSize) {
  double coverage = std::min(1.0, std::max(uvArea, 1e-6));
  // The small slack keeps float noise from bumping an exact fit up a step.
  double side = std::ceil(std::sqrt(std::max(worldArea, 0.0) / coverage) * texelsPerUnit - 1e-3);
  if (!std::isfinite(side)) side = double(maxAtlasSize);
  int s = int(std::min(side, double(maxAtlasSize)));
  s = (s + 3) / 4 * 4;
  s = std::max(16, std::min(s, std::max(16, maxAtlasSize / 4 * 4)));
  return s;
}

bool uvInRange(glm::vec2 uv) {
  constexpr float kEps = 1e-5f;
  return uv.x >= -kEps && uv.y >= -kEps && uv.x <= 1.0f + kEps && uv.y <= 1.0f + kEps;
}

// A layout recorded by an earlier run (extras.afterglow.lightmap on every static node).
bool hasRecordedLayout(const Scene& scene, const std::vector<int>& statics) {
  if (statics.empty()) return false;
  for (int i : statics) {
    const scenes::LightmapLocation& l = scene.instances[i].lightmap;
    if (l.atlas < 0 || l.width <= 0 || l.height <= 0) return false;
  }
  return true;
}

Result<UnwrapResult> keep(Scene& scene, const UnwrapOptions& options, Progress& progress) {
  UnwrapResult result;
  const std::string file = sceneName(scene);
  const char* hint = "; use --uv generate to make new lightmap UVs";
  auto t0 = Clock::now();
  std::vector<int> statics;
  for (size_t i = 0; i < scene.instances.size(); ++i)
    if (staticWithGeometry(scene, scene.instances[i])) statics.push_back(int(i));

  // Every static primitive must carry TEXCOORD_1 inside [0,1].
  progress.begin(stageStep(Stage::Uv, "checking TEXCOORD_1"), statics.size());
  std::vector<double> worldAreas(statics.size()), uvAreas(statics.size());
  for (size_t k = 0; k < statics.size(); ++k) {
    Instance& inst = scene.instances[statics[k]];
    const Mesh& mesh = scene.meshes[inst.mesh];
    if (!(inst.lightmapScale > 0.0f) || !std::isfinite(inst.lightmapScale)) inst.lightmapScale = 1.0f;
    std::string where = format("%s: instance '%s' mesh '%s'", file.c_str(), inst.name.c_str(),
                               mesh.name.c_str());
    size_t outside = 0;
    double area = 0.0, uvArea = 0.0;
    glm::mat3 linear(inst.transform);
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const Primitive& prim = mesh.primitives[p];
      if (prim.triangleCount() == 0) continue;
      if (prim.uv1.empty())
        return Status::error(format("%s primitive %zu has no TEXCOORD_1%s", where.c_str(), p, hint));
      if (prim.uv1.size() != prim.positions.size())
        return Status::error(format("%s primitive %zu has %zu TEXCOORD_1 values for %zu vertices%s",
                                    where.c_str(), p, prim.uv1.size(), prim.positions.size(), hint));
      for (size_t t = 0; t < prim.triangleCount(); ++t) {
        uint32_t a = prim.indices[3 * t], b = prim.indices[3 * t + 1], c = prim.indices[3 * t + 2];
        if (!uvInRange(prim.uv1[a]) || !uvInRange(prim.uv1[b]) || !uvInRange(prim.uv1[c])) ++outside;
        glm::vec3 e1 = linear * (prim.positions[b] - prim.positions[a]);
        glm::vec3 e2 = linear * (prim.positions[c] - prim.positions[a]);
        area += 0.5 * double(glm::length(glm::cross(e1, e2)));
        glm::dvec2 u1 = glm::dvec2(prim.uv1[b] - prim.uv1[a]);
        glm::dvec2 u2 = glm::dvec2(prim.uv1[c] - prim.uv1[a]);
        uvArea += 0.5 * std::abs(u1.x * u2.y - u1.y * u2.x);
      }
    }
    if (outside > 0)
      return Status::error(format("%s: %zu triangles of TEXCOORD_1 lie outside [0,1]%s",
                                  where.c_str(), outside, hint));
    worldAreas[k] = area;
    uvAreas[k] = uvArea;
    progress.advance(1);
  }
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");

  // A layout an earlier `afterglow uv` recorded (shared atlases) is kept as it is when its charts
  // share no texel; otherwise each static instance gets an atlas of its own.
  bool keepRecorded = false;
  if (hasRecordedLayout(scene, statics)) {
    Metrics recorded = computeMetrics(scene, 0);
    keepRecorded = recorded.overlappingTexels == 0;
    if (!keepRecorded)
      result.warnings.push_back(format(
          "the recorded extras.afterglow.lightmap layout has charts of different instances on %zu "
          "shared texels; each static instance gets an atlas of its own instead",
          recorded.overlappingTexels));
  }

  std::vector<int> sides(statics.size());
  for (size_t k = 0; k < statics.size() && !keepRecorded; ++k) {
    if (progress.cancelled()) return Status::error("cancelled");
    Instance& inst = scene.instances[statics[k]];
    const Mesh& mesh = scene.meshes[inst.mesh];
    const double density = double(options.pack.texelsPerUnit) * inst.lightmapScale;
    int side = keepAtlasSide(worldAreas[k], uvAreas[k], density, options.pack.maxAtlasSize);
    // Overlaps are judged on the instance alone, at the resolution it will be baked at. Authored
    // layouts are often packed tighter than a texel at our density (a small prop's charts a
    // fraction of a texel apart), so the atlas grows until no texel is shared by two charts;
    // only a layout that still overlaps at maxAtlasSize is rejected.
    Scene one;
    one.meshes.push_back(mesh);
    Instance single = inst;
    single.mesh = 0;
    one.instances.push_back(single);
    const int areaSide = side;
    const int maxSide = std::max(16, options.pack.maxAtlasSize / 4 * 4);
    for (;;) {
      one.instances[0].lightmap = {0, side, side};
      Metrics m = computeMetrics(one, 0);
      if (m.overlappingTexels == 0) break;
      if (side >= maxSide)
        return Status::error(format(
            "%s: instance '%s' mesh '%s': TEXCOORD_1 charts overlap on %zu texels of a %dx%d "
            "atlas%s",
            file.c_str(), inst.name.c_str(), mesh.name.c_str(), m.overlappingTexels, side, side,
            hint));
      side = std::min(maxSide, side * 2);
    }
    if (side != areaSide)
      result.warnings.push_back(format(
          "instance '%s': its authored TEXCOORD_1 charts share texels at %dx%d, so its atlas is "
          "%dx%d (%.0f texels per metre instead of %g)",
          inst.name.c_str(), areaSide, areaSide, side, side, density * side / areaSide, density));
    sides[k] = side;
  }
  result.timings.charts = secondsSince(t0);

  // Authored UVs are per object, so without a recorded layout each static instance gets an atlas
  // of its own (Unity's and Bevy's per-object lightmaps); either way it gets a mesh of its own,
  // as in generate mode.
  t0 = Clock::now();
  size_t firstNew = scene.meshes.size();
  for (size_t k = 0; k < statics.size(); ++k) {
    Instance& inst = scene.instances[statics[k]];
    scene.meshes.push_back(scene.meshes[inst.mesh]);
    inst.mesh = int(firstNew + k);
    if (!keepRecorded) inst.lightmap = {int(k), sides[k], sides[k]};
  }
  dropUnusedMeshes(scene);
  result.timings.apply = secondsSince(t0);

  t0 = Clock::now();
  progress.begin(stageStep(Stage::Uv, "metrics"), 1);
  result.metrics = computeMetrics(scene, options.pack.padding);
  progress.advance(1);
  progress.end();
  result.timings.metrics = secondsSince(t0);
  if (result.metrics.paddingViolations > 0)
    result.warnings.push_back(format("authored TEXCOORD_1 leaves %zu texels closer than %d texels "
                                     "to another chart (bilinear filtering may bleed)",
                                     result.metrics.paddingViolations, options.pack.padding));
  return result;
}

}  // namespace

Result<UnwrapResult> unwrap(Scene& scene, const UnwrapOptions& options, Progress& progress) {
  if (!(options.pack.texelsPerUnit > 0.0f) || !std::isfinite(options.pack.texelsPerUnit))
    return Status::error(format("texelsPerUnit must be positive, got %g",
                                double(options.pack.texelsPerUnit)));
  if (options.pack.padding < 0)
    return Status::error(format("padding must not be negative, got %d", options.pack.padding));
  if (options.pack.maxAtlasSize < 16)
    return Status::error(format("maxAtlasSize must be at least 16, got %d",
                                options.pack.maxAtlasSize));
  return options.mode == UvMode::Keep ? keep(scene, options, progress)
                                      : generate(scene, options, progress);
}

float texelsPerUnitFor(const Scene& scene, double texels) {
  double area = 0.0;  // world area of static geometry, × lightmapScale²
  for (const Instance& inst : scene.instances) {
    if (!inst.isStatic || inst.mesh < 0 || size_t(inst.mesh) >= scene.meshes.size()) continue;
    const double scale = double(inst.lightmapScale) * double(inst.lightmapScale);
    scenes::forEachWorldTriangle(scene, inst, [&](size_t, size_t, glm::vec3 fa, glm::vec3 fb,
                                                  glm::vec3 fc) {
      const glm::dvec3 a(fa), b(fb), c(fc);
      const double twice = glm::length(glm::cross(b - a, c - a));
      if (std::isfinite(twice)) area += 0.5 * scale * twice;
    });
  }
  if (!(area > 0.0) || !(texels > 0.0)) return 0.0f;
  return float(std::sqrt(texels / area));
}

Result<float> fitTexelsPerUnit(const Scene& scene, const UnwrapOptions& options, int atlasSize,
                               Progress& progress) {
  if (atlasSize < 16) return Status::error(format("atlas size must be at least 16, got %d", atlasSize));
  if (options.mode != UvMode::Generate)
    return Status::error("fitting an atlas size needs generated UVs (--uv generate)");
  // Fits when one atlas within atlasSize² holds everything.
  auto fits = [&](float texelsPerUnit, bool* ok) -> Status {
    Scene copy = scene;
    UnwrapOptions o = options;
    o.pack.texelsPerUnit = texelsPerUnit;
    o.pack.maxAtlasSize = atlasSize;
    if (progress.cancelled()) return Status::error("cancelled");
    Result<UnwrapResult> r = unwrap(copy, o);
    progress.advance();
    // A chart too big for the atlas fails the unwrap: too many texels per unit.
    *ok = r && r->metrics.atlases.size() == 1;
    return Status::ok();
  };
  // Start from the density that would fill the atlas at a typical 70% utilisation.
  const float guess = texelsPerUnitFor(scene, 0.7 * double(atlasSize) * double(atlasSize));
  if (!(guess > 0.0f)) return Status::error("no static geometry to fit into an atlas");
  float lo = 0.0f, hi = guess;
  bool ok = false;
  progress.begin(stageStep(Stage::Uv, "fitting the atlas"), 16);
  // Grow until it no longer fits, shrink until it does.
  for (int i = 0; i < 20; ++i) {
    if (Status s = fits(hi, &ok); !s) return s;
    if (!ok) break;
    lo = hi;
    hi *= 1.5f;
  }
  if (lo == 0.0f) {
    for (int i = 0; i < 40 && lo == 0.0f; ++i) {
      hi /= 1.5f;
      if (Status s = fits(hi, &ok); !s) return s;
      if (ok) lo = hi, hi *= 1.5f;
    }
    if (lo == 0.0f) return Status::error(format("nothing fits a %d texel atlas", atlasSize));
  }
  while (hi - lo > 0.01f * lo) {
    const float mid = 0.5f * (lo + hi);
    if (Status s = fits(mid, &ok); !s) return s;
    (ok ? lo : hi) = mid;
  }
  progress.end();
  return lo;
}

}  // namespace afterglow::uv
