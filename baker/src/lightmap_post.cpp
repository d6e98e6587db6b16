#include "lightmap_post.h"

#include <utility>

namespace afterglow::baker {

namespace {

// One Jacobi pass: pixels in state `from` with at least one valid neighbour become the average
// of those neighbours and turn valid. Reads a snapshot so the order of visits does not matter.
size_t growPass(int width, int height, std::vector<glm::vec3>& image, std::vector<uint8_t>& state,
                uint8_t from) {
  const std::vector<uint8_t> before = state;
  std::vector<std::pair<size_t, glm::vec3>> filled;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t p = size_t(y) * size_t(width) + size_t(x);
      if (before[p] != from) continue;
      glm::vec3 sum(0.0f);
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
          const size_t q = size_t(ny) * size_t(width) + size_t(nx);
          if (before[q] != kPixelValid) continue;
          sum += image[q];
          ++n;
        }
      }
      if (n > 0) filled.emplace_back(p, sum / float(n));
    }
  }
  for (const auto& [p, value] : filled) {
    image[p] = value;
    state[p] = kPixelValid;
  }
  return filled.size();
}

}  // namespace

size_t fillInvalidPixels(int width, int height, std::vector<glm::vec3>& image,
                         std::vector<uint8_t>& state) {
  size_t total = 0;
  for (;;) {
    const size_t n = growPass(width, height, image, state, kPixelInvalid);
    if (n == 0) break;
    total += n;
  }
  return total;
}

size_t dilatePixels(int width, int height, std::vector<glm::vec3>& image,
                    std::vector<uint8_t>& state, int radius) {
  size_t total = 0;
  for (int r = 0; r < radius; ++r) {
    const size_t n = growPass(width, height, image, state, kPixelEmpty);
    if (n == 0) break;
    total += n;
  }
  return total;
}

}  // namespace afterglow::baker
