#include "afterglow/preview/probe_spheres.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "afterglow/trace/raytracer.h"
#include "afterglow/trace/camera.h"
#include "afterglow/core/parallel.h"

namespace afterglow::preview {

namespace {

constexpr float kAllRadius = 0.2f;       // × the median spacing, every probe
constexpr float kHandfulRadius = 0.4f;   // × the median spacing, a handful
constexpr float kWallGap = 0.9f;         // × the distance to the nearest surface found
constexpr float kMaxRadiusPx = 1.0f / 8.0f;  // × the picture's height
constexpr float kBigRadiusPx = 1.0f / 30.0f; // × the picture's height
constexpr float kMinRadiusPx = 2.0f;         // pixels

// Where a sphere lands on a pinhole picture (the camera model of render.cpp's PinholeCamera).
class Projector {
 public:
  Projector(const trace::View& view, int width, int height)
      : eye_(view.position),
        forward_(view.forward),
        up_(view.up),
        right_(glm::normalize(glm::cross(view.forward, view.up))),
        tanHalf_(std::tan(view.yfov * 0.5f)),
        aspect_(float(width) / float(height)),
        width_(float(width)),
        height_(float(height)) {}

  struct Box {
    float x0 = 0.0f, x1 = 0.0f, y0 = 0.0f, y1 = 0.0f;  // pixels, top-left origin
    bool straddles = false;  // crosses the camera's plane: anywhere on the picture
    bool behind = false;     // wholly behind the camera: nowhere
  };

  // The picture rectangle holding the sphere's outline: per axis, the two tangents from the eye
  // to the circle the sphere projects to in that axis' plane with the view direction.
  Box box(glm::vec3 centre, float radius) const {
    const glm::vec3 d = centre - eye_;
    const float z = glm::dot(d, forward_);
    Box b;
    if (z <= -radius) {
      b.behind = true;
      return b;
    }
    if (z <= radius * 1.001f) {
      b.straddles = true;
      b.x1 = width_;
      b.y1 = height_;
      return b;
    }
    float sx0, sx1, sy0, sy1;
    tangents(glm::dot(d, right_), z, radius, &sx0, &sx1);
    tangents(glm::dot(d, up_), z, radius, &sy0, &sy1);
    b.x0 = (sx0 / (tanHalf_ * aspect_) * 0.5f + 0.5f) * width_;
    b.x1 = (sx1 / (tanHalf_ * aspect_) * 0.5f + 0.5f) * width_;
    b.y0 = (0.5f - sy1 / tanHalf_ * 0.5f) * height_;
    b.y1 = (0.5f - sy0 / tanHalf_ * 0.5f) * height_;
    return b;
  }

  // The picture point of a point in front of the camera.
  glm::vec2 point(glm::vec3 p) const {
    const glm::vec3 d = p - eye_;
    const float z = glm::dot(d, forward_);
    return {(glm::dot(d, right_) / (z * tanHalf_ * aspect_) * 0.5f + 0.5f) * width_,
            (0.5f - glm::dot(d, up_) / (z * tanHalf_) * 0.5f) * height_};
  }

  glm::vec3 eye() const { return eye_; }

 private:
  // The slopes a/z of the two lines through the origin tangent to the circle of radius r at
  // (a, z), z > r: the roots of s²(z² − r²) − 2azs + a² − r² = 0.
  static void tangents(float a, float z, float r, float* lo, float* hi) {
    const double A = a, Z = z, R = r;
    const double root = R * std::sqrt(std::max(0.0, A * A + Z * Z - R * R));
    const double den = Z * Z - R * R;
    *lo = float((A * Z - root) / den);
    *hi = float((A * Z + root) / den);
  }

  glm::vec3 eye_, forward_, up_, right_;
  float tanHalf_, aspect_, width_, height_;
};

// The 26 directions to a cube's faces, edges and corners from its centre.
std::vector<glm::vec3> clearanceDirections() {
  std::vector<glm::vec3> out;
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x)
        if (x != 0 || y != 0 || z != 0)
          out.push_back(glm::normalize(glm::vec3(float(x), float(y), float(z))));
  return out;
}

// `radius`, or kWallGap × the nearest surface the clearance rays meet if that is less.
float clearRadius(const trace::RayTracer& tracer, glm::vec3 centre, float radius) {
  static const std::vector<glm::vec3> directions = clearanceDirections();
  float nearest = radius / kWallGap;
  for (const glm::vec3& dir : directions) {
    trace::Ray ray;
    ray.origin = centre;
    ray.direction = dir;
    ray.tfar = nearest;
    const trace::Hit hit = tracer.intersect(ray);
    if (hit.valid()) nearest = std::min(nearest, hit.t);
  }
  return std::min(radius, kWallGap * nearest);
}

// A sphere lit by the probes at its centre (their SH and directions, interpolated from hint).
ProbeSphere litSphere(const bakefiles::LightProbes& probes, glm::vec3 centre, float radius,
                      int hint) {
  ProbeSphere s;
  s.centre = centre;
  s.radius = radius;
  runtime::ProbeLighting lighting = probes.sample(centre, hint);
  s.sh = lighting.sh;
  s.directions = std::move(lighting.lights);
  s.window = probes.deringWindow;
  return s;
}

// One candidate of a handful: where it lands on the picture and how big it looks.
struct Candidate {
  int probe;
  float radius;      // world
  glm::vec2 centre;  // pixels
  float radiusPx;
};

// Farthest-point picks over `pool` (in probe order), adding to `picked` until it holds `count`.
// The picture's edges count as picked at half the distance (as a grid's cells have their
// centres half a step from its border): plain farthest-point picks crowd the edges and corners.
// Each candidate keeps its distance to the nearest pick, updated per pick: O(count × pool).
void pickSpread(const std::vector<Candidate>& pool, glm::vec2 pictureSize, size_t count,
                std::vector<Candidate>& picked) {
  const glm::vec2 pictureCentre = 0.5f * pictureSize;
  std::vector<float> nearest(pool.size(), std::numeric_limits<float>::infinity());
  std::vector<bool> used(pool.size(), false);  // picked, or overlapping a pick
  auto take = [&](const Candidate& p) {
    for (size_t i = 0; i < pool.size(); ++i) {
      const float d = glm::length(pool[i].centre - p.centre);
      nearest[i] = std::min(nearest[i], d);
      // Once it overlaps a pick it always will.
      if (d <= pool[i].radiusPx + p.radiusPx + 1.0f) used[i] = true;
    }
  };
  for (const Candidate& p : picked) take(p);
  while (picked.size() < count) {
    int best = -1;
    float bestScore = 0.0f;
    for (size_t i = 0; i < pool.size(); ++i) {
      if (used[i]) continue;
      const Candidate& c = pool[i];
      // Nothing picked yet: the one nearest the centre (the largest negated distance).
      const glm::vec2 edge = glm::min(c.centre, pictureSize - c.centre);
      const float score = picked.empty() ? -glm::length(c.centre - pictureCentre)
                                         : std::min(nearest[i], 2.0f * std::min(edge.x, edge.y));
      // Ties (spheres one behind another on the picture) go to the larger, then the first.
      if (best < 0 || score > bestScore ||
          (score == bestScore && c.radiusPx > pool[size_t(best)].radiusPx)) {
        best = int(i);
        bestScore = score;
      }
    }
    if (best < 0) return;
    picked.push_back(pool[size_t(best)]);
    take(picked.back());
  }
}

}  // namespace

std::vector<float> nearestProbeDistances(const runtime::ProbeTetrahedra& mesh) {
  const size_t n = mesh.positions.size();
  std::vector<float> nearest(n, std::numeric_limits<float>::infinity());
  auto edge = [&](int a, int b) {
    const float d = glm::length(mesh.positions[size_t(a)] - mesh.positions[size_t(b)]);
    nearest[size_t(a)] = std::min(nearest[size_t(a)], d);
    nearest[size_t(b)] = std::min(nearest[size_t(b)], d);
  };
  if (!mesh.tetrahedra.empty()) {
    for (const glm::ivec4& t : mesh.tetrahedra)
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
          if (t[i] >= 0 && t[j] >= 0 && size_t(t[i]) < n && size_t(t[j]) < n) edge(t[i], t[j]);
  } else {
    for (size_t a = 0; a < n; ++a)
      for (size_t b = a + 1; b < n; ++b) edge(int(a), int(b));
  }
  return nearest;
}

float medianProbeSpacing(const runtime::ProbeTetrahedra& mesh) {
  // Probes in no tetrahedron (duplicates) have no edge and no say.
  std::vector<float> found;
  for (float d : nearestProbeDistances(mesh))
    if (std::isfinite(d) && d > 0.0f) found.push_back(d);
  if (found.empty()) return 0.0f;
  std::nth_element(found.begin(), found.begin() + std::ptrdiff_t(found.size() / 2), found.end());
  return found[found.size() / 2];
}

Result<std::vector<ProbeSphere>> chooseProbeSpheres(const trace::RayTracer& tracer,
                                                    const bakefiles::LightProbes& probes, const trace::View& view,
                                                    int width, int height, int count) {
  const size_t n = probes.mesh.positions.size();
  if (probes.sh.size() != n)
    return Status::error(format("%zu probe SH for %zu probe positions", probes.sh.size(), n));
  if (n == 0 || width <= 0 || height <= 0) return std::vector<ProbeSphere>();
  float spacing = medianProbeSpacing(probes.mesh);
  if (!(spacing > 0.0f)) {
    // A single probe (or all at one point): a size from the level instead.
    const scenes::Bounds b = tracer.bounds();
    spacing = b.empty() ? 1.0f : std::max(0.05f * glm::length(b.size()), 1e-3f);
  }
  // A handful of spheres take their size from their own probe's neighbours: a probe of the
  // coarse grid in the open gets a sphere that shows, one of the refined probes by a wall a
  // small one (the median is a refined probe's spacing in most levels).
  const std::vector<float> own =
      count == 0 ? std::vector<float>() : nearestProbeDistances(probes.mesh);
  auto baseRadius = [&](size_t i) {
    if (count == 0) return kAllRadius * spacing;
    return kHandfulRadius * (std::isfinite(own[i]) && own[i] > 0.0f ? own[i] : spacing);
  };
  const Projector projector(view, width, height);
  const float w = float(width), h = float(height);
  auto onPicture = [&](const Projector::Box& b) {
    return !b.behind && b.x1 > 0.0f && b.x0 < w && b.y1 > 0.0f && b.y0 < h;
  };

  // Only probes whose sphere may show are shrunk away from walls (each costs 26 rays).
  std::vector<int> shown;
  for (size_t i = 0; i < n; ++i)
    if (onPicture(projector.box(probes.mesh.positions[i], baseRadius(i)))) shown.push_back(int(i));
  std::vector<float> radius(shown.size());
  parallelFor(shown.size(), [&](size_t k) {
    const size_t i = size_t(shown[k]);
    radius[k] = clearRadius(tracer, probes.mesh.positions[i], baseRadius(i));
  }, 16);

  std::vector<Candidate> picked;
  if (count == 0) {
    for (size_t k = 0; k < shown.size(); ++k)
      if (radius[k] > 0.0f) picked.push_back({shown[k], radius[k], glm::vec2(0.0f), 0.0f});
  } else {
    std::vector<Candidate> big, small;
    std::vector<char> visible(shown.size(), 0);
    parallelFor(shown.size(), [&](size_t k) {
      const glm::vec3 c = probes.mesh.positions[size_t(shown[k])];
      const glm::vec3 d = c - projector.eye();
      const float distance = glm::length(d);
      if (!(radius[k] > 0.0f) || distance <= radius[k]) return;
      trace::Ray ray;
      ray.origin = projector.eye();
      ray.direction = d / distance;
      ray.tfar = distance - radius[k];
      visible[k] = !tracer.occluded(ray);
    }, 16);
    for (size_t k = 0; k < shown.size(); ++k) {
      if (!visible[k]) continue;
      const glm::vec3 c = probes.mesh.positions[size_t(shown[k])];
      const Projector::Box b = projector.box(c, radius[k]);
      if (b.behind || b.straddles || b.x0 < 0.0f || b.y0 < 0.0f || b.x1 > w || b.y1 > h) continue;
      const float r = 0.5f * std::max(b.x1 - b.x0, b.y1 - b.y0);
      if (r > kMaxRadiusPx * h || r < kMinRadiusPx) continue;
      const Candidate cand{shown[k], radius[k], projector.point(c), r};
      (r >= kBigRadiusPx * h ? big : small).push_back(cand);
    }
    pickSpread(big, glm::vec2(w, h), size_t(count), picked);
    pickSpread(small, glm::vec2(w, h), size_t(count), picked);
  }

  // A tetrahedron at each probe, to start the point location's walk next to it.
  std::vector<int> hint(n, 0);
  for (size_t t = probes.mesh.tetrahedra.size(); t-- > 0;)
    for (int k = 0; k < 4; ++k) {
      const int v = probes.mesh.tetrahedra[t][k];
      if (v >= 0 && size_t(v) < n) hint[size_t(v)] = int(t);
    }
  std::vector<ProbeSphere> spheres(picked.size());
  parallelFor(picked.size(), [&](size_t i) {
    ProbeSphere& s = spheres[i];
    const int probe = picked[i].probe;
    s = litSphere(probes, probes.mesh.positions[size_t(probe)], picked[i].radius, hint[size_t(probe)]);
    s.probe = probe;
  }, 64);
  return spheres;
}

ProbeSphere sphereAt(const bakefiles::LightProbes& probes, glm::vec3 centre, float radius) {
  return litSphere(probes, centre, radius, 0);
}

ProbeSphereIndex::ProbeSphereIndex(const std::vector<ProbeSphere>& spheres, const trace::View& view,
                                   int width, int height)
    : spheres_(spheres),
      tilesX_((std::max(width, 1) + kTile - 1) / kTile),
      tilesY_((std::max(height, 1) + kTile - 1) / kTile),
      tiles_(size_t(tilesX_) * size_t(tilesY_)) {
  const Projector projector(view, width, height);
  for (size_t i = 0; i < spheres_.size(); ++i) {
    const ProbeSphere& s = spheres_[i];
    if (!(s.radius > 0.0f) || glm::length(s.centre - view.position) <= s.radius) continue;
    const Projector::Box b = projector.box(s.centre, s.radius);
    if (b.behind) continue;
    // A pixel of margin: the box is exact, but rounding must not cut a sphere's edge. Clamped
    // to the picture before the conversion to int (a sphere just in front of the eye spans far
    // beyond it).
    auto tile = [](float pixels, float size, int tiles) {
      return std::clamp(int(std::floor(std::clamp(pixels, -1.0f, size + 1.0f))) / kTile, 0,
                        tiles - 1);
    };
    const int x0 = tile(b.x0 - 1.0f, float(width), tilesX_);
    const int x1 = tile(b.x1 + 1.0f, float(width), tilesX_);
    const int y0 = tile(b.y0 - 1.0f, float(height), tilesY_);
    const int y1 = tile(b.y1 + 1.0f, float(height), tilesY_);
    for (int ty = y0; ty <= y1; ++ty)
      for (int tx = x0; tx <= x1; ++tx)
        tiles_[size_t(ty) * size_t(tilesX_) + size_t(tx)].push_back(uint32_t(i));
  }
}

bool ProbeSphereIndex::shade(const trace::Ray& ray, int px, int py, float tMax,
                             glm::vec3* radiance) const {
  const int tx = px / kTile, ty = py / kTile;
  if (px < 0 || py < 0 || tx >= tilesX_ || ty >= tilesY_) return false;
  const glm::vec3 d = ray.direction;  // a camera ray's: unit, so t and tMax are distances
  float nearest = tMax;
  int hit = -1;
  for (uint32_t i : tiles_[size_t(ty) * size_t(tilesX_) + size_t(tx)]) {
    const ProbeSphere& s = spheres_[i];
    const glm::vec3 oc = ray.origin - s.centre;
    const float b = glm::dot(oc, d);
    // The squared distance from the centre to the ray's line, not b² − (|oc|² − r²): that
    // difference of large numbers loses the sphere of a far probe to rounding.
    const glm::vec3 across = oc - b * d;
    const float discriminant = s.radius * s.radius - glm::dot(across, across);
    if (discriminant < 0.0f || glm::dot(oc, oc) <= s.radius * s.radius) continue;
    const float t = -b - std::sqrt(discriminant);
    if (t > 0.0f && t < nearest) {
      nearest = t;
      hit = int(i);
    }
  }
  if (hit < 0) return false;
  const ProbeSphere& s = spheres_[size_t(hit)];
  const glm::vec3 position = ray.origin + nearest * d;
  const glm::vec3 normal = glm::normalize(position - s.centre);
  // The L2 series rings below zero opposite a strong light; no surface reflects less than
  // nothing.
  const runtime::ProbeLighting lighting{s.sh, s.directions};
  const glm::vec3 irradiance = glm::max(lighting.irradianceOverPi(normal, s.window), 0.0f);
  if (s.finish == SphereFinish::Diffuse) {
    *radiance = kProbeSphereAlbedo * irradiance;
    return true;
  }
  const float roughness = s.finish == SphereFinish::Mirror ? 0.0f : kRoughMetalRoughness;
  *radiance = reflections_ ? reflections_->specular(position, normal, -d, kMetalSphereF0,
                                                    roughness, &irradiance)
                           : glm::vec3(0.0f);
  return true;
}

}  // namespace afterglow::preview
