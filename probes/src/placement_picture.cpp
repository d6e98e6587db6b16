#include "afterglow/probes/placement_picture.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "afterglow/baker/raytracer.h"
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

std::vector<glm::vec3> placementPicture(const scenes::Scene& scene,
                                        const baker::RayTracer& tracer, const Placement& placement,
                                        int levels, const baker::View& view, int width,
                                        int height) {
  std::vector<glm::vec3> image(size_t(width) * size_t(height), glm::vec3(0.02f));
  std::vector<float> depth(image.size(), std::numeric_limits<float>::infinity());
  // The scene: base colour under a headlight (dimmed, so the dots stand out).
  parallelFor(size_t(height), [&](size_t y) {
    for (int x = 0; x < width; ++x) {
      const baker::Ray ray =
          baker::cameraRay(view, width, height, float(x) + 0.5f, float(y) + 0.5f);
      const baker::Hit hit = tracer.intersect(ray);
      if (!hit.valid()) continue;
      const scenes::Material& m = tracer.material(hit);
      const float facing = std::abs(glm::dot(hit.geometricNormal, ray.direction));
      const size_t i = y * size_t(width) + size_t(x);
      image[i] = glm::vec3(m.baseColorFactor) * (0.08f + 0.3f * facing);
      depth[i] = hit.t;
    }
  }, 1);
  // The probes, far ones first so near ones cover them: a dot of a fifth of the finest spacing,
  // 1.5 to 4 pixels across whatever its distance (so a probe next to the camera does not hide
  // the view), hidden where the surface seen there is nearer than the probe.
  const glm::vec3 right = glm::normalize(glm::cross(view.forward, view.up));
  const float tanHalf = std::tan(0.5f * view.yfov), aspect = float(width) / float(height);
  const float radiusWorld = 0.1f * placement.spacing / float(1 << std::min(levels, 8));
  std::vector<size_t> order(placement.positions.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto distance = [&](size_t i) {
    return glm::dot(placement.positions[i] - view.position, view.forward);
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return distance(a) > distance(b); });
  for (size_t i : order) {
    const glm::vec3 d = placement.positions[i] - view.position;
    const float z = glm::dot(d, view.forward);
    if (!(z > 1e-3f)) continue;
    const float sx = glm::dot(d, right) / (z * tanHalf * aspect);
    const float sy = glm::dot(d, view.up) / (z * tanHalf);
    const float px = (sx * 0.5f + 0.5f) * float(width), py = (0.5f - sy * 0.5f) * float(height);
    const float r =
        std::clamp(radiusWorld / (z * tanHalf) * 0.5f * float(height), 1.5f, 4.0f);
    const float along = glm::length(d);
    // The PNG's tone curve is x / (1 + x): stored as its inverse, the dot shows its colour.
    const glm::vec3 shown = glm::min(probeKindColour(placement.kinds[i]), glm::vec3(0.9f));
    const glm::vec3 colour = shown / (1.0f - shown);
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
