#include "afterglow/probes/placement_picture.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "afterglow/trace/raytracer.h"
#include "afterglow/core/parallel.h"

namespace afterglow::probes {

glm::vec3 probeKindColour(ProbeKind kind) {
  switch (kind) {
    case ProbeKind::Grid: return {0.9f, 0.9f, 0.9f};
    case ProbeKind::Refined: return {0.0f, 0.75f, 0.9f};
    case ProbeKind::Moved: return {0.9f, 0.45f, 0.05f};
    case ProbeKind::Pinned: return {0.9f, 0.0f, 0.85f};
  }
  return glm::vec3(1.0f);
}

glm::vec3 reflectionBoxColour() { return {0.95f, 0.85f, 0.1f}; }

std::vector<glm::vec3> placementPicture(const scenes::Scene& scene,
                                        const trace::RayTracer& tracer, const Placement& placement,
                                        int levels, const trace::View& view, int width,
                                        int height,
                                        const std::vector<ReflectionProbeEntry>& reflections) {
  std::vector<glm::vec3> image(size_t(width) * size_t(height), glm::vec3(0.02f));
  std::vector<float> depth(image.size(), std::numeric_limits<float>::infinity());
  // The scene: base colour under a headlight (dimmed, so the dots stand out).
  parallelFor(size_t(height), [&](size_t y) {
    for (int x = 0; x < width; ++x) {
      const trace::Ray ray =
          trace::cameraRay(view, width, height, float(x) + 0.5f, float(y) + 0.5f);
      const trace::Hit hit = tracer.intersect(ray);
      if (!hit.valid()) continue;
      const scenes::Material& m = tracer.material(hit);
      const float facing = std::abs(glm::dot(hit.geometricNormal, ray.direction));
      const size_t i = y * size_t(width) + size_t(x);
      image[i] = glm::vec3(m.baseColorFactor) * (0.08f + 0.3f * facing);
      depth[i] = hit.t;
    }
  }, 1);
  const glm::vec3 right = glm::normalize(glm::cross(view.forward, view.up));
  const float tanHalf = std::tan(0.5f * view.yfov), aspect = float(width) / float(height);
  // The PNG's tone curve is x / (1 + x): a colour stored as its inverse shows as itself.
  auto shownAs = [](glm::vec3 c) {
    const glm::vec3 shown = glm::min(c, glm::vec3(0.9f));
    return shown / (1.0f - shown);
  };
  // Where a world point lands: pixel coordinates and its distance from the camera; false behind
  // the camera.
  auto project = [&](glm::vec3 p, glm::vec2* pixel, float* along) {
    const glm::vec3 d = p - view.position;
    const float z = glm::dot(d, view.forward);
    if (!(z > 1e-3f)) return false;
    const float sx = glm::dot(d, right) / (z * tanHalf * aspect);
    const float sy = glm::dot(d, view.up) / (z * tanHalf);
    *pixel = glm::vec2((sx * 0.5f + 0.5f) * float(width), (0.5f - sy * 0.5f) * float(height));
    *along = glm::length(d);
    return true;
  };

  // The reflection probes' boxes first, so the probes' dots stay on top: each edge sampled
  // about once a pixel, two pixels wide, full colour where nothing nearer is seen there, dim
  // where a surface hides it (a room's box lies just inside its walls, so a little slack).
  const glm::vec3 boxColour = shownAs(reflectionBoxColour());
  const glm::vec3 hiddenColour = shownAs(0.3f * reflectionBoxColour());
  for (const ReflectionProbeEntry& r : reflections) {
    const glm::vec3 lo = r.position - 0.5f * r.size, hi = r.position + 0.5f * r.size;
    auto corner = [&](int c) {
      return glm::vec3(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
    };
    for (int a = 0; a < 8; ++a)
      for (int bit = 1; bit <= 4; bit <<= 1) {
        if (a & bit) continue;
        const glm::vec3 p0 = corner(a), p1 = corner(a | bit);
        glm::vec2 s0, s1;
        float d0, d1;
        // The edge's length on screen decides its samples; an end behind the camera counts
        // as long (such an edge is sampled finely and its hidden samples skipped).
        const bool both = project(p0, &s0, &d0) && project(p1, &s1, &d1);
        const float pixels = both ? glm::length(s1 - s0) : float(width + height);
        const int steps = int(std::min(4.0f * float(width + height), std::ceil(pixels))) + 1;
        for (int k = 0; k <= steps; ++k) {
          const glm::vec3 p = glm::mix(p0, p1, float(k) / float(steps));
          glm::vec2 s;
          float along;
          if (!project(p, &s, &along)) continue;
          for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
              const int x = int(std::floor(s.x - 0.5f)) + dx, y = int(std::floor(s.y - 0.5f)) + dy;
              if (x < 0 || y < 0 || x >= width || y >= height) continue;
              const size_t i = size_t(y) * size_t(width) + size_t(x);
              const bool hidden = depth[i] < along * 0.99f - 1e-3f;
              image[i] = hidden ? glm::max(image[i], hiddenColour) : boxColour;
            }
        }
      }
  }

  // The probes, far ones first so near ones cover them: a dot of a fifth of the finest spacing,
  // 1.5 to 4 pixels across whatever its distance (so a probe next to the camera does not hide
  // the view), hidden where the surface seen there is nearer than the probe.
  const float radiusWorld = 0.1f * placement.spacing / float(1 << std::min(levels, 8));
  // The reflection probes' capture positions come after the light probes, drawn alike.
  std::vector<glm::vec3> dots = placement.positions;
  for (const ReflectionProbeEntry& r : reflections) dots.push_back(r.position);
  std::vector<size_t> order(dots.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto distance = [&](size_t i) { return glm::dot(dots[i] - view.position, view.forward); };
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return distance(a) > distance(b); });
  const size_t lightProbes = placement.positions.size();
  for (size_t i : order) {
    const glm::vec3 d = dots[i] - view.position;
    const float z = glm::dot(d, view.forward);
    if (!(z > 1e-3f)) continue;
    const float sx = glm::dot(d, right) / (z * tanHalf * aspect);
    const float sy = glm::dot(d, view.up) / (z * tanHalf);
    const float px = (sx * 0.5f + 0.5f) * float(width), py = (0.5f - sy * 0.5f) * float(height);
    // A reflection probe's dot is larger: there are few, and each stands for a whole box.
    const float r = i < lightProbes
                        ? std::clamp(radiusWorld / (z * tanHalf) * 0.5f * float(height), 1.5f, 4.0f)
                        : 5.0f;
    const float along = glm::length(d);
    const glm::vec3 colour =
        shownAs(i < lightProbes ? probeKindColour(placement.kinds[i]) : reflectionBoxColour());
    for (int y = int(std::floor(py - r)); y <= int(std::ceil(py + r)); ++y)
      for (int x = int(std::floor(px - r)); x <= int(std::ceil(px + r)); ++x) {
        if (x < 0 || y < 0 || x >= width || y >= height) continue;
        const float dx = float(x) + 0.5f - px, dy = float(y) + 0.5f - py;
        if (dx * dx + dy * dy > r * r) continue;
        const size_t k = size_t(y) * size_t(width) + size_t(x);
        // depth holds the hit's ray parameter along a unit direction: a distance.
        if (depth[k] < along) continue;
        // A darker rim, so neighbouring dots stay apart.
        image[k] = (dx * dx + dy * dy > 0.6f * r * r) ? colour * 0.2f : colour;
      }
  }
  return image;
}

}  // namespace afterglow::probes
