#include "shells.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>

#include "afterglow/core/math.h"
#include "afterglow/core/parallel.h"
#include "afterglow/core/union_find.h"

namespace afterglow::probes {

namespace {

struct PositionKey {
  uint32_t bits[3];
  bool operator==(const PositionKey& o) const { return std::memcmp(bits, o.bits, 12) == 0; }
};
struct PositionHash {
  size_t operator()(const PositionKey& k) const {
    return (size_t(k.bits[0]) * 73856093u) ^ (size_t(k.bits[1]) * 19349663u) ^
           (size_t(k.bits[2]) * 83492791u);
  }
};

// One mesh's shells per triangle in primitive order, numbered from 0 in the order of their first
// triangle (deterministic); first[p]: primitive p's first triangle. Returns the shell count.
uint32_t meshShells(const scenes::Mesh& mesh, std::vector<uint32_t>& shell,
                    std::vector<uint32_t>& first) {
  std::unordered_map<PositionKey, uint32_t, PositionHash> welded;
  std::vector<std::array<uint32_t, 3>> corners;  // welded corner ids per triangle
  for (const scenes::Primitive& p : mesh.primitives) {
    first.push_back(uint32_t(corners.size()));
    std::vector<uint32_t> weldOf(p.positions.size());
    for (size_t v = 0; v < p.positions.size(); ++v) {
      const glm::vec3 q = p.positions[v] + glm::vec3(0.0f);  // -0 welds with +0
      PositionKey key;
      std::memcpy(key.bits, &q, 12);
      weldOf[v] = welded.emplace(key, uint32_t(welded.size())).first->second;
    }
    for (size_t t = 0; t < p.triangleCount(); ++t) {
      std::array<uint32_t, 3> c{};
      for (int k = 0; k < 3; ++k) {
        const uint32_t i = p.indices[3 * t + size_t(k)];
        c[size_t(k)] = i < weldOf.size() ? weldOf[i] : ~0u;
      }
      corners.push_back(c);
    }
  }
  UnionFind joins(corners.size());
  std::unordered_map<uint64_t, uint32_t> edgeOwner;  // an edge's first triangle
  for (uint32_t t = 0; t < corners.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = corners[t][size_t(k)], b = corners[t][size_t((k + 1) % 3)];
      if (a == ~0u || b == ~0u || a == b) continue;
      if (a > b) std::swap(a, b);
      const auto [it, inserted] = edgeOwner.emplace((uint64_t(a) << 32) | b, t);
      if (!inserted) joins.unite(t, it->second);
    }
  shell.resize(corners.size());
  std::unordered_map<uint32_t, uint32_t> number;
  for (uint32_t t = 0; t < corners.size(); ++t)
    shell[t] = number.emplace(joins.find(t), uint32_t(number.size())).first->second;
  return uint32_t(number.size());
}

// One shell of one static instance, in world space.
struct PlacedShell {
  bool doubleSided = false;   // any of its triangles
  std::vector<std::array<glm::vec3, 3>> triangles;
  glm::vec3 lo{1e30f}, hi{-1e30f};
  glm::vec3 centre() const { return 0.5f * (lo + hi); }
};

// The generalised winding number of a shell's triangles around p: Σ Ω / 4π over its triangles, Ω each
// triangle's signed solid angle (Van Oosterom and Strackee), positive where p sees its back.
double windingNumber(const std::vector<std::array<glm::vec3, 3>>& triangles, glm::vec3 p) {
  double sum = 0.0;
  for (const std::array<glm::vec3, 3>& t : triangles) {
    const glm::dvec3 a = glm::dvec3(t[0] - p), b = glm::dvec3(t[1] - p), c = glm::dvec3(t[2] - p);
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double det = glm::dot(a, glm::cross(b, c));
    const double div = la * lb * lc + glm::dot(a, b) * lc + glm::dot(b, c) * la +
                       glm::dot(c, a) * lb;
    sum += 2.0 * std::atan2(det, div);
  }
  return sum / (4.0 * kPiDouble);
}

bool within(glm::vec3 lo, glm::vec3 hi, const PlacedShell& outer) {
  return glm::all(glm::greaterThanEqual(lo, outer.lo)) && glm::all(glm::lessThanEqual(hi, outer.hi));
}

}  // namespace

LevelObjects::LevelObjects(const scenes::Scene& scene) {
  std::vector<std::vector<uint32_t>> shellOf(scene.meshes.size()), first(scene.meshes.size());
  std::vector<uint32_t> shellCount(scene.meshes.size(), 0);
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    shellCount[m] = meshShells(scene.meshes[m], shellOf[m], first[m]);

  // Every static instance's shells in world space.
  std::vector<PlacedShell> placed;
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    const scenes::Instance& inst = scene.instances[i];
    const scenes::Mesh* mesh = scene.meshOf(inst);
    if (!inst.isStatic || !mesh) continue;
    const size_t m = size_t(inst.mesh), base = placed.size();
    placed.resize(base + shellCount[m]);
    // A mirrored transform turns the winding: glTF then takes clockwise as the front.
    const bool mirrored = glm::determinant(glm::mat3(inst.transform)) < 0.0f;
    scenes::forEachWorldTriangle(scene, inst, [&](size_t p, size_t t, glm::vec3 a, glm::vec3 b,
                                                  glm::vec3 c) {
      if (!finite(a) || !finite(b) || !finite(c)) return;
      PlacedShell& s = placed[base + shellOf[m][first[m][p] + t]];
      s.doubleSided = s.doubleSided || scene.material(mesh->primitives[p].material).doubleSided;
      s.triangles.push_back(mirrored ? std::array<glm::vec3, 3>{a, c, b}
                                     : std::array<glm::vec3, 3>{a, b, c});
      s.lo = glm::min(glm::min(s.lo, a), glm::min(b, c));
      s.hi = glm::max(glm::max(s.hi, a), glm::max(b, c));
    });
  }

  // A double-sided shell around another shell's centre is a room; one around none an object.
  std::vector<uint8_t> room(placed.size(), 0);
  parallelFor(placed.size(), [&](size_t a) {
    const PlacedShell& outer = placed[a];
    if (!outer.doubleSided || outer.triangles.empty()) return;
    for (size_t b = 0; b < placed.size() && !room[a]; ++b) {
      const PlacedShell& inner = placed[b];
      if (b == a || inner.triangles.empty() || !within(inner.lo, inner.hi, outer)) continue;
      room[a] = windingNumber(outer.triangles, inner.centre()) > 0.5;
    }
  }, 4);
  for (size_t a = 0; a < placed.size(); ++a) {
    if (!placed[a].doubleSided || placed[a].triangles.empty()) continue;
    if (room[a]) {
      ++rooms_;
      continue;
    }
    objects_.push_back(Object{std::move(placed[a].triangles), placed[a].lo, placed[a].hi});
  }
}

float LevelObjects::winding(glm::vec3 p) const {
  double most = 0.0;
  for (const Object& o : objects_)
    if (glm::all(glm::greaterThanEqual(p, o.lo)) && glm::all(glm::lessThanEqual(p, o.hi)))
      most = std::max(most, windingNumber(o.triangles, p));
  return float(most);
}

}  // namespace afterglow::probes
