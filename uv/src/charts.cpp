// Chart segmentation: weld, connect with OpenMesh, cut at hard edges, grow planar regions, grow
// charts over regions inside a normal cone, parameterise (split what parameterises badly), merge
// neighbours while the merged chart still unfolds with low stretch, then split vertices per chart.
#include "afterglow/uv/charts.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <queue>
#include <unordered_map>
#include <utility>

#include <OpenMesh/Core/Mesh/TriConnectivity.hh>

#include "afterglow/core/check.h"
#include "chart_param.h"

namespace afterglow::uv {
namespace {

using detail::ChartGeometry;
using detail::ChartParam;
// Connectivity only: positions stay in our own double-precision arrays.
using OmMesh = OpenMesh::TriConnectivity;

// A grown chart is split again (tighter cone) when it unfolds worse than this.
constexpr double kMaxChartStretch = 1.08;
// Two charts merge only when the union unfolds at most this badly, flip-free.
constexpr double kMaxMergedStretch = 1.02;
// Each merge attempt re-measures the whole union; past this size one chart fewer is not worth it.
constexpr size_t kMaxMergeTriangles = 6000;
// Failed merge attempts per chart before giving up on it.
constexpr int kMaxMergeFailures = 6;
constexpr double kMinConeDeg = 5.0;

double cosDeg(double deg) { return std::cos(deg * 3.14159265358979323846 / 180.0); }

struct Geometry {
  std::vector<glm::dvec3> pos;      // per vertex id (welded, plus copies for isolated faces)
  std::vector<uint32_t> faceV;      // 3 vertex ids per triangle, corner order of the input
  std::vector<double> area;
  std::vector<glm::dvec3> normal;   // unit; zero for degenerate triangles
  std::vector<uint8_t> degenerate;
  std::vector<int32_t> nbr;         // 3 per triangle: neighbour across corner k -> k+1, -1 when
                                    // boundary, non-manifold or a hard edge
  std::vector<int32_t> twin;        // 3 per triangle: the face across the edge, hard or not
  std::vector<double> edgeLen;      // 3 per triangle
  size_t triangleCount() const { return area.size(); }
};

struct Region {
  std::vector<uint32_t> faces;
  double area = 0.0;
  glm::dvec3 normalSum{0.0};  // area-weighted
  glm::dvec3 seedNormal{0.0};
};

struct WorkChart {
  std::vector<uint32_t> regions;
  std::vector<uint32_t> faces;   // non-degenerate faces
  std::vector<uint32_t> verts;   // vertex ids, parallel to param.uv
  ChartParam param;
  int euler = 1;
  bool crosses = false;  // its UV boundary crosses itself (the map overlaps)
  bool alive = true;
};

struct BitsHash {
  size_t operator()(const glm::vec3& v) const {
    uint32_t b[3];
    std::memcpy(b, &v, sizeof b);
    uint64_t h = b[0] * 0x9E3779B97F4A7C15ull;
    h ^= (b[1] + 0x7F4A7C15ull) * 0xC2B2AE3D27D4EB4Full;
    h ^= (b[2] + 0x165667B1ull) * 0x165667B19E3779F9ull;
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

// OpenMesh would refuse (and complain on stderr about) a face through a closed fan, along a used
// half-edge, or where the fan around a vertex cannot be re-linked; such faces go in as isolated
// triangles instead. The checks mirror PolyConnectivity::add_face.
bool canAddFace(const OmMesh& mesh, const OmMesh::VertexHandle (&v)[3]) {
  OmMesh::HalfedgeHandle edge[3];
  for (int i = 0; i < 3; ++i) {
    if (!mesh.is_boundary(v[i])) return false;
    edge[i] = mesh.find_halfedge(v[i], v[(i + 1) % 3]);
    if (edge[i].is_valid() && !mesh.is_boundary(edge[i])) return false;
  }
  for (int i = 0; i < 3; ++i) {
    auto innerPrev = edge[i], innerNext = edge[(i + 1) % 3];
    if (!innerPrev.is_valid() || !innerNext.is_valid()) continue;
    if (mesh.next_halfedge_handle(innerPrev) == innerNext) continue;
    auto boundaryPrev = mesh.opposite_halfedge_handle(innerNext);
    do boundaryPrev = mesh.opposite_halfedge_handle(mesh.next_halfedge_handle(boundaryPrev));
    while (!mesh.is_boundary(boundaryPrev));
    if (boundaryPrev == innerPrev) return false;
  }
  return true;
}

Geometry buildGeometry(const scenes::Primitive& prim, const ChartOptions& options) {
  Geometry g;
  const size_t n = prim.indices.size() / 3;
  for (uint32_t i : prim.indices) AG_CHECK(i < prim.positions.size(), "index out of range");
  g.faceV.resize(3 * n);
  g.area.resize(n);
  g.normal.assign(n, glm::dvec3(0.0));
  g.degenerate.assign(n, 0);
  g.nbr.assign(3 * n, -1);
  g.twin.assign(3 * n, -1);
  g.edgeLen.resize(3 * n);

  // glTF splits vertices at normal and UV seams; welding by exact position restores connectivity.
  std::unordered_map<glm::vec3, uint32_t, BitsHash> weld;
  std::vector<uint32_t> weldOf(prim.positions.size());
  for (size_t i = 0; i < prim.positions.size(); ++i) {
    glm::vec3 key = prim.positions[i] + glm::vec3(0.0f);  // folds -0 into +0
    auto [it, inserted] = weld.emplace(key, static_cast<uint32_t>(g.pos.size()));
    if (inserted) g.pos.emplace_back(prim.positions[i]);
    weldOf[i] = it->second;
  }
  const size_t welded = g.pos.size();

  double totalArea = 0.0;
  for (size_t t = 0; t < n; ++t) {
    glm::dvec3 p0 = prim.positions[prim.indices[3 * t]], p1 = prim.positions[prim.indices[3 * t + 1]],
               p2 = prim.positions[prim.indices[3 * t + 2]];
    glm::dvec3 c = glm::cross(p1 - p0, p2 - p0);
    double len = glm::length(c);
    g.area[t] = 0.5 * len;
    if (len > 0.0) g.normal[t] = c / len;
    if (std::isfinite(g.area[t])) totalArea += g.area[t];
    g.edgeLen[3 * t] = glm::length(p1 - p0);
    g.edgeLen[3 * t + 1] = glm::length(p2 - p1);
    g.edgeLen[3 * t + 2] = glm::length(p0 - p2);
  }
  const double minArea = n ? totalArea / static_cast<double>(n) * options.degenerateAreaFraction : 0.0;

  OmMesh mesh;
  mesh.reserve(welded, 3 * n, n);
  for (size_t v = 0; v < welded; ++v) mesh.new_vertex();
  std::vector<int32_t> triOfFace;
  triOfFace.reserve(n);
  std::unordered_map<uint64_t, uint32_t> seenFaces;  // sorted welded triple -> first triangle
  seenFaces.reserve(n);
  for (size_t t = 0; t < n; ++t) {
    uint32_t w[3];
    for (int k = 0; k < 3; ++k) w[k] = weldOf[prim.indices[3 * t + k]];
    bool repeated = w[0] == w[1] || w[1] == w[2] || w[0] == w[2];
    if (repeated || !(g.area[t] > minArea)) {
      g.degenerate[t] = 1;
      for (int k = 0; k < 3; ++k) g.faceV[3 * t + k] = w[k];
      continue;
    }
    uint32_t s[3] = {w[0], w[1], w[2]};
    std::sort(s, s + 3);
    uint64_t key = (uint64_t(s[0]) * 0x100000001B3ull) ^ (uint64_t(s[1]) << 21) ^ (uint64_t(s[2]) << 42) ^ s[2];
    bool duplicate = false;
    auto [it, inserted] = seenFaces.emplace(key, static_cast<uint32_t>(t));
    if (!inserted) {
      uint32_t o = it->second;
      uint32_t so[3] = {g.faceV[3 * o], g.faceV[3 * o + 1], g.faceV[3 * o + 2]};
      std::sort(so, so + 3);
      duplicate = so[0] == s[0] && so[1] == s[1] && so[2] == s[2];
    }
    OmMesh::VertexHandle vh[3] = {OmMesh::VertexHandle(int(w[0])), OmMesh::VertexHandle(int(w[1])),
                                  OmMesh::VertexHandle(int(w[2]))};
    OmMesh::FaceHandle fh;
    if (!duplicate && canAddFace(mesh, vh)) fh = mesh.add_face(vh[0], vh[1], vh[2]);
    if (fh.is_valid()) {
      for (int k = 0; k < 3; ++k) g.faceV[3 * t + k] = w[k];
      if (triOfFace.size() <= size_t(fh.idx())) triOfFace.resize(fh.idx() + 1, -1);
      triOfFace[fh.idx()] = static_cast<int32_t>(t);
    } else {
      // Non-manifold or duplicate: its own vertices, hence its own boundary.
      for (int k = 0; k < 3; ++k) {
        g.faceV[3 * t + k] = static_cast<uint32_t>(g.pos.size());
        g.pos.push_back(g.pos[w[k]]);
      }
    }
  }

  const double hardCos = cosDeg(options.hardEdgeAngleDeg);
  // A lightmap texel straddling a hard shading edge would blend two different normals.
  const double seamCos = cosDeg(options.shadingSeamAngleDeg);
  auto normalsAgree = [&](uint32_t oa, uint32_t ob) {
    if (prim.normals.size() != prim.positions.size()) return true;
    glm::dvec3 a = prim.normals[oa], b = prim.normals[ob];
    double la = glm::length(a), lb = glm::length(b);
    if (!(la > 0.0) || !(lb > 0.0)) return true;
    return glm::dot(a, b) >= seamCos * la * lb;
  };
  for (auto fh : mesh.faces()) {
    int32_t t = triOfFace[fh.idx()];
    for (int k = 0; k < 3; ++k) {
      uint32_t a = g.faceV[3 * t + k], b = g.faceV[3 * t + (k + 1) % 3];
      auto heh = mesh.find_halfedge(OmMesh::VertexHandle(int(a)), OmMesh::VertexHandle(int(b)));
      auto ofh = mesh.face_handle(mesh.opposite_halfedge_handle(heh));
      if (!ofh.is_valid()) continue;
      int32_t o = triOfFace[ofh.idx()];
      g.twin[3 * t + k] = o;
      if (glm::dot(g.normal[t], g.normal[o]) < hardCos) continue;
      bool agree = true;
      for (int ko = 0; ko < 3; ++ko) {
        uint32_t v = g.faceV[3 * o + ko];
        if (v == a) agree = agree && normalsAgree(prim.indices[3 * t + k], prim.indices[3 * o + ko]);
        if (v == b) agree = agree && normalsAgree(prim.indices[3 * t + (k + 1) % 3], prim.indices[3 * o + ko]);
      }
      if (agree) g.nbr[3 * t + k] = o;
    }
  }
  return g;
}

// Planar regions: connected faces within planarAngleDeg of their seed's normal.
std::vector<Region> growRegions(const Geometry& g, const ChartOptions& options,
                                std::vector<int32_t>& regionOf) {
  const size_t n = g.triangleCount();
  std::vector<uint32_t> order;
  for (uint32_t t = 0; t < n; ++t)
    if (!g.degenerate[t]) order.push_back(t);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return g.area[a] > g.area[b]; });
  regionOf.assign(n, -1);
  const double planarCos = cosDeg(options.planarAngleDeg);
  std::vector<Region> regions;
  std::vector<uint32_t> stack;
  for (uint32_t seed : order) {
    if (regionOf[seed] >= 0) continue;
    Region r;
    r.seedNormal = g.normal[seed];
    int32_t id = static_cast<int32_t>(regions.size());
    regionOf[seed] = id;
    stack.assign(1, seed);
    while (!stack.empty()) {
      uint32_t f = stack.back();
      stack.pop_back();
      r.faces.push_back(f);
      r.area += g.area[f];
      r.normalSum += g.normal[f] * g.area[f];
      for (int k = 0; k < 3; ++k) {
        int32_t o = g.nbr[3 * f + k];
        if (o < 0 || regionOf[o] >= 0) continue;
        if (glm::dot(g.normal[o], r.seedNormal) < planarCos) continue;
        regionOf[o] = id;
        stack.push_back(static_cast<uint32_t>(o));
      }
    }
    std::sort(r.faces.begin(), r.faces.end());
    regions.push_back(std::move(r));
  }
  return regions;
}

struct Adjacency {
  std::vector<std::vector<std::pair<uint32_t, double>>> of;  // neighbour region, shared length
};

Adjacency regionAdjacency(const Geometry& g, const std::vector<int32_t>& regionOf, size_t count) {
  struct Entry { uint32_t a, b; double len; };
  std::vector<Entry> entries;
  for (size_t t = 0; t < g.triangleCount(); ++t) {
    if (regionOf[t] < 0) continue;
    for (int k = 0; k < 3; ++k) {
      int32_t o = g.nbr[3 * t + k];
      if (o < 0 || regionOf[o] < 0 || regionOf[o] == regionOf[t]) continue;
      entries.push_back({uint32_t(regionOf[t]), uint32_t(regionOf[o]), g.edgeLen[3 * t + k]});
    }
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  });
  Adjacency adj;
  adj.of.resize(count);
  for (const auto& e : entries) {
    auto& list = adj.of[e.a];
    if (!list.empty() && list.back().first == e.b) list.back().second += e.len;
    else list.emplace_back(e.b, e.len);
  }
  return adj;
}

class Charter {
 public:
  Charter(const Geometry& g, const ChartOptions& options)
      : g_(g), options_(options), localOf_(g.pos.size(), -1), faceStamp_(g.triangleCount(), 0) {
    regions_ = growRegions(g_, options_, regionOf_);
    adj_ = regionAdjacency(g_, regionOf_, regions_.size());
    regionChart_.assign(regions_.size(), -2);
  }

  std::vector<WorkChart> run() {
    std::vector<uint32_t> all(regions_.size());
    for (uint32_t r = 0; r < all.size(); ++r) all[r] = r;
    std::vector<WorkChart> charts;
    segment(all, options_.maxChartAngleDeg, charts);
    merge(charts);
    return charts;
  }

 private:
  // Grows charts over the given regions inside a normal cone of half-angle coneDeg, then
  // parameterises each; charts that unfold badly are regrown with a tighter cone.
  void segment(const std::vector<uint32_t>& subset, double coneDeg, std::vector<WorkChart>& out) {
    const double coneCos = cosDeg(coneDeg);
    std::vector<uint32_t> order = subset;
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return regions_[a].area > regions_[b].area;
    });
    for (uint32_t r : subset) regionChart_[r] = -1;
    std::vector<std::vector<uint32_t>> grown;
    using Item = std::pair<double, uint32_t>;
    for (uint32_t seed : order) {
      if (regionChart_[seed] != -1) continue;
      int32_t id = static_cast<int32_t>(grown.size());
      grown.emplace_back();
      auto& members = grown.back();
      glm::dvec3 sum(0.0);
      std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
      auto add = [&](uint32_t r) {
        regionChart_[r] = id;
        members.push_back(r);
        sum += regions_[r].normalSum;
        glm::dvec3 axis = glm::normalize(sum);
        for (const auto& [o, len] : adj_.of[r]) {
          if (regionChart_[o] != -1) continue;
          double deviation = 1.0 - glm::dot(glm::normalize(regions_[o].normalSum), axis);
          // Prefer regions that share much of their outline with the chart (compact charts).
          double perimeterShare = len / std::max(perimeter(o), 1e-30);
          queue.emplace(deviation + 0.05 * (1.0 - std::min(perimeterShare, 1.0)), o);
        }
      };
      add(seed);
      while (!queue.empty()) {
        uint32_t r = queue.top().second;
        queue.pop();
        if (regionChart_[r] != -1) continue;
        glm::dvec3 axis = glm::normalize(sum + regions_[r].normalSum);
        bool fits = true;
        for (uint32_t f : regions_[r].faces)
          if (!(glm::dot(g_.normal[f], axis) >= coneCos)) { fits = false; break; }
        if (fits) add(r);
      }
    }
    // Regions left at -2 mark "not in any subset being grown".
    for (uint32_t r : subset) regionChart_[r] = -2;

    for (auto& members : grown) {
      WorkChart chart;
      chart.regions = members;
      std::sort(chart.regions.begin(), chart.regions.end());
      collectFaces(chart);
      parameterise(chart);
      bool good = chart.param.flipped == 0 && chart.param.stretch <= kMaxChartStretch &&
                  !chart.crosses;
      if (good || chart.regions.size() == 1) {
        out.push_back(std::move(chart));
      } else if (coneDeg * 0.5 >= kMinConeDeg) {
        segment(chart.regions, coneDeg * 0.5, out);
      } else {
        for (uint32_t r : chart.regions) {
          WorkChart single;
          single.regions = {r};
          collectFaces(single);
          parameterise(single);
          out.push_back(std::move(single));
        }
      }
    }
  }

  double perimeter(uint32_t r) {
    if (perimeter_.empty()) {
      perimeter_.assign(regions_.size(), 0.0);
      for (size_t t = 0; t < g_.triangleCount(); ++t) {
        if (regionOf_[t] < 0) continue;
        for (int k = 0; k < 3; ++k) {
          int32_t o = g_.nbr[3 * t + k];
          if (o < 0 || regionOf_[o] != regionOf_[t]) perimeter_[regionOf_[t]] += g_.edgeLen[3 * t + k];
        }
      }
    }
    return perimeter_[r];
  }

  void collectFaces(WorkChart& chart) const {
    chart.faces.clear();
    for (uint32_t r : chart.regions)
      chart.faces.insert(chart.faces.end(), regions_[r].faces.begin(), regions_[r].faces.end());
    std::sort(chart.faces.begin(), chart.faces.end());
  }

  // Boundary edges of the faces (as pairs of local vertex indices): edges whose twin is not one
  // of the faces. Call while localOf_ holds the local indices.
  std::vector<std::pair<uint32_t, uint32_t>> boundary(const std::vector<uint32_t>& faces) {
    ++stamp_;
    for (uint32_t f : faces) faceStamp_[f] = stamp_;
    std::vector<std::pair<uint32_t, uint32_t>> segments;
    for (uint32_t f : faces)
      for (int k = 0; k < 3; ++k) {
        int32_t o = g_.twin[3 * f + k];
        if (o >= 0 && faceStamp_[o] == stamp_) continue;
        segments.emplace_back(uint32_t(localOf_[g_.faceV[3 * f + k]]),
                              uint32_t(localOf_[g_.faceV[3 * f + (k + 1) % 3]]));
      }
    return segments;
  }

  ChartGeometry localGeometry(const std::vector<uint32_t>& faces, std::vector<uint32_t>& verts,
                              std::vector<std::pair<uint32_t, uint32_t>>& segments) {
    ChartGeometry cg;
    verts.clear();
    cg.triangles.reserve(faces.size() * 3);
    for (uint32_t f : faces)
      for (int k = 0; k < 3; ++k) {
        uint32_t v = g_.faceV[3 * f + k];
        if (localOf_[v] < 0) {
          localOf_[v] = static_cast<int32_t>(verts.size());
          verts.push_back(v);
          cg.positions.push_back(g_.pos[v]);
        }
        cg.triangles.push_back(static_cast<uint32_t>(localOf_[v]));
      }
    segments = boundary(faces);
    for (uint32_t v : verts) localOf_[v] = -1;
    return cg;
  }

  // Euler characteristic V - E + F (1 for a disk).
  int euler(const std::vector<uint32_t>& faces) {
    std::vector<uint64_t> edges;
    edges.reserve(faces.size() * 3);
    size_t vertexCount = 0;
    for (uint32_t f : faces)
      for (int k = 0; k < 3; ++k) {
        uint32_t a = g_.faceV[3 * f + k], b = g_.faceV[3 * f + (k + 1) % 3];
        if (localOf_[a] < 0) { localOf_[a] = 0; scratch_.push_back(a); ++vertexCount; }
        edges.push_back((uint64_t(std::min(a, b)) << 32) | std::max(a, b));
      }
    for (uint32_t v : scratch_) localOf_[v] = -1;
    scratch_.clear();
    std::sort(edges.begin(), edges.end());
    size_t edgeCount = size_t(std::unique(edges.begin(), edges.end()) - edges.begin());
    return int(vertexCount) - int(edgeCount) + int(faces.size());
  }

  void parameterise(WorkChart& chart) {
    std::vector<std::pair<uint32_t, uint32_t>> segments;
    ChartGeometry cg = localGeometry(chart.faces, chart.verts, segments);
    glm::dvec3 sum(0.0);
    for (uint32_t r : chart.regions) sum += regions_[r].normalSum;
    glm::dvec3 axis = glm::normalize(sum);
    bool planar = true;
    if (chart.regions.size() == 1) {
      axis = regions_[chart.regions[0]].seedNormal;
    } else {
      const double planarCos = cosDeg(options_.planarAngleDeg);
      for (uint32_t f : chart.faces)
        if (!(glm::dot(g_.normal[f], axis) >= planarCos)) { planar = false; break; }
    }
    chart.param = planar ? detail::projectPlanar(cg, axis) : detail::solveLscm(cg);
    chart.euler = euler(chart.faces);
    chart.crosses = chart.param.flipped == 0 && detail::boundaryCrosses(chart.param.uv, segments);
  }

  // Merges neighbouring charts, smallest first, while the union stays a disk and unfolds
  // flip-free with low stretch: fewer, larger charts pack with less padding waste. The smaller
  // chart is unfolded onto the larger one's existing map (LSCM with the shared vertices pinned),
  // so a merge attempt costs the small chart's solve, not the union's.
  void merge(std::vector<WorkChart>& charts) {
    std::vector<int32_t> chartOf(g_.triangleCount(), -1);
    for (size_t c = 0; c < charts.size(); ++c)
      for (uint32_t f : charts[c].faces) chartOf[f] = static_cast<int32_t>(c);
    std::vector<uint32_t> order(charts.size());
    for (uint32_t c = 0; c < order.size(); ++c) order[c] = c;
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return charts[a].param.area3d < charts[b].param.area3d;
    });
    std::vector<std::pair<uint32_t, double>> shared, byChart;
    std::vector<uint32_t> tried;
    for (uint32_t c : order) {
      if (!charts[c].alive) continue;
      int failures = 0;
      tried.clear();
      bool merged = true;
      while (merged && failures < kMaxMergeFailures) {
        merged = false;
        shared.clear();
        for (uint32_t f : charts[c].faces)
          for (int k = 0; k < 3; ++k) {
            int32_t o = g_.nbr[3 * f + k];
            if (o < 0 || chartOf[o] < 0 || chartOf[o] == int32_t(c)) continue;
            shared.emplace_back(uint32_t(chartOf[o]), g_.edgeLen[3 * f + k]);
          }
        std::sort(shared.begin(), shared.end());
        byChart.clear();
        for (const auto& s : shared) {
          if (!byChart.empty() && byChart.back().first == s.first) byChart.back().second += s.second;
          else byChart.push_back(s);
        }
        std::stable_sort(byChart.begin(), byChart.end(),
                         [](const auto& a, const auto& b) { return a.second > b.second; });
        for (const auto& entry : byChart) {
          uint32_t d = entry.first;
          if (std::find(tried.begin(), tried.end(), d) != tried.end()) continue;
          if (charts[c].faces.size() + charts[d].faces.size() > kMaxMergeTriangles) continue;
          tried.push_back(d);
          bool cLarger = charts[c].param.area3d >= charts[d].param.area3d;
          WorkChart u;
          if (tryMerge(charts[cLarger ? c : d], charts[cLarger ? d : c], chartOf, u)) {
            for (uint32_t f : charts[d].faces) chartOf[f] = int32_t(c);
            charts[d] = WorkChart();
            charts[d].alive = false;
            charts[c] = std::move(u);
            merged = true;
            break;
          }
          if (++failures >= kMaxMergeFailures) break;
        }
      }
    }
  }

  bool tryMerge(const WorkChart& big, const WorkChart& small, const std::vector<int32_t>& chartOf,
                WorkChart& u) {
    // Gluing two disks along one arc gives a disk; along two arcs, a ring, which does not
    // unfold. chi(union) = chi(big) + chi(small) - chi(intersection), and the intersection is
    // the shared vertices and edges.
    const int32_t bigId = chartOf[big.faces.front()];
    for (size_t i = 0; i < big.verts.size(); ++i) localOf_[big.verts[i]] = int32_t(i);
    int sharedVerts = 0, sharedEdges = 0;
    for (uint32_t f : small.faces)
      for (int k = 0; k < 3; ++k) {
        int32_t o = g_.twin[3 * f + k];
        if (o >= 0 && chartOf[o] == bigId) ++sharedEdges;
      }
    for (uint32_t v : small.verts)
      if (localOf_[v] >= 0) ++sharedVerts;
    bool ok = sharedVerts - sharedEdges == 1 && sharedEdges > 0;
    if (ok) {
      u.regions.resize(big.regions.size() + small.regions.size());
      std::merge(big.regions.begin(), big.regions.end(), small.regions.begin(), small.regions.end(),
                 u.regions.begin());
      u.faces.resize(big.faces.size() + small.faces.size());
      std::merge(big.faces.begin(), big.faces.end(), small.faces.begin(), small.faces.end(),
                 u.faces.begin());
      u.euler = big.euler + small.euler - 1;
      ChartGeometry cg;
      u.verts = big.verts;
      cg.positions.reserve(big.verts.size() + small.verts.size());
      for (uint32_t v : big.verts) cg.positions.push_back(g_.pos[v]);
      for (uint32_t v : small.verts)
        if (localOf_[v] < 0) {
          localOf_[v] = int32_t(u.verts.size());
          u.verts.push_back(v);
          cg.positions.push_back(g_.pos[v]);
        }
      std::vector<uint32_t> smallTriangles;
      smallTriangles.reserve(small.faces.size() * 3);
      for (uint32_t f : small.faces)
        for (int k = 0; k < 3; ++k) smallTriangles.push_back(uint32_t(localOf_[g_.faceV[3 * f + k]]));
      cg.triangles.reserve(u.faces.size() * 3);
      for (uint32_t f : u.faces)
        for (int k = 0; k < 3; ++k) cg.triangles.push_back(uint32_t(localOf_[g_.faceV[3 * f + k]]));
      std::vector<std::pair<uint32_t, uint32_t>> segments = boundary(u.faces);
      for (uint32_t v : u.verts) localOf_[v] = -1;

      glm::dvec3 sum(0.0);
      for (uint32_t r : u.regions) sum += regions_[r].normalSum;
      glm::dvec3 axis = glm::normalize(sum);
      const double planarCos = cosDeg(options_.planarAngleDeg);
      bool planar = true;
      for (uint32_t f : u.faces)
        if (!(glm::dot(g_.normal[f], axis) >= planarCos)) { planar = false; break; }
      if (planar) {
        u.param = detail::projectPlanar(cg, axis);
      } else {
        std::vector<glm::dvec2> uv(cg.positions.size(), glm::dvec2(0.0));
        std::vector<uint8_t> pinned(cg.positions.size(), 0);
        for (size_t i = 0; i < big.verts.size(); ++i) { uv[i] = big.param.uv[i]; pinned[i] = 1; }
        if (!detail::lscmSolve(cg.positions, smallTriangles, pinned, uv)) return false;
        u.param = detail::evaluate(cg, std::move(uv));
      }
      double limit = std::max(kMaxMergedStretch, std::max(big.param.stretch, small.param.stretch));
      return u.param.flipped == 0 && u.param.stretch <= limit &&
             !detail::boundaryCrosses(u.param.uv, segments);
    }
    for (uint32_t v : big.verts) localOf_[v] = -1;
    return false;
  }

  const Geometry& g_;
  const ChartOptions& options_;
  std::vector<Region> regions_;
  std::vector<int32_t> regionOf_;
  std::vector<int32_t> regionChart_;
  std::vector<double> perimeter_;
  Adjacency adj_;
  std::vector<int32_t> localOf_;
  std::vector<uint32_t> scratch_;
  std::vector<uint32_t> faceStamp_;  // == stamp_ marks the faces of the chart being examined
  uint32_t stamp_ = 0;
};

// UV of a point on the plane of chart triangle s, by the triangle's affine 3D -> 2D map.
glm::dvec2 extendAffine(const glm::dvec3 (&p)[3], const glm::dvec2 (&q)[3], glm::dvec3 x) {
  glm::dvec3 e1 = p[1] - p[0], e2 = p[2] - p[0], d = x - p[0];
  double a = glm::dot(e1, e1), b = glm::dot(e1, e2), c = glm::dot(e2, e2);
  double det = a * c - b * b;
  if (!(std::abs(det) > 0.0)) return q[0];
  double r1 = glm::dot(d, e1), r2 = glm::dot(d, e2);
  double beta = (c * r1 - b * r2) / det, gamma = (a * r2 - b * r1) / det;
  return q[0] + beta * (q[1] - q[0]) + gamma * (q[2] - q[0]);
}

void chartPrimitive(const scenes::Primitive& prim, int primIndex, const ChartOptions& options,
                    MeshCharts& result) {
  Geometry g = buildGeometry(prim, options);
  const size_t n = g.triangleCount();
  std::vector<WorkChart> charts = Charter(g, options).run();

  // Final charts of this primitive: per chart its faces and a vertex -> uv table.
  struct Final {
    std::vector<uint32_t> faces;
    std::vector<std::pair<uint32_t, glm::dvec2>> uv;  // sorted by vertex id once complete
    bool planar = false;
  };
  std::vector<Final> finals;
  std::vector<int32_t> chartOf(n, -1);
  std::vector<int32_t> vertexChart(g.pos.size(), -1);
  for (auto& c : charts) {
    if (!c.alive) continue;
    Final f;
    f.faces = std::move(c.faces);
    f.planar = c.param.planar;
    for (size_t i = 0; i < c.verts.size(); ++i) {
      f.uv.emplace_back(c.verts[i], c.param.uv[i]);
      if (vertexChart[c.verts[i]] < 0) vertexChart[c.verts[i]] = int32_t(finals.size());
    }
    for (uint32_t t : f.faces) chartOf[t] = int32_t(finals.size());
    std::sort(f.uv.begin(), f.uv.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    finals.push_back(std::move(f));
  }
  auto findUv = [](const Final& f, uint32_t v) -> const glm::dvec2* {
    auto it = std::lower_bound(f.uv.begin(), f.uv.end(), v,
                               [](const auto& e, uint32_t key) { return e.first < key; });
    return it != f.uv.end() && it->first == v ? &it->second : nullptr;
  };

  // Degenerate triangles join a chart that holds one of their vertices; their other vertices
  // are placed by the affine map of a chart triangle at the shared vertex.
  for (bool progress = true; progress;) {
    progress = false;
    for (uint32_t t = 0; t < n; ++t) {
      if (chartOf[t] >= 0 || !g.degenerate[t]) continue;
      int32_t c = -1;
      uint32_t shared = 0;
      for (int k = 0; k < 3 && c < 0; ++k)
        if (vertexChart[g.faceV[3 * t + k]] >= 0) { c = vertexChart[g.faceV[3 * t + k]]; shared = g.faceV[3 * t + k]; }
      if (c < 0) continue;
      Final& f = finals[c];
      std::vector<std::pair<uint32_t, glm::dvec2>> added;
      for (int k = 0; k < 3; ++k) {
        uint32_t v = g.faceV[3 * t + k];
        if (findUv(f, v) || std::any_of(added.begin(), added.end(), [&](const auto& e) { return e.first == v; }))
          continue;
        glm::dvec2 uv = *findUv(f, shared);
        for (uint32_t s : f.faces) {
          if (g.degenerate[s]) continue;
          int ks = -1;
          for (int j = 0; j < 3; ++j) if (g.faceV[3 * s + j] == shared) ks = j;
          if (ks < 0) continue;
          glm::dvec3 p[3];
          glm::dvec2 q[3];
          for (int j = 0; j < 3; ++j) { p[j] = g.pos[g.faceV[3 * s + j]]; q[j] = *findUv(f, g.faceV[3 * s + j]); }
          uv = extendAffine(p, q, g.pos[v]);
          break;
        }
        added.emplace_back(v, uv);
      }
      for (const auto& e : added) {
        f.uv.push_back(e);
        if (vertexChart[e.first] < 0) vertexChart[e.first] = c;
      }
      if (!added.empty())
        std::sort(f.uv.begin(), f.uv.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      f.faces.push_back(t);
      chartOf[t] = c;
      progress = true;
    }
  }
  // Degenerate triangles with no charted neighbour: a zero-area chart of their own.
  for (uint32_t t = 0; t < n; ++t) {
    if (chartOf[t] >= 0) continue;
    Final f;
    f.planar = true;
    f.faces = {t};
    const glm::dvec3 origin = g.pos[g.faceV[3 * t]];
    for (int k = 0; k < 3; ++k) {
      uint32_t v = g.faceV[3 * t + k];
      if (!findUv(f, v)) {
        f.uv.emplace_back(v, glm::dvec2(g.pos[v].x - origin.x, g.pos[v].y - origin.y));
        std::sort(f.uv.begin(), f.uv.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      }
    }
    chartOf[t] = int32_t(finals.size());
    finals.push_back(std::move(f));
  }

  // Split vertices: one new vertex per (original vertex, chart), numbered in triangle order.
  const uint32_t chartBase = static_cast<uint32_t>(result.charts.size());
  ChartedPrimitive& out = result.primitives[primIndex];
  out.indices.resize(3 * n);
  std::unordered_map<uint64_t, uint32_t> newVertex;
  newVertex.reserve(prim.positions.size() * 2);
  for (uint32_t t = 0; t < n; ++t) {
    const Final& f = finals[chartOf[t]];
    for (int k = 0; k < 3; ++k) {
      uint32_t original = prim.indices[3 * t + k];
      uint64_t key = (uint64_t(chartOf[t]) << 32) | original;
      auto [it, inserted] = newVertex.emplace(key, uint32_t(out.vertexRemap.size()));
      if (inserted) {
        out.vertexRemap.push_back(original);
        out.chartUv.push_back(glm::vec2(*findUv(f, g.faceV[3 * t + k])));
        out.vertexChart.push_back(chartBase + uint32_t(chartOf[t]));
      }
      out.indices[3 * t + k] = it->second;
    }
  }
  // area2d counts the triangles that were parameterised: a degenerate triangle whose vertices all
  // lie in a curved chart keeps their (not collinear) UVs and would add UV area with no 3D area.
  for (const Final& f : finals) {
    Chart chart;
    chart.primitive = primIndex;
    chart.planar = f.planar;
    chart.triangles = f.faces;
    std::sort(chart.triangles.begin(), chart.triangles.end());
    for (uint32_t t : chart.triangles) {
      chart.area3d += g.area[t];
      if (g.degenerate[t]) continue;
      glm::dvec2 q0 = out.chartUv[out.indices[3 * t]], q1 = out.chartUv[out.indices[3 * t + 1]],
                 q2 = out.chartUv[out.indices[3 * t + 2]];
      chart.area2d += 0.5 * std::abs((q1.x - q0.x) * (q2.y - q0.y) - (q2.x - q0.x) * (q1.y - q0.y));
    }
    result.charts.push_back(std::move(chart));
  }
}

}  // namespace

MeshCharts computeCharts(const scenes::Mesh& mesh, const ChartOptions& options) {
  MeshCharts result;
  result.primitives.resize(mesh.primitives.size());
  for (size_t p = 0; p < mesh.primitives.size(); ++p)
    chartPrimitive(mesh.primitives[p], static_cast<int>(p), options, result);
  return result;
}

}  // namespace afterglow::uv
