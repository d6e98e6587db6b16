// Two resolutions: where each lightmap texel reads its bounced light in the indirect grid.
#include <algorithm>
#include <cmath>

#include "afterglow/baker/texels.h"
#include "afterglow/core/parallel.h"
#include "afterglow/core/stages.h"
#include "afterglow/trace/raytracer.h"
#include "precompute/indirect_grid.h"

namespace afterglow::baker {

namespace {

// Lightmap pixel point `fine` mapped to the indirect atlas through the chart of `triangle`
// (of instance `inst`'s primitive `primitive`): a chart is only turned and scaled between the
// two atlases (uv/indirect.h), so one edge fixes the map, as a complex multiplication: the
// triangle's longest, which a sliver has too (a sliver's barycentrics would not be worth much).
bool throughTriangle(const scenes::Scene& scene, uint32_t inst, uint32_t primitive,
                     uint32_t triangle, glm::dvec2 fine, glm::dvec2& out) {
  const scenes::Instance& instance = scene.instances[inst];
  const scenes::Primitive& prim = scene.meshes[size_t(instance.mesh)].primitives[primitive];
  const size_t first = size_t(triangle) * 3;
  if (prim.uv1.size() != prim.positions.size() || prim.indirectUv.size() != prim.positions.size() ||
      first + 2 >= prim.indices.size() || instance.indirectLightmap.width <= 0)
    return false;
  const glm::dvec2 fineSize(instance.lightmap.width, instance.lightmap.height);
  const glm::dvec2 coarse(instance.indirectLightmap.width, instance.indirectLightmap.height);
  glm::dvec2 a[3], b[3];
  for (int k = 0; k < 3; ++k) {
    const uint32_t v = prim.indices[first + size_t(k)];
    a[k] = glm::dvec2(prim.uv1[v]) * fineSize;
    b[k] = glm::dvec2(prim.indirectUv[v]) * coarse;
  }
  int i = 0;
  double longest = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double l = glm::length(a[(k + 1) % 3] - a[k]);
    if (l > longest) longest = l, i = k;
  }
  if (!(longest > 1e-9)) return false;
  const int j = (i + 1) % 3;
  const glm::dvec2 from = a[j] - a[i], to = b[j] - b[i];
  const double norm = glm::dot(from, from);
  const glm::dvec2 w((to.x * from.x + to.y * from.y) / norm,
                     (to.y * from.x - to.x * from.y) / norm);
  const glm::dvec2 z = fine - a[i];
  out = b[i] + glm::dvec2(w.x * z.x - w.y * z.y, w.x * z.y + w.y * z.x);
  return std::isfinite(out.x) && std::isfinite(out.y);
}

}  // namespace

bool indirectPoint(const scenes::Scene& scene, const TexelSet& texels, uint32_t t,
                   glm::dvec2& out) {
  return throughTriangle(scene, texels.instance[t], texels.primitive[t], texels.triangle[t],
                         glm::dvec2(texels.pixel[t]) + 0.5, out);
}

uint32_t gridTexel(const scenes::Scene& scene, const TexelSet& lightmap, uint32_t t,
                   glm::dvec2 point, const TexelSet& indirect, int x, int y) {
  const scenes::LightmapLocation& where =
      scene.instances[lightmap.instance[t]].indirectLightmap;
  if (where.atlas < 0 || size_t(where.atlas) >= indirect.atlases.size()) return runtime::kNoTexel;
  const runtime::AtlasLayout& layout = indirect.atlases[size_t(where.atlas)];
  if (x < 0 || y < 0 || x >= layout.width || y >= layout.height) return runtime::kNoTexel;
  const uint32_t o = layout.texelOfPixel[size_t(y) * size_t(layout.width) + size_t(x)];
  if (o == runtime::kNoTexel || !indirect.valid[o] || indirect.instance[o] != lightmap.instance[t])
    return runtime::kNoTexel;
  // Of t's chart (which may span primitives): t's point maps alike through the grid texel's
  // triangle. A chart packed beside t's in the grid atlas (one padding texel apart) maps it
  // elsewhere; its light would come from wherever that chart lies in the level (on Sponza at
  // 16 texels/m, 9,719 lightmap texels read a grid texel over 5 grid texels away from them).
  glm::dvec2 via;
  if ((indirect.triangle[o] != lightmap.triangle[t] || indirect.primitive[o] != lightmap.primitive[t]) &&
      (!throughTriangle(scene, lightmap.instance[t], indirect.primitive[o], indirect.triangle[o],
                        glm::dvec2(lightmap.pixel[t]) + 0.5, via) ||
       glm::length(via - point) > kSameChart))
    return runtime::kNoTexel;
  return o;
}

namespace {

// The corners of one lightmap texel: grid texels around its point, and whether its sample sees
// theirs (computed once each: neighbouring squares share them).
class CornerSearch {
 public:
  CornerSearch(const scenes::Scene& scene, const trace::RayTracer& tracer,
               const TexelSet& lightmap, const TexelSet& indirect, uint32_t t, int x0, int y0)
      : scene_(scene), tracer_(tracer), lightmap_(lightmap), indirect_(indirect), t_(t),
        x0_(x0 - 1), y0_(y0 - 1) {
    indirectPoint(scene, lightmap, t, point_);
  }

  // Bits of square (x, y)'s corners k = (k & 1, k >> 1) that are grid texels of t's instance,
  // and of those whose samples t's sample sees.
  void square(int x, int y, uint8_t& ours, uint8_t& seen) {
    ours = seen = 0;
    for (int k = 0; k < 4; ++k) {
      const Pixel& p = pixel(x + (k & 1), y + (k >> 1));
      if (p.texel == runtime::kNoTexel) continue;
      ours |= uint8_t(1u << k);
      if (p.seen) seen |= uint8_t(1u << k);
    }
  }

 private:
  struct Pixel {
    bool known = false;
    bool seen = false;
    uint32_t texel = runtime::kNoTexel;
  };
  const Pixel& pixel(int x, int y) {
    Pixel& p = cache_[size_t(y - y0_) * 4 + size_t(x - x0_)];
    if (p.known) return p;
    p.known = true;
    p.texel = gridTexel(scene_, lightmap_, t_, point_, indirect_, x, y);
    if (p.texel == runtime::kNoTexel) return p;
    // No bounced light through a wall standing on the chart between the two samples.
    const glm::vec3 d = indirect_.position[p.texel] - lightmap_.position[t_];
    const float length = glm::length(d);
    if (!(length > 0.0f)) {
      p.seen = true;
      return p;
    }
    trace::Ray ray;
    ray.origin = lightmap_.position[t_];
    ray.direction = d / length;
    ray.tfar = 0.99f * length;
    ray.mask = trace::kMaskShadowCasters;
    p.seen = !tracer_.occluded(ray);
    return p;
  }
  const scenes::Scene& scene_;
  const trace::RayTracer& tracer_;
  const TexelSet& lightmap_;
  const TexelSet& indirect_;
  uint32_t t_;
  glm::dvec2 point_;  // t's point in the indirect atlas
  int x0_, y0_;      // the 4 × 4 pixels around the point's own square
  Pixel cache_[16];
};

// How far (grid texels) a texel whose 3 × 3 squares have no grid texel of its own looks.
constexpr int kFarCorner = 3;

// The squares tried when a point's own has no usable corner, nearest first.
constexpr int kSquares[9][2] = {{0, 0},  {-1, 0}, {1, 0},  {0, -1}, {0, 1},
                                {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};

// The valid grid texels by where they lie in the level: a texel whose own chart has no grid
// texel to read (a chart the grid found wholly buried, a moulding thinner than a grid texel)
// reads the nearest one around it that faces its way and that it sees, whatever chart it is
// of, rather than staying black.
class WorldGrid {
 public:
  explicit WorldGrid(const TexelSet& indirect) : indirect_(indirect) {
    std::vector<float> edges;
    for (uint32_t o = 0; o < indirect.size(); ++o)
      if (indirect.valid[o]) edges.push_back(indirect.edge[o]);
    if (edges.empty()) return;
    std::nth_element(edges.begin(), edges.begin() + long(edges.size() / 2), edges.end());
    cell_ = 2.0f * edges[edges.size() / 2];
    for (uint32_t o = 0; o < indirect.size(); ++o)
      if (indirect.valid[o]) cells_.push_back({key(cellOf(indirect.position[o])), o});
    std::sort(cells_.begin(), cells_.end());
  }

  // The nearest valid grid texel within kReach cells (4 grid texels) of lightmap texel t's
  // sample, facing its side and in its sight, or kNoTexel.
  uint32_t nearest(const trace::RayTracer& tracer, const TexelSet& lightmap, uint32_t t) const {
    if (cells_.empty()) return runtime::kNoTexel;
    const glm::vec3 from = lightmap.position[t];
    const glm::ivec3 c = cellOf(from);
    std::vector<std::pair<float, uint32_t>> found;
    for (int dz = -kReach; dz <= kReach; ++dz)
      for (int dy = -kReach; dy <= kReach; ++dy)
        for (int dx = -kReach; dx <= kReach; ++dx) {
          const uint64_t k = key(c + glm::ivec3(dx, dy, dz));
          auto it = std::lower_bound(cells_.begin(), cells_.end(), std::make_pair(k, uint32_t(0)));
          for (; it != cells_.end() && it->first == k; ++it) {
            const uint32_t o = it->second;
            const float d = glm::length(indirect_.position[o] - from);
            if (d <= float(kReach) * cell_ && glm::dot(indirect_.normal[o], lightmap.normal[t]) >= 0.0f)
              found.push_back({d, o});
          }
        }
    std::sort(found.begin(), found.end());
    for (size_t i = 0; i < found.size() && i < 8; ++i) {
      const glm::vec3 d = indirect_.position[found[i].second] - from;
      const float length = glm::length(d);
      trace::Ray ray;
      ray.origin = from;
      ray.direction = length > 0.0f ? d / length : lightmap.normal[t];
      ray.tfar = 0.99f * length;
      ray.mask = trace::kMaskShadowCasters;
      if (!(length > 0.0f) || !tracer.occluded(ray)) return found[i].second;
    }
    return runtime::kNoTexel;
  }

 private:
  static constexpr int kReach = 2;
  glm::ivec3 cellOf(glm::vec3 p) const { return glm::ivec3(glm::floor(p / cell_)); }
  static uint64_t key(glm::ivec3 c) {
    return (uint64_t(uint32_t(c.x) & 0x1fffffu) << 42) | (uint64_t(uint32_t(c.y) & 0x1fffffu) << 21) |
           uint64_t(uint32_t(c.z) & 0x1fffffu);
  }
  const TexelSet& indirect_;
  float cell_ = 0.0f;
  std::vector<std::pair<uint64_t, uint32_t>> cells_;  // (cell, grid texel), sorted
};

}  // namespace

std::vector<runtime::IndirectCorners> indirectCorners(const scenes::Scene& scene,
                                                      const trace::RayTracer& tracer,
                                                      const TexelSet& lightmap,
                                                      const TexelSet& indirect,
                                                      Progress& progress) {
  std::vector<runtime::IndirectCorners> corners(lightmap.size());
  const WorldGrid world(indirect);
  progress.begin(stageStep(Stage::Direct, "indirect corners"), lightmap.size());
  parallelForBlocks(lightmap.size(), [&](size_t begin, size_t end, int) {
    for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
      glm::dvec2 p;
      if (!lightmap.valid[t] || !indirectPoint(scene, lightmap, uint32_t(t), p)) continue;
      const scenes::LightmapLocation& where =
          scene.instances[lightmap.instance[t]].indirectLightmap;
      // p among the texel centres (at half-integers): its square's lower-left centre.
      const glm::dvec2 q = p - 0.5;
      const int bx = int(std::floor(q.x)), by = int(std::floor(q.y));
      CornerSearch search(scene, tracer, lightmap, indirect, uint32_t(t), bx, by);
      // The point's own square when a corner of it is in sight; else the nearest square that
      // has one (a texel beside an object whose grid texels are buried under it), with the
      // point clamped onto it; else the nearest with grid texels at all (a convex surface that
      // bends away between samples).
      int sx = 0, sy = 0;
      uint8_t mask = 0;
      double bestSeen = 1e30, bestOurs = 1e30;
      int oursX = 0, oursY = 0;
      uint8_t oursMask = 0;
      for (const auto& d : kSquares) {
        const int x = bx + d[0], y = by + d[1];
        const glm::dvec2 f = glm::clamp(q - glm::dvec2(x, y), 0.0, 1.0);
        const double distance = glm::length(q - glm::dvec2(x, y) - f);
        if (distance >= bestSeen) continue;
        uint8_t ours, seen;
        search.square(x, y, ours, seen);
        if (seen && distance < bestSeen) bestSeen = distance, sx = x, sy = y, mask = seen;
        if (ours && distance < bestOurs) bestOurs = distance, oursX = x, oursY = y, oursMask = ours;
        if (d[0] == 0 && d[1] == 0 && seen) break;
      }
      if (!mask) sx = oursX, sy = oursY, mask = oursMask;
      glm::dvec2 f = glm::clamp(q - glm::dvec2(sx, sy), 0.0, 1.0);
      if (!mask) {
        // A strip narrower than a grid texel (a moulding) whose grid samples all fell inside
        // what it stands on: the nearest grid texel of its chart a few texels away stands in,
        // alone (the square's first corner, all the weight); else the nearest in the level
        // (WorldGrid).
        double nearest = 1e30;
        for (int y = by - kFarCorner; y <= by + 1 + kFarCorner; ++y)
          for (int x = bx - kFarCorner; x <= bx + 1 + kFarCorner; ++x) {
            const double d = glm::length(q - glm::dvec2(x, y));
            if (d >= nearest ||
                gridTexel(scene, lightmap, uint32_t(t), p, indirect, x, y) == runtime::kNoTexel)
              continue;
            nearest = d, sx = x, sy = y, mask = 1, f = glm::dvec2(0.0);
          }
        if (!mask) {
          const uint32_t o = world.nearest(tracer, lightmap, uint32_t(t));
          if (o != runtime::kNoTexel && indirect.atlas[o] == uint32_t(where.atlas))
            sx = indirect.pixel[o].x, sy = indirect.pixel[o].y, mask = 1, f = glm::dvec2(0.0);
        }
      }
      if (!mask) continue;
      int fx = int(std::lround(f.x * 16.0)), fy = int(std::lround(f.y * 16.0));
      // All the weight on the far column (or row), or the near one outside the atlas: the
      // square one further on, its near corners those, with the same values.
      if (fx == 16 || sx < 0) ++sx, fx = 0, mask = uint8_t((mask >> 1) & 0x5u);
      if (fy == 16 || sy < 0) ++sy, fy = 0, mask = uint8_t((mask >> 2) & 0x3u);
      if (!mask || sx < 0 || sy < 0) continue;
      runtime::IndirectCorners& c = corners[t];
      c.x = uint16_t(sx);
      c.y = uint16_t(sy);
      c.atlas = uint8_t(where.atlas);
      c.fraction = uint8_t(fx | (fy << 4));
      c.mask = mask;
    }
    progress.advance(end - begin);
  }, 1024);
  progress.end();
  return corners;
}

}  // namespace afterglow::baker
