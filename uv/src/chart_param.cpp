#include "chart_param.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>
#include <Eigen/Sparse>

namespace afterglow::uv::detail {
namespace {

constexpr int kDenseUnknowns = 48;

double signedArea(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return 0.5 * ((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
}

// Orients the map (mirrors it when most triangles come out clockwise), counts flips, scales the
// UVs so the 2D area equals the 3D area and measures the normalised L2 stretch.
void finish(const ChartGeometry& chart, ChartParam& param) {
  const auto& p = chart.positions;
  const auto& t = chart.triangles;
  double positive = 0.0, negative = 0.0;
  for (size_t i = 0; i < t.size(); i += 3) {
    double a = signedArea(param.uv[t[i]], param.uv[t[i + 1]], param.uv[t[i + 2]]);
    (a > 0.0 ? positive : negative) += std::abs(a);
  }
  if (negative > positive)
    for (auto& q : param.uv) q.x = -q.x;
  double area3d = 0.0, area2d = 0.0, stretchSum = 0.0;
  int flipped = 0;
  for (size_t i = 0; i < t.size(); i += 3) {
    glm::dvec3 p0 = p[t[i]], p1 = p[t[i + 1]], p2 = p[t[i + 2]];
    glm::dvec2 q0 = param.uv[t[i]], q1 = param.uv[t[i + 1]], q2 = param.uv[t[i + 2]];
    double a3 = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    double a2 = signedArea(q0, q1, q2);
    area3d += a3;
    area2d += std::abs(a2);
    // A vanishing UV area on a real triangle is as bad as a flip: nothing is left to texel.
    if (!(a2 > 1e-14 * std::max(a3, 1e-30))) {
      ++flipped;
      continue;
    }
    stretchSum += a3 * triangleStretchSquared(p0, p1, p2, q0, q1, q2);
  }
  param.area3d = area3d;
  param.flipped = flipped;
  if (area2d > 0.0 && area3d > 0.0) {
    double scale = std::sqrt(area3d / area2d);
    glm::dvec2 lo(std::numeric_limits<double>::max());
    for (const auto& q : param.uv) lo = glm::min(lo, q);
    for (auto& q : param.uv) q = (q - lo) * scale;
    param.stretch = flipped ? std::numeric_limits<double>::infinity()
                            : std::sqrt(stretchSum / area3d * (area2d / area3d));
  } else {
    param.stretch = area3d > 0.0 ? std::numeric_limits<double>::infinity() : 1.0;
  }
}

}  // namespace

double triangleStretchSquared(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                              glm::dvec2 q0, glm::dvec2 q1, glm::dvec2 q2) {
  double a2 = 2.0 * signedArea(q0, q1, q2);
  glm::dvec3 ss = (p0 * (q1.y - q2.y) + p1 * (q2.y - q0.y) + p2 * (q0.y - q1.y)) / a2;
  glm::dvec3 st = (p0 * (q2.x - q1.x) + p1 * (q0.x - q2.x) + p2 * (q1.x - q0.x)) / a2;
  return 0.5 * (glm::dot(ss, ss) + glm::dot(st, st));
}

ChartParam projectPlanar(const ChartGeometry& chart, glm::dvec3 normal) {
  glm::dvec3 n = glm::normalize(normal);
  glm::dvec3 helper = std::abs(n.x) < 0.6 ? glm::dvec3(1, 0, 0)
                      : std::abs(n.y) < 0.6 ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1);
  glm::dvec3 tangent = glm::normalize(glm::cross(helper, n));
  glm::dvec3 bitangent = glm::cross(n, tangent);
  std::vector<glm::dvec2> uv(chart.positions.size());
  for (size_t i = 0; i < chart.positions.size(); ++i)
    uv[i] = {glm::dot(chart.positions[i], tangent), glm::dot(chart.positions[i], bitangent)};
  ChartParam param = evaluate(chart, std::move(uv));
  param.planar = true;
  return param;
}


bool lscmSolve(const std::vector<glm::dvec3>& p, const std::vector<uint32_t>& t,
               const std::vector<uint8_t>& pinned, std::vector<glm::dvec2>& uv) {
  const int n = static_cast<int>(p.size());
  std::vector<int> column(n, -1);
  int freeCount = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    uint32_t v = t[i];
    if (!pinned[v] && column[v] < 0) column[v] = freeCount++;
  }
  if (freeCount == 0) return true;
  const int unknowns = 2 * freeCount;

  // The normal equations (A^T A) x = A^T b are assembled per triangle: each triangle adds two
  // Cauchy-Riemann residual rows over its six unknowns.
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(t.size() / 3 * 36);
  Eigen::VectorXd atb = Eigen::VectorXd::Zero(unknowns);
  for (size_t i = 0; i < t.size(); i += 3) {
    glm::dvec3 p0 = p[t[i]], p1 = p[t[i + 1]], p2 = p[t[i + 2]];
    glm::dvec3 e1 = p1 - p0, e2 = p2 - p0;
    double len1 = glm::length(e1);
    glm::dvec3 nrm = glm::cross(e1, e2);
    double area = 0.5 * glm::length(nrm);
    if (!(len1 > 0.0) || !(area > 0.0)) continue;
    glm::dvec3 x = e1 / len1;
    glm::dvec3 y = glm::normalize(glm::cross(nrm, x));
    glm::dvec2 q[3] = {{0.0, 0.0}, {len1, 0.0}, {glm::dot(e2, x), glm::dot(e2, y)}};
    double w = 1.0 / (2.0 * std::sqrt(area));  // sqrt(area) / (2 area)
    // Row 0: u_x - v_y, row 1: u_y + v_x; unknown 2j is u_j, 2j+1 is v_j.
    double row[2][6];
    for (int j = 0; j < 3; ++j) {
      glm::dvec2 d = q[(j + 2) % 3] - q[(j + 1) % 3];
      double gx = -d.y * w, gy = d.x * w;
      row[0][2 * j] = gx;
      row[0][2 * j + 1] = -gy;
      row[1][2 * j] = gy;
      row[1][2 * j + 1] = gx;
    }
    int col[6];
    double b[2] = {0.0, 0.0};
    for (int j = 0; j < 3; ++j) {
      int v = static_cast<int>(t[i + j]);
      col[2 * j] = column[v] < 0 ? -1 : 2 * column[v];
      col[2 * j + 1] = column[v] < 0 ? -1 : 2 * column[v] + 1;
      if (column[v] < 0)
        for (int r = 0; r < 2; ++r) b[r] -= row[r][2 * j] * uv[v].x + row[r][2 * j + 1] * uv[v].y;
    }
    for (int a = 0; a < 6; ++a) {
      if (col[a] < 0) continue;
      atb[col[a]] += row[0][a] * b[0] + row[1][a] * b[1];
      for (int c = 0; c < 6; ++c)
        if (col[c] >= 0)
          triplets.emplace_back(col[a], col[c], row[0][a] * row[0][c] + row[1][a] * row[1][c]);
    }
  }
  Eigen::VectorXd x;
  if (unknowns <= kDenseUnknowns) {
    // Small systems (most merge attempts): a dense factorisation beats the sparse set-up.
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(unknowns, unknowns);
    for (const auto& t : triplets) normal(t.row(), t.col()) += t.value();
    Eigen::LDLT<Eigen::MatrixXd> solver(normal);
    if (solver.info() != Eigen::Success || !solver.isPositive()) return false;
    x = solver.solve(atb);
  } else {
    Eigen::SparseMatrix<double> normal(unknowns, unknowns);
    normal.setFromTriplets(triplets.begin(), triplets.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
    if (solver.info() != Eigen::Success) return false;
    x = solver.solve(atb);
    if (solver.info() != Eigen::Success) return false;
  }
  if (!x.allFinite()) return false;
  for (int i = 0; i < n; ++i)
    if (column[i] >= 0) uv[i] = {x[2 * column[i]], x[2 * column[i] + 1]};
  return true;
}

ChartParam solveLscm(const ChartGeometry& chart) {
  const auto& p = chart.positions;
  const int n = static_cast<int>(p.size());
  std::vector<glm::dvec2> uv(p.size(), glm::dvec2(0.0));
  // Pins: the extreme vertices along the longest bounding-box axis, placed at their distance so
  // a developable chart unrolls at scale 1.
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const auto& q : p) { lo = glm::min(lo, q); hi = glm::max(hi, q); }
  glm::dvec3 ext = hi - lo;
  int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
  int pinA = 0, pinB = 0;
  for (int i = 1; i < n; ++i) {
    if (p[i][axis] < p[pinA][axis]) pinA = i;
    if (p[i][axis] > p[pinB][axis]) pinB = i;
  }
  std::vector<uint8_t> pinned(p.size(), 0);
  pinned[pinA] = pinned[pinB] = 1;
  uv[pinB] = {glm::length(p[pinB] - p[pinA]), 0.0};
  if (pinA == pinB || !lscmSolve(p, chart.triangles, pinned, uv)) {
    ChartParam failed;
    failed.uv = std::move(uv);
    failed.flipped = static_cast<int>(chart.triangles.size() / 3);
    failed.stretch = std::numeric_limits<double>::infinity();
    return failed;
  }
  return evaluate(chart, std::move(uv));
}

ChartParam evaluate(const ChartGeometry& chart, std::vector<glm::dvec2> uv) {
  ChartParam param;
  param.uv = std::move(uv);
  finish(chart, param);
  return param;
}

bool boundaryCrosses(const std::vector<glm::dvec2>& uv,
                     const std::vector<std::pair<uint32_t, uint32_t>>& segments) {
  const size_t count = segments.size();
  if (count < 4) return false;
  glm::dvec2 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const auto& [a, b] : segments) {
    lo = glm::min(lo, glm::min(uv[a], uv[b]));
    hi = glm::max(hi, glm::max(uv[a], uv[b]));
  }
  glm::dvec2 size = hi - lo;
  const double eps = 1e-10 * glm::dot(size, size);
  auto orient = [](glm::dvec2 o, glm::dvec2 p, glm::dvec2 q) {
    return (p.x - o.x) * (q.y - o.y) - (p.y - o.y) * (q.x - o.x);
  };
  auto cross = [&](const std::pair<uint32_t, uint32_t>& s, const std::pair<uint32_t, uint32_t>& t) {
    if (s.first == t.first || s.first == t.second || s.second == t.first || s.second == t.second)
      return false;
    glm::dvec2 a = uv[s.first], b = uv[s.second], c = uv[t.first], d = uv[t.second];
    double d1 = orient(c, d, a), d2 = orient(c, d, b);
    if (!((d1 > eps && d2 < -eps) || (d1 < -eps && d2 > eps))) return false;
    double d3 = orient(a, b, c), d4 = orient(a, b, d);
    return (d3 > eps && d4 < -eps) || (d3 < -eps && d4 > eps);
  };
  if (count <= 48) {
    for (size_t i = 0; i < count; ++i)
      for (size_t j = i + 1; j < count; ++j)
        if (cross(segments[i], segments[j])) return true;
    return false;
  }
  // Uniform grid of about one segment per cell; each segment is tested against the earlier
  // segments in the cells its bounding box covers.
  const int cells = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(count))));
  glm::dvec2 cellSize = glm::max(size / double(cells), glm::dvec2(1e-300));
  std::vector<std::vector<uint32_t>> grid(size_t(cells) * size_t(cells));
  auto cellOf = [&](double v, double origin, double extent) {
    return std::clamp(static_cast<int>((v - origin) / extent), 0, cells - 1);
  };
  for (size_t i = 0; i < count; ++i) {
    glm::dvec2 a = uv[segments[i].first], b = uv[segments[i].second];
    glm::dvec2 mn = glm::min(a, b), mx = glm::max(a, b);
    int x0 = cellOf(mn.x, lo.x, cellSize.x), x1 = cellOf(mx.x, lo.x, cellSize.x);
    int y0 = cellOf(mn.y, lo.y, cellSize.y), y1 = cellOf(mx.y, lo.y, cellSize.y);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        auto& cell = grid[size_t(y) * cells + x];
        for (uint32_t j : cell)
          if (cross(segments[i], segments[j])) return true;
        cell.push_back(static_cast<uint32_t>(i));
      }
  }
  return false;
}

}  // namespace afterglow::uv::detail
