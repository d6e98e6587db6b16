// The camera: the one model of every picture afterglow draws (`render`, its path-traced
// reference, the probe placement's picture). A pinhole view in world space, its primary rays,
// and a loop that fills a picture row by row on the worker threads.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/parallel.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/scenes/scene.h"
#include "afterglow/trace/raytracer.h"

namespace afterglow::trace {

// A pinhole camera in world space.
struct View {
  glm::vec3 position{0.0f};
  glm::vec3 forward{0.0f, 0.0f, -1.0f};  // unit
  glm::vec3 up{0.0f, 1.0f, 0.0f};        // unit, orthogonal to forward
  float yfov = 0.8f;                     // radians, vertical field of view
};

// The view of a glTF camera (camera to world, looking down −Z with +Y up).
View cameraView(const scenes::Camera& camera);
// A view from `from` toward `at`, +Y up (or +Z when looking straight up or down).
View lookAtView(glm::vec3 from, glm::vec3 at, float yfov);
// A view of the whole scene from above its −Z side, for scenes without cameras.
View defaultView(const scenes::Scene& scene, float yfov);

// Primary rays of a pinhole view, shared by every picture so that a baked and a path-traced
// picture see exactly the same geometry through the same pixels.
class PinholeCamera {
 public:
  PinholeCamera(const View& view, int width, int height)
      : view_(view),
        right_(glm::normalize(glm::cross(view.forward, view.up))),
        tanHalf_(std::tan(view.yfov * 0.5f)),
        aspect_(float(width) / float(height)),
        width_(float(width)),
        height_(float(height)) {}

  // The ray through picture point (x, y), in pixels from the top-left corner (pixel centres at
  // +0.5).
  Ray ray(float x, float y) const {
    const float cx = (2.0f * (x / width_) - 1.0f) * tanHalf_ * aspect_;
    const float cy = (1.0f - 2.0f * (y / height_)) * tanHalf_;
    Ray r;
    r.origin = view_.position;
    r.direction = glm::normalize(view_.forward + cx * right_ + cy * view_.up);
    return r;
  }

 private:
  View view_;
  glm::vec3 right_;
  float tanHalf_, aspect_, width_, height_;
};

// The primary ray through picture point (x, y) of a width × height view (PinholeCamera::ray).
Ray cameraRay(const View& view, int width, int height, float x, float y);

// Fills a width × height picture with shade(camera, px, py), row 0 at the top: rows in parallel
// (one row per task, so progress moves per row), stopping between pixels once progress is
// cancelled (a path-traced row at many samples per pixel takes a while).
template <class Shade>
Result<std::vector<glm::vec3>> renderPixels(const View& view, int width, int height,
                                            const char* stage, Progress& progress,
                                            const Shade& shade) {
  if (width <= 0 || height <= 0) return Status::error("render: the image size must be positive");
  const PinholeCamera camera(view, width, height);
  std::vector<glm::vec3> image(size_t(width) * size_t(height), glm::vec3(0.0f));
  progress.begin(stage, size_t(height));
  parallelFor(size_t(height), [&](size_t row) {
    for (int px = 0; px < width; ++px) {
      if (progress.cancelled()) return;
      image[row * size_t(width) + size_t(px)] = shade(camera, px, int(row));
    }
    progress.advance();
  }, 1);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  return image;
}

}  // namespace afterglow::trace
