// AtlasLayout: where texels sit in a lightmap atlas and how their values become its image.
// GLM and the standard library only.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace afterglow::runtime {

constexpr uint32_t kNoTexel = 0xffffffffu;

// Where texels sit in the lightmap atlases, and how texel values become the atlas image: a
// pixel takes its texel's value, except the pixels the baker lists as mixes (texels too
// buried to trust, the padding around charts that bilinear filtering reads, seams), which
// take a weighted sum of texel values. resolveAtlas() applies it; the bake and the runtime
// both go through it, so their lightmaps agree to the bit.
struct AtlasLayout {
  int width = 0;
  int height = 0;
  std::vector<uint32_t> texelOfPixel;  // width*height entries: texel index or kNoTexel
  // Pixel mixPixel[i] = Σ_k mixWeight[k] · value[mixTexel[k]], k in [mixStart[i], mixStart[i+1]).
  std::vector<uint32_t> mixPixel;
  std::vector<uint32_t> mixStart{0};
  std::vector<uint32_t> mixTexel;
  std::vector<float> mixWeight;
};

// The atlas image (width*height, row 0 at v = 0) from per-texel values; pixels without a
// texel or a mix are black.
void resolveAtlas(const AtlasLayout& layout, const std::vector<glm::vec3>& texelValues,
                  std::vector<glm::vec3>& image);
// The same into an image of width*height pixels that holds black wherever the layout puts
// neither a texel nor a mix (as resolveAtlas leaves it, or zero-filled): writes only the pixels
// the texels reach, so a runtime refreshing its atlases every frame skips clearing them.
void refreshAtlas(const AtlasLayout& layout, const std::vector<glm::vec3>& texelValues,
                  std::vector<glm::vec3>& image);

}  // namespace afterglow::runtime
