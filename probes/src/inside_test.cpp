#include "inside_test.h"

#include <algorithm>
#include <cmath>

#include "afterglow/core/math.h"

namespace afterglow::probes {

std::vector<glm::vec3> sphereDirections(int n) {
  std::vector<glm::vec3> out;
  const float golden = kPi * (3.0f - std::sqrt(5.0f));
  for (int i = 0; i < n; ++i) {
    const float z = 1.0f - (2.0f * float(i) + 1.0f) / float(n);
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const float phi = golden * float(i) + 0.3f;
    glm::vec3 d(r * std::cos(phi), r * std::sin(phi), z);
    // A fixed tilt about x then y.
    const float a = 0.17f, b = 0.11f;
    d = glm::vec3(d.x, std::cos(a) * d.y - std::sin(a) * d.z, std::sin(a) * d.y + std::cos(a) * d.z);
    d = glm::vec3(std::cos(b) * d.x + std::sin(b) * d.z, d.y, -std::sin(b) * d.x + std::cos(b) * d.z);
    out.push_back(glm::normalize(d));
  }
  return out;
}

InsideTest::InsideTest(const scenes::Scene& scene, const trace::RayTracer& tracer,
                       float backFraction)
    : scene_(scene), tracer_(tracer), backFraction_(backFraction), objects_(scene) {
  for (const scenes::Instance& inst : scene.instances) allStatic_ = allStatic_ && inst.isStatic;
}

void InsideTest::firstHits(glm::vec3 p, const std::vector<glm::vec3>& directions,
                           std::vector<trace::Hit>& hits) const {
  const size_t n = directions.size();
  std::vector<trace::Ray> rays(n);
  hits.resize(n);
  for (size_t i = 0; i < n; ++i) {
    rays[i].origin = p;
    rays[i].direction = directions[i];
  }
  tracer_.intersect(rays.data(), hits.data(), n);
  if (allStatic_) return;
  for (size_t i = 0; i < n; ++i) {
    trace::Hit& hit = hits[i];
    // Dynamic objects are no walls: look past them.
    for (int guard = 0; hit.valid() && guard < 16 && !scene_.instances[hit.instance].isStatic;
         ++guard) {
      trace::Ray next = rays[i];
      next.tnear = hit.t + 1e-5f * (1.0f + hit.t);
      hit = tracer_.intersect(next);
    }
    if (hit.valid() && !scene_.instances[hit.instance].isStatic) hit = trace::Hit();
  }
}

Sight InsideTest::judge(glm::vec3 p, const std::vector<trace::Hit>& hits) const {
  size_t back = 0;
  for (const trace::Hit& hit : hits)
    back += hit.valid() && !hit.frontFace && !tracer_.material(hit).doubleSided;
  return Sight{float(back) / float(std::max<size_t>(hits.size(), 1)), objects_.winding(p)};
}

}  // namespace afterglow::probes
