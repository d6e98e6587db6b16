#include <algorithm>
#include <cmath>

#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

void resolveAtlas(const AtlasLayout& layout, const std::vector<glm::vec3>& texelValues,
                  std::vector<glm::vec3>& image) {
  const size_t pixels = size_t(layout.width) * size_t(layout.height);
  image.assign(pixels, glm::vec3(0.0f));
  const size_t mapped = std::min(pixels, layout.texelOfPixel.size());
  for (size_t p = 0; p < mapped; ++p) {
    const uint32_t t = layout.texelOfPixel[p];
    if (t < texelValues.size()) image[p] = texelValues[t];
  }
  for (size_t i = 0; i + 1 < layout.mixStart.size() && i < layout.mixPixel.size(); ++i) {
    const uint32_t p = layout.mixPixel[i];
    if (p >= pixels) continue;
    glm::vec3 sum(0.0f);
    for (uint32_t k = layout.mixStart[i]; k < layout.mixStart[i + 1]; ++k)
      if (layout.mixTexel[k] < texelValues.size())
        sum += layout.mixWeight[k] * texelValues[layout.mixTexel[k]];
    image[p] = sum;
  }
}

void SparseLinks::appendRow(const uint32_t* targets, const float* weights, size_t n) {
  float largest = 0.0f;
  for (size_t i = 0; i < n; ++i) largest = std::max(largest, weights[i]);
  const float scale = largest > 0.0f ? largest / 65535.0f : 0.0f;
  rowScale.push_back(scale);
  for (size_t i = 0; i < n && scale > 0.0f; ++i) {
    const float q = std::round(weights[i] / scale);
    if (!(q >= 1.0f)) continue;
    target.push_back(targets[i]);
    weight.push_back(uint16_t(std::min(q, 65535.0f)));
  }
  rowStart.push_back(uint32_t(target.size()));
}

}  // namespace afterglow::runtime
