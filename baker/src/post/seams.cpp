#include "post/seams.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <tuple>
#include <utility>

#include "afterglow/core/parallel.h"

namespace afterglow::baker {

namespace {

// Welding tolerance, as a fraction of the instance's bounding-box diagonal: far above float
// noise on vertices an exporter split, far below any real feature.
constexpr float kWeldFraction = 1e-5f;
// Corners whose uv1 differ by less than this (in pixels) are one point of the atlas: the edge
// is not cut there.
constexpr float kSameUvPixels = 1e-3f;
constexpr uint32_t kUnset = 0xffffffffu;

// One triangle corner of an instance.
struct Corner {
  glm::vec3 position;  // world
  glm::vec3 normal;    // world shading normal, unit
  glm::vec2 pixel;     // uv1 × atlas size
};

// An instance's triangles over all its primitives: corners 3t..3t+2 belong to triangle t.
struct Triangles {
  std::vector<Corner> corners;
  std::vector<glm::vec3> faceNormal;  // world, unit; zero for degenerate triangles
};

bool usableTriangle(const scenes::Primitive& prim, size_t t) {
  const size_t n = prim.positions.size();
  return prim.uv1.size() == n && prim.normals.size() == n && prim.indices[3 * t] < n &&
         prim.indices[3 * t + 1] < n && prim.indices[3 * t + 2] < n;
}

Triangles gatherTriangles(const scenes::Mesh& mesh, const glm::mat4& transform,
                          glm::vec2 atlasSize) {
  const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(transform)));
  Triangles out;
  for (const scenes::Primitive& prim : mesh.primitives) {
    for (size_t t = 0; t < prim.triangleCount(); ++t) {
      if (!usableTriangle(prim, t)) continue;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = prim.indices[3 * t + size_t(k)];
        const glm::vec3 n = normalMatrix * prim.normals[v];
        const float length = glm::length(n);
        out.corners.push_back({glm::vec3(transform * glm::vec4(prim.positions[v], 1.0f)),
                               length > 0.0f ? n / length : glm::vec3(0.0f),
                               prim.uv1[v] * atlasSize});
      }
      const Corner* c = &out.corners[out.corners.size() - 3];
      const glm::vec3 n = glm::cross(c[1].position - c[0].position, c[2].position - c[0].position);
      const float length = glm::length(n);
      out.faceNormal.push_back(length > 0.0f ? n / length : glm::vec3(0.0f));
    }
  }
  return out;
}

float boundingDiagonal(const std::vector<Corner>& corners) {
  scenes::Bounds bounds;
  for (const Corner& c : corners) bounds.extend(c.position);
  return glm::length(bounds.size());
}

// A weld id per corner: corners within `tolerance` of an earlier corner take its id. Corners
// are bucketed in cells of 16 tolerances, and a corner looks only at the cells its tolerance
// ball reaches (usually its own), through a sorted list rather than a hash map so that ties
// resolve the same way every run.
std::vector<uint32_t> weldCorners(const std::vector<Corner>& corners, float tolerance) {
  using Cell = std::array<int64_t, 3>;
  const float cellSize = 16.0f * tolerance;
  auto cellOf = [&](glm::vec3 p) {
    return Cell{int64_t(std::floor(p.x / cellSize)), int64_t(std::floor(p.y / cellSize)),
                int64_t(std::floor(p.z / cellSize))};
  };
  std::vector<std::pair<Cell, uint32_t>> byCell(corners.size());
  for (size_t i = 0; i < corners.size(); ++i) byCell[i] = {cellOf(corners[i].position), uint32_t(i)};
  std::sort(byCell.begin(), byCell.end());
  auto cellLess = [](const auto& a, const auto& b) { return a.first < b.first; };

  std::vector<uint32_t> weld(corners.size(), kUnset);
  uint32_t next = 0;
  for (uint32_t i = 0; i < corners.size(); ++i) {
    const glm::vec3 p = corners[i].position;
    const Cell lo = cellOf(p - glm::vec3(tolerance)), hi = cellOf(p + glm::vec3(tolerance));
    uint32_t first = kUnset;  // the lowest earlier corner within tolerance
    for (int64_t x = lo[0]; x <= hi[0]; ++x)
      for (int64_t y = lo[1]; y <= hi[1]; ++y)
        for (int64_t z = lo[2]; z <= hi[2]; ++z) {
          const auto range = std::equal_range(byCell.begin(), byCell.end(),
                                              std::make_pair(Cell{x, y, z}, 0u), cellLess);
          // Within a cell corners are in index order, so the first match is the lowest.
          for (auto it = range.first; it != range.second && it->second < std::min(i, first); ++it)
            if (glm::distance(corners[it->second].position, p) <= tolerance) {
              first = it->second;
              break;
            }
        }
    weld[i] = first == kUnset ? next++ : weld[first];
  }
  return weld;
}

// A triangle edge between two welded points, `lo` < `hi`, with the corners at either end.
struct Edge {
  uint32_t lo, hi;
  uint32_t triangle;
  uint32_t cornerLo, cornerHi;

  bool samePoints(const Edge& o) const { return lo == o.lo && hi == o.hi; }
  bool operator<(const Edge& o) const {
    return std::tie(lo, hi, triangle) < std::tie(o.lo, o.hi, o.triangle);
  }
};

std::vector<Edge> sortedEdges(const std::vector<uint32_t>& weld) {
  std::vector<Edge> edges;
  for (uint32_t t = 0; 3 * size_t(t) < weld.size(); ++t)
    for (uint32_t k = 0; k < 3; ++k) {
      uint32_t a = 3 * t + k, b = 3 * t + (k + 1) % 3;
      if (weld[a] == weld[b]) continue;  // collapsed edge
      if (weld[a] > weld[b]) std::swap(a, b);
      edges.push_back({weld[a], weld[b], t, a, b});
    }
  std::sort(edges.begin(), edges.end());
  return edges;
}

// Whether light runs on smoothly across the edge the two triangles share: both face normals
// and the shading normals at both shared points agree within the angle. A hard edge (a box's
// corner) or a hard shading edge the author split is lit differently on its two sides.
bool smoothAcross(const Triangles& tris, const Edge& a, const Edge& b, float cosMaxAngle) {
  const auto& c = tris.corners;
  return glm::dot(tris.faceNormal[a.triangle], tris.faceNormal[b.triangle]) >= cosMaxAngle &&
         glm::dot(c[a.cornerLo].normal, c[b.cornerLo].normal) >= cosMaxAngle &&
         glm::dot(c[a.cornerHi].normal, c[b.cornerHi].normal) >= cosMaxAngle;
}

// Whether the atlas holds the shared edge twice: the uv1 differ at one end at least.
bool cutInUv(const Triangles& tris, const Edge& a, const Edge& b) {
  const auto& c = tris.corners;
  return glm::distance(c[a.cornerLo].pixel, c[b.cornerLo].pixel) > kSameUvPixels ||
         glm::distance(c[a.cornerHi].pixel, c[b.cornerHi].pixel) > kSameUvPixels;
}

std::vector<Seam> instanceSeams(const scenes::Mesh& mesh, const glm::mat4& transform,
                                glm::vec2 atlasSize, float cosMaxAngle) {
  const Triangles tris = gatherTriangles(mesh, transform, atlasSize);
  const float tolerance = kWeldFraction * boundingDiagonal(tris.corners);
  if (!(tolerance > 0.0f)) return {};  // no extent: nothing to weld or stitch
  const std::vector<Edge> edges = sortedEdges(weldCorners(tris.corners, tolerance));
  std::vector<Seam> seams;
  for (size_t i = 0; i < edges.size();) {
    size_t end = i + 1;
    while (end < edges.size() && edges[end].samePoints(edges[i])) ++end;
    // Exactly two triangles: a manifold edge (a fold of three or more has no "other side").
    if (end - i == 2) {
      const Edge& a = edges[i];
      const Edge& b = edges[i + 1];
      if (a.triangle != b.triangle && cutInUv(tris, a, b) && smoothAcross(tris, a, b, cosMaxAngle)) {
        const auto& c = tris.corners;
        seams.push_back({c[a.cornerLo].pixel, c[a.cornerHi].pixel, c[b.cornerLo].pixel,
                         c[b.cornerHi].pixel});
      }
    }
    i = end;
  }
  return seams;
}

// A pixel's weight in a lookup.
struct Tap {
  uint32_t pixel;
  float weight;
  bool operator<(const Tap& o) const { return pixel < o.pixel; }
};

// The bilinear footprint of an atlas point (pixels), scaled by `sign`: between pixel centres,
// clamped at the atlas edges, as a renderer fetches it (baker/src/render.cpp).
void addFootprint(glm::vec2 point, int width, int height, float sign, std::vector<Tap>& out) {
  const float x = point.x - 0.5f, y = point.y - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const int px = std::clamp(int(fx) + i, 0, width - 1);
      const int py = std::clamp(int(fy) + j, 0, height - 1);
      const float w = (i ? tx : 1.0f - tx) * (j ? ty : 1.0f - ty);
      if (w == 0.0f) continue;  // a point on a pixel row or column does not read past it
      out.push_back({uint32_t(py) * uint32_t(width) + uint32_t(px), sign * w});
    }
}

// Sparse rows, one per seam sample: d_s = a_s − b_s, over atlas pixels or over unknowns.
struct SampleRows {
  std::vector<Tap> taps;
  std::vector<size_t> start{0};  // sample s: taps [start[s], start[s+1])

  size_t size() const { return start.size() - 1; }
};

SampleRows sampleSeams(const std::vector<Seam>& seams, int width, int height) {
  SampleRows out;
  for (const Seam& seam : seams) {
    const float pixels = std::max(glm::distance(seam.a0, seam.a1), glm::distance(seam.b0, seam.b1));
    if (!std::isfinite(pixels)) continue;  // broken uv1: nothing sensible to sample
    // Half a texel apart, at the middles of equal steps: the shared endpoints belong to other
    // seams too and would otherwise count twice.
    const int n = std::max(1, int(std::ceil(2.0f * pixels)));
    for (int i = 0; i < n; ++i) {
      const float t = (float(i) + 0.5f) / float(n);
      addFootprint(glm::mix(seam.a0, seam.a1, t), width, height, 1.0f, out.taps);
      addFootprint(glm::mix(seam.b0, seam.b1, t), width, height, -1.0f, out.taps);
      out.start.push_back(out.taps.size());
    }
  }
  return out;
}

// The unknowns: every pixel a sample reads that holds a mix, ascending.
std::vector<uint32_t> unknownPixels(const SampleRows& samples, const std::vector<uint8_t>& has) {
  std::vector<uint32_t> pixels;
  for (const Tap& tap : samples.taps)
    if (has[tap.pixel]) pixels.push_back(tap.pixel);
  std::sort(pixels.begin(), pixels.end());
  pixels.erase(std::unique(pixels.begin(), pixels.end()), pixels.end());
  return pixels;
}

// The rows over unknown indices, each merged by unknown; pixels that are not unknowns are black
// and add nothing to d_s · x.
SampleRows rowsOverUnknowns(const SampleRows& samples, const std::vector<uint32_t>& pixels) {
  SampleRows out;
  std::vector<Tap> row;
  for (size_t s = 0; s < samples.size(); ++s) {
    row.clear();
    for (size_t k = samples.start[s]; k < samples.start[s + 1]; ++k) {
      const Tap& tap = samples.taps[k];
      const auto it = std::lower_bound(pixels.begin(), pixels.end(), tap.pixel);
      if (it != pixels.end() && *it == tap.pixel)
        row.push_back({uint32_t(it - pixels.begin()), tap.weight});
    }
    std::sort(row.begin(), row.end());
    for (size_t k = 0; k < row.size(); ++k) {
      if (k > 0 && row[k].pixel == row[k - 1].pixel) out.taps.back().weight += row[k].weight;
      else out.taps.push_back(row[k]);
    }
    out.start.push_back(out.taps.size());
  }
  return out;
}

// Minimises Σ_s (d_s·x)² + λ |x − x0|² by Gauss-Seidel on its dual: x = x0 − Σ_s y_s d_s with
// (D Dᵀ + λI) y = D x0, one sample at a time in seam order:
//   Δ = (d_s·x − λ y_s) / (|d_s|² + λ),  y_s += Δ,  x −= Δ d_s.
// The primal sweep (pixel by pixel) first lets each pixel close its samples' whole gap alone,
// overshooting by the inverse of its footprint weight (2× and more) before later sweeps undo
// it; the dual only ever moves x along the rows d_s, so every step is the smallest change that
// closes a sample, and 8 sweeps reach the minimiser. Linear in x0: every quantity is a mix.
std::vector<PixelMix> solveStitch(const SampleRows& rows, const std::vector<PixelMix>& x0,
                                  const PostOptions& options) {
  const float lambda = options.stitchLambda;
  std::vector<PixelMix> x = x0;
  std::vector<PixelMix> y(rows.size());
  std::vector<std::pair<const PixelMix*, float>> parts;
  for (int sweep = 0; sweep < options.stitchIterations; ++sweep) {
    for (size_t s = 0; s < rows.size(); ++s) {
      const auto begin = rows.taps.begin() + ptrdiff_t(rows.start[s]);
      const auto end = rows.taps.begin() + ptrdiff_t(rows.start[s + 1]);
      float norm2 = 0.0f;
      for (auto t = begin; t != end; ++t) norm2 += t->weight * t->weight;
      if (norm2 == 0.0f) continue;  // both sides read the same pixels, or only black ones
      const float scale = 1.0f / (norm2 + lambda);
      parts.clear();
      for (auto t = begin; t != end; ++t) parts.push_back({&x[t->pixel], t->weight * scale});
      parts.push_back({&y[s], -lambda * scale});
      const PixelMix delta = combineMixes(parts, options.stitchMaxMix);
      parts.assign({{&y[s], 1.0f}, {&delta, 1.0f}});
      y[s] = combineMixes(parts, options.stitchMaxMix);
      for (auto t = begin; t != end; ++t) {
        parts.assign({{&x[t->pixel], 1.0f}, {&delta, -t->weight}});
        x[t->pixel] = combineMixes(parts, options.stitchMaxMix);
      }
    }
  }
  return x;
}

// Drops a stitched mix's negative weights, scaling the rest to keep the sum. Where two texel
// grids do not line up the least-squares answer holds small negative weights (down to about
// −0.12), which a shadow edge crossing the seam would turn into negative light; a convex mix
// stays within the light of the texels it draws on, at the price of about half the reduction
// of the step across the seam.
void makeConvex(PixelMix& mix) {
  float total = 0.0f, positive = 0.0f;
  for (const auto& e : mix) total += e.second, positive += std::max(e.second, 0.0f);
  if (!(total > 0.0f)) return mix.clear();  // nothing but cancellation: black
  mix.erase(std::remove_if(mix.begin(), mix.end(), [](const auto& e) { return e.second <= 0.0f; }),
            mix.end());
  for (auto& e : mix) e.second *= total / positive;
}

}  // namespace

std::vector<std::vector<Seam>> findSeams(const scenes::Scene& scene,
                                         const std::vector<runtime::AtlasLayout>& atlases,
                                         float maxAngleDeg) {
  const float cosMaxAngle = std::cos(glm::radians(maxAngleDeg));
  std::vector<std::vector<Seam>> perInstance(scene.instances.size());
  parallelFor(scene.instances.size(), [&](size_t i) {
    const scenes::Instance& inst = scene.instances[i];
    if (!inst.isStatic || inst.mesh < 0 || size_t(inst.mesh) >= scene.meshes.size() ||
        inst.lightmap.atlas < 0 || size_t(inst.lightmap.atlas) >= atlases.size())
      return;
    const runtime::AtlasLayout& layout = atlases[size_t(inst.lightmap.atlas)];
    perInstance[i] = instanceSeams(scene.meshes[size_t(inst.mesh)], inst.transform,
                                   glm::vec2(layout.width, layout.height), cosMaxAngle);
  }, 1);
  std::vector<std::vector<Seam>> perAtlas(atlases.size());
  for (size_t i = 0; i < perInstance.size(); ++i)
    if (!perInstance[i].empty()) {
      std::vector<Seam>& seams = perAtlas[size_t(scene.instances[i].lightmap.atlas)];
      seams.insert(seams.end(), perInstance[i].begin(), perInstance[i].end());
    }
  return perAtlas;
}

void stitchSeams(const std::vector<Seam>& seams, int width, int height,
                 const PostOptions& options, std::vector<PixelMix>& mix,
                 const std::vector<uint8_t>& has, PostStats& stats) {
  if (seams.empty() || width <= 0 || height <= 0) return;
  const SampleRows samples = sampleSeams(seams, width, height);
  const std::vector<uint32_t> pixels = unknownPixels(samples, has);
  std::vector<PixelMix> x0(pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i) x0[i] = mix[pixels[i]];
  std::vector<PixelMix> x = solveStitch(rowsOverUnknowns(samples, pixels), x0, options);
  for (size_t i = 0; i < pixels.size(); ++i) {
    makeConvex(x[i]);
    stats.stitchedEntries += x[i].size();
    mix[pixels[i]] = std::move(x[i]);
  }
  stats.seamEdges += seams.size();
  stats.seamSamples += samples.size();
  stats.stitchedPixels += pixels.size();
}

}  // namespace afterglow::baker
