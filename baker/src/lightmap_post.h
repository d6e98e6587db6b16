// Lightmap post-processing after the solve: invalid texels (samples buried in geometry) take
// their value from valid neighbours, then every chart is dilated into its padding so bilinear
// filtering at chart borders never fetches an unbaked (black) pixel.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace afterglow::baker {

// Per-pixel state of an atlas image during post-processing.
enum PixelState : uint8_t {
  kPixelEmpty = 0,    // no texel (padding or unused atlas space)
  kPixelInvalid = 1,  // a texel whose value is not trusted (buried sample)
  kPixelValid = 2,    // a baked texel, or a pixel filled by this pass
};

// Replaces every invalid pixel with the average of its valid 8-neighbours, repeating until no
// invalid pixel has a valid neighbour (each pass reads the previous pass only, so the result
// is independent of traversal order). Invalid pixels unreachable from any valid one keep their
// value and state. Returns the number of pixels filled.
size_t fillInvalidPixels(int width, int height, std::vector<glm::vec3>& image,
                         std::vector<uint8_t>& state);

// Grows the valid region `radius` pixels into empty pixels: each pass sets every empty pixel
// with a valid 8-neighbour to the average of those neighbours. Returns the pixels filled.
size_t dilatePixels(int width, int height, std::vector<glm::vec3>& image,
                    std::vector<uint8_t>& state, int radius);

}  // namespace afterglow::baker
