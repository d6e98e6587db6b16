#include "afterglow/trace/camera.h"

namespace afterglow::trace {

Ray cameraRay(const View& view, int width, int height, float x, float y) {
  return PinholeCamera(view, width, height).ray(x, y);
}

View cameraView(const scenes::Camera& camera) {
  View v;
  v.position = glm::vec3(camera.transform * glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
  v.forward = glm::normalize(glm::vec3(camera.transform * glm::vec4(0.0f, 0.0f, -1.0f, 0.0f)));
  glm::vec3 up = glm::vec3(camera.transform * glm::vec4(0.0f, 1.0f, 0.0f, 0.0f));
  up -= v.forward * glm::dot(up, v.forward);
  v.up = glm::length(up) > 1e-6f ? glm::normalize(up) : glm::vec3(0.0f, 1.0f, 0.0f);
  v.yfov = camera.perspective ? camera.yfov : 0.8f;
  return v;
}

View lookAtView(glm::vec3 from, glm::vec3 at, float yfov) {
  View v;
  v.position = from;
  glm::vec3 f = at - from;
  v.forward = glm::length(f) > 0.0f ? glm::normalize(f) : glm::vec3(0.0f, 0.0f, -1.0f);
  glm::vec3 up(0.0f, 1.0f, 0.0f);
  if (std::abs(glm::dot(up, v.forward)) > 0.999f) up = glm::vec3(0.0f, 0.0f, 1.0f);
  v.up = glm::normalize(up - v.forward * glm::dot(up, v.forward));
  v.yfov = yfov;
  return v;
}

View defaultView(const scenes::Scene& scene, float yfov) {
  const scenes::Bounds b = scene.bounds();
  if (b.empty()) return lookAtView(glm::vec3(0.0f, 0.0f, 1.0f), glm::vec3(0.0f), yfov);
  const glm::vec3 centre = (b.min + b.max) * 0.5f;
  const float radius = glm::length(b.size()) * 0.5f;
  const float distance = radius / std::tan(yfov * 0.5f) * 1.1f;
  // From above and to the side, so floors and walls both show.
  return lookAtView(centre + glm::normalize(glm::vec3(0.4f, 0.6f, -1.0f)) * distance, centre, yfov);
}

}  // namespace afterglow::trace
