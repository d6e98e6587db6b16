// The bake folder's images: linear EXRs (lightmaps, renders, the DFG table) and tone-mapped PNG
// previews, written through an AtomicOutput, and linear images read back. OpenImageIO stays
// inside images.cpp.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/atomic_file.h"
#include "afterglow/core/status.h"

namespace afterglow::bakefiles {

// A linear RGB image (one atlas's lightmap, E/π; a rendered view), row 0 first (v = 0 for a
// lightmap).
struct LightmapImage {
  int width = 0;
  int height = 0;
  std::vector<glm::vec3> pixels;
};

// A linear image (a lightmap EXR, or a rendered view) as RGB, row 0 first; one channel is read
// as grey. Errors name the file.
Result<LightmapImage> readLinearImage(const std::string& path);

// How an EXR stores its channels: half floats (lightmaps) or 32-bit floats (renders compared
// with other renderers' float EXRs).
enum class ExrPixels { Half, Float };
// Linear RGB EXR (zip compressed), row 0 = v 0 (glTF's image orientation; the top row).
Status writeExr(const std::string& path, int width, int height,
                const std::vector<glm::vec3>& pixels, AtomicOutput& out,
                ExrPixels pixelType = ExrPixels::Half);
// 8-bit sRGB PNG from linear RGB: pixels × exposure, Reinhard tone map, sRGB encode.
Status writeTonemappedPng(const std::string& path, int width, int height,
                          const std::vector<glm::vec3>& pixels, float exposure,
                          AtomicOutput& out);
// 8-bit RGBA PNG of values in [0, 1] stored linearly (v × 255, rounded): data, not a picture
// (a shadowmask).
Status writeLinearRgbaPng(const std::string& path, int width, int height,
                          const std::vector<glm::vec4>& pixels, AtomicOutput& out);
// The exposure that maps the 99th percentile luminance of the given pixels (those with a
// non-zero mask entry, or all when the mask is empty) to 0.8 after the Reinhard curve.
float autoExposure(const std::vector<glm::vec3>& pixels, const std::vector<uint8_t>& mask = {});

}  // namespace afterglow::bakefiles
