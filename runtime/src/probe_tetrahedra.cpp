// Light probes' point location: a visibility walk over the tetrahedra in double precision, and
// the closest hull face for points outside the hull.
#include "afterglow/runtime/probe_tetrahedra.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace afterglow::runtime {
namespace {

using glm::dvec3;

// A point is inside a tetrahedron when none of its barycentric coordinates is below −kEpsilon:
// a point a relative 1e-7 of the tetrahedron's size beyond a face counts as on it (the weights
// are then clamped to be non-negative, which moves them by at most about kEpsilon).
constexpr double kEpsilon = 1e-7;

double det3(const dvec3& a, const dvec3& b, const dvec3& c) { return glm::dot(a, glm::cross(b, c)); }

// Six times the signed volume of (a, b, c, d): positive when d lies on the side of the plane abc
// that a right-handed turn a→b→c points to.
double orient(const dvec3& a, const dvec3& b, const dvec3& c, const dvec3& d) {
  return det3(b - a, c - a, d - a);
}

std::array<dvec3, 4> corners(const ProbeTetrahedra& mesh, int t) {
  const glm::ivec4& v = mesh.tetrahedra[size_t(t)];
  return {dvec3(mesh.positions[size_t(v[0])]), dvec3(mesh.positions[size_t(v[1])]),
          dvec3(mesh.positions[size_t(v[2])]), dvec3(mesh.positions[size_t(v[3])])};
}

bool validTetrahedron(const ProbeTetrahedra& mesh, int t) {
  const glm::ivec4& v = mesh.tetrahedra[size_t(t)];
  for (int i = 0; i < 4; ++i)
    if (v[i] < 0 || size_t(v[i]) >= mesh.positions.size()) return false;
  return true;
}

// The barycentric coordinates of p in tetrahedron t (coordinate i belongs to corner i, and is
// zero on the face opposite it). False when t is degenerate (or not positively oriented) or an
// index is out of range: the walk then gives up on it.
bool barycentric(const ProbeTetrahedra& mesh, int t, const dvec3& p, std::array<double, 4>& b) {
  if (!validTetrahedron(mesh, t)) return false;
  const std::array<dvec3, 4> c = corners(mesh, t);
  const double volume = orient(c[0], c[1], c[2], c[3]);
  if (!(volume > 0.0) || !std::isfinite(volume)) return false;
  b[0] = orient(p, c[1], c[2], c[3]) / volume;
  b[1] = orient(c[0], p, c[2], c[3]) / volume;
  b[2] = orient(c[0], c[1], p, c[3]) / volume;
  b[3] = orient(c[0], c[1], c[2], p) / volume;
  return true;
}

int mostNegative(const std::array<double, 4>& b) {
  int worst = 0;
  for (int i = 1; i < 4; ++i)
    if (b[size_t(i)] < b[size_t(worst)]) worst = i;
  return worst;
}

ProbeLocation insideLocation(const ProbeTetrahedra& mesh, int t, const std::array<double, 4>& b) {
  ProbeLocation loc;
  loc.tetrahedron = t;
  loc.probes = mesh.tetrahedra[size_t(t)];
  loc.inside = true;
  double sum = 0.0;
  std::array<double, 4> w{};
  for (size_t i = 0; i < 4; ++i) sum += (w[i] = std::max(b[i], 0.0));
  for (int i = 0; i < 4; ++i) loc.weights[i] = float(w[size_t(i)] / sum);
  return loc;
}

// The closest point to p on triangle abc, as barycentric weights (u, v, w) of a, b, c
// (Ericson, Real-Time Collision Detection, 5.1.5), and its squared distance to p.
std::array<double, 3> closestOnTriangle(const dvec3& p, const dvec3& a, const dvec3& b,
                                        const dvec3& c, double& distance2) {
  std::array<double, 3> uvw;
  const dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  const dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  const dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (d1 <= 0.0 && d2 <= 0.0) {
    uvw = {1.0, 0.0, 0.0};                                        // vertex a
  } else if (d3 >= 0.0 && d4 <= d3) {
    uvw = {0.0, 1.0, 0.0};                                        // vertex b
  } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);                              // edge ab
    uvw = {1.0 - v, v, 0.0};
  } else if (d6 >= 0.0 && d5 <= d6) {
    uvw = {0.0, 0.0, 1.0};                                        // vertex c
  } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);                              // edge ac
    uvw = {1.0 - w, 0.0, w};
  } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));         // edge bc
    uvw = {0.0, 1.0 - w, w};
  } else {
    const double denom = 1.0 / (va + vb + vc);                    // the face's interior
    const double v = vb * denom, w = vc * denom;
    uvw = {1.0 - v - w, v, w};
  }
  const dvec3 q = uvw[0] * a + uvw[1] * b + uvw[2] * c;
  distance2 = glm::dot(p - q, p - q);
  return uvw;
}

// p is outside the hull: the closest point on any hull face. Brute force over every face of
// every tetrahedron with a -1 neighbour, O(tetrahedra) per outside query: fine for the meshes
// and query counts of a bake or a tool, but an engine sampling many outside points per frame
// would want the hull faces in a list of their own or a BVH.
ProbeLocation outsideLocation(const ProbeTetrahedra& mesh, const dvec3& p) {
  ProbeLocation best;
  double bestDistance2 = std::numeric_limits<double>::infinity();
  const int count = int(mesh.tetrahedra.size());
  for (int t = 0; t < count; ++t) {
    if (!validTetrahedron(mesh, t) || size_t(t) >= mesh.neighbours.size()) continue;
    const std::array<dvec3, 4> c = corners(mesh, t);
    for (int opposite = 0; opposite < 4; ++opposite) {
      if (mesh.neighbours[size_t(t)][opposite] != -1) continue;
      int face[3], n = 0;
      for (int i = 0; i < 4; ++i)
        if (i != opposite) face[n++] = i;
      double distance2 = 0.0;
      const std::array<double, 3> uvw =
          closestOnTriangle(p, c[size_t(face[0])], c[size_t(face[1])], c[size_t(face[2])],
                            distance2);
      if (!(distance2 < bestDistance2)) continue;
      bestDistance2 = distance2;
      best.tetrahedron = t;
      best.inside = false;
      best.probes = glm::ivec4(-1);
      best.weights = glm::vec4(0.0f);
      double sum = 0.0;
      for (size_t i = 0; i < 3; ++i) sum += std::max(uvw[i], 0.0);
      for (int i = 0; i < 3; ++i) {
        best.probes[i] = mesh.tetrahedra[size_t(t)][face[i]];
        best.weights[i] = float(std::max(uvw[size_t(i)], 0.0) / sum);
      }
    }
  }
  return best;
}

ProbeLocation nearestProbe(const ProbeTetrahedra& mesh, const dvec3& p) {
  ProbeLocation loc;
  size_t nearest = 0;
  double nearestDistance2 = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const dvec3 d = dvec3(mesh.positions[i]) - p;
    const double distance2 = glm::dot(d, d);
    if (distance2 < nearestDistance2) {
      nearestDistance2 = distance2;
      nearest = i;
    }
  }
  loc.probes = glm::ivec4(int(nearest), -1, -1, -1);
  loc.weights = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
  return loc;
}

}  // namespace

ProbeLocation locateProbe(const ProbeTetrahedra& mesh, glm::vec3 p, int hint) {
  if (mesh.positions.empty()) return ProbeLocation();
  const dvec3 q(p);
  const int count = int(mesh.tetrahedra.size());
  if (count == 0 || !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) {
    if (count == 0) return nearestProbe(mesh, q);
    ProbeLocation loc;  // no point to locate: the first probe of the first tetrahedron
    loc.tetrahedron = 0;
    loc.probes = glm::ivec4(mesh.tetrahedra[0][0], -1, -1, -1);
    loc.weights = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
    return loc;
  }
  const bool hasNeighbours = mesh.neighbours.size() == mesh.tetrahedra.size();

  // The walk: at most one step per tetrahedron, else (a cycle, possible on a mesh that is not
  // Delaunay or on a degenerate one) the brute-force scan below.
  int t = hint >= 0 && hint < count ? hint : 0;
  std::array<double, 4> b{};
  bool walked = false;
  for (int step = 0; step <= count && hasNeighbours; ++step) {
    if (!barycentric(mesh, t, q, b)) break;
    const int worst = mostNegative(b);
    if (b[size_t(worst)] >= -kEpsilon) return insideLocation(mesh, t, b);
    const int next = mesh.neighbours[size_t(t)][worst];
    if (next == -1) {  // beyond a hull face, so (the hull being convex) outside
      walked = true;
      break;
    }
    if (next < 0 || next >= count) break;
    t = next;
  }
  if (!walked) {
    // Brute force: the tetrahedron whose smallest coordinate is the largest.
    int best = -1;
    double bestMin = -std::numeric_limits<double>::infinity();
    std::array<double, 4> bestB{};
    for (int i = 0; i < count; ++i) {
      if (!barycentric(mesh, i, q, b)) continue;
      const double m = b[size_t(mostNegative(b))];
      if (m > bestMin) {
        bestMin = m;
        best = i;
        bestB = b;
      }
    }
    if (best >= 0 && bestMin >= -kEpsilon) return insideLocation(mesh, best, bestB);
  }
  ProbeLocation loc = outsideLocation(mesh, q);
  if (loc.tetrahedron < 0) {  // no hull face (a mesh without neighbours): the nearest probe
    loc = nearestProbe(mesh, q);
  }
  return loc;
}

std::string checkProbeTetrahedra(const ProbeTetrahedra& mesh) {
  const int count = int(mesh.tetrahedra.size());
  const int probes = int(mesh.positions.size());
  const std::string probeCount = " (" + std::to_string(probes) + " probes)";
  for (int i = 0; i < probes; ++i) {
    const glm::vec3& v = mesh.positions[size_t(i)];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      return "probe " + std::to_string(i) + " has a position that is not finite";
  }
  if (mesh.neighbours.size() != mesh.tetrahedra.size())
    return std::to_string(mesh.neighbours.size()) + " neighbour entries for " +
           std::to_string(count) + " tetrahedra";
  for (int t = 0; t < count; ++t) {
    const std::string name = "tetrahedron " + std::to_string(t);
    const glm::ivec4& v = mesh.tetrahedra[size_t(t)];
    for (int i = 0; i < 4; ++i)
      if (v[i] < 0 || v[i] >= probes)
        return name + ": corner " + std::to_string(i) + " is probe " + std::to_string(v[i]) +
               ", out of range" + probeCount;
    const std::array<dvec3, 4> c = corners(mesh, t);
    const double volume = orient(c[0], c[1], c[2], c[3]) / 6.0;
    if (!(volume > 0.0))
      return name + ": " +
             (volume == 0.0 ? std::string("zero volume")
                            : "negative volume (corners not positively oriented)");
  }
  for (int t = 0; t < count; ++t) {
    const std::string name = "tetrahedron " + std::to_string(t);
    const glm::ivec4& v = mesh.tetrahedra[size_t(t)];
    for (int i = 0; i < 4; ++i) {
      const int n = mesh.neighbours[size_t(t)][i];
      if (n == -1) continue;
      const std::string across = name + ": neighbour " + std::to_string(n) +
                                 " across the face opposite corner " + std::to_string(i);
      if (n < -1 || n >= count) return across + " is out of range";
      if (n == t) return across + " is itself";
      int back = -1;
      for (int j = 0; j < 4; ++j)
        if (mesh.neighbours[size_t(n)][j] == t) back = j;
      if (back < 0) return across + " does not have it as a neighbour";
      // The shared face: t's corners but i, n's corners but back, as sets.
      std::array<int, 3> mine{}, theirs{};
      for (int j = 0, a = 0, b = 0; j < 4; ++j) {
        if (j != i) mine[size_t(a++)] = v[j];
        if (j != back) theirs[size_t(b++)] = mesh.tetrahedra[size_t(n)][j];
      }
      std::sort(mine.begin(), mine.end());
      std::sort(theirs.begin(), theirs.end());
      if (mine != theirs) return across + " does not share that face";
      if (mesh.tetrahedra[size_t(n)][back] == v[i])
        return across + " has the same opposite corner (a duplicated tetrahedron)";
    }
  }
  return "";
}

}  // namespace afterglow::runtime
