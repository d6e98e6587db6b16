// Conservative rasterisation of one triangle onto texel squares, shared by the packer (which must
// reserve every texel a chart touches) and the metrics (which must see the same footprint).
//
// Texel (x, y) is the square [x, x+1] x [y, y+1]. A triangle covers it when the closed triangle
// meets the open square grown by `grow` texels on each side. For a triangle with area that is
// "overlaps with positive area"; sliver and even collinear triangles still cover every texel their
// segment passes through, so nothing that a sampler might hit is left out.
//
// The packer rasterises exactly (kPackGrow = 0) and the metrics shrink squares by a hair
// (kMetricsGrow): UVs travel through float (rotation * p + offset, / atlas size, * atlas size
// again), which moves a vertex lying exactly on a texel edge by up to ~1e-3 texel at 4096 texels;
// the shrink keeps such a vertex from reading as a touched neighbour texel, so the metrics see
// at most the footprint the packer reserved.
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace afterglow::uv {

constexpr double kPackGrow = 0.0;       // texels
constexpr double kMetricsGrow = -2e-3;  // texels

// Separating-axis test of the closed triangle (a, b, c) against the open square
// (x - grow, x + 1 + grow) x (y - grow, y + 1 + grow).
inline bool triangleTouchesTexel(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c,
                                 int x, int y, double grow) {
  const double x0 = x - grow, x1 = x + 1 + grow, y0 = y - grow, y1 = y + 1 + grow;
  if (std::max({a.x, b.x, c.x}) <= x0 || std::min({a.x, b.x, c.x}) >= x1) return false;
  if (std::max({a.y, b.y, c.y}) <= y0 || std::min({a.y, b.y, c.y}) >= y1) return false;
  const glm::dvec2 centre(0.5 * (x0 + x1), 0.5 * (y0 + y1));
  const double half = 0.5 * (x1 - x0);
  const glm::dvec2 v[3] = {a, b, c};
  for (int i = 0; i < 3; ++i) {
    const glm::dvec2 e = v[(i + 1) % 3] - v[i];
    const glm::dvec2 n(-e.y, e.x);
    if (n.x == 0.0 && n.y == 0.0) continue;  // repeated vertex: no axis
    const double ta = glm::dot(n, a), tb = glm::dot(n, b), tc = glm::dot(n, c);
    const double tmin = std::min({ta, tb, tc}), tmax = std::max({ta, tb, tc});
    const double sc = glm::dot(n, centre), sr = half * (std::abs(n.x) + std::abs(n.y));
    if (tmax <= sc - sr || tmin >= sc + sr) return false;
  }
  return true;
}

// Calls visit(x, y) for every texel in [0, width) x [0, height) the triangle covers.
template <class Visit>
void rasterizeTriangle(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c,
                       double grow, int width, int height, Visit&& visit) {
  const double minX = std::min({a.x, b.x, c.x}), maxX = std::max({a.x, b.x, c.x});
  const double minY = std::min({a.y, b.y, c.y}), maxY = std::max({a.y, b.y, c.y});
  if (!(minX == minX) || !(minY == minY) || !(maxX == maxX) || !(maxY == maxY)) return;  // NaN
  // Texels whose grown square the bounding box overlaps; the test decides the rest.
  const double g = std::abs(grow);
  const int xs = int(std::max(0.0, std::floor(minX - g)));
  const int ys = int(std::max(0.0, std::floor(minY - g)));
  const int xe = int(std::min(double(width - 1), std::ceil(maxX + g) - 1.0));
  const int ye = int(std::min(double(height - 1), std::ceil(maxY + g) - 1.0));
  for (int y = ys; y <= ye; ++y)
    for (int x = xs; x <= xe; ++x)
      if (triangleTouchesTexel(a, b, c, x, y, grow)) visit(x, y);
}

}  // namespace afterglow::uv
