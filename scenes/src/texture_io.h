// Image decoding for the glTF importer: any format OpenImageIO reads, into linear RGBA float.
#pragma once

#include <cstddef>
#include <string>

#include "afterglow/core/status.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::scenes::detail {

// The exact sRGB EOTF (IEC 61966-2-1), encoded value in [0, 1] to linear.
float srgbToLinear(float encoded);

// Decodes image bytes into texture.width/height/texels/srgb. srgb applies the EOTF to RGB (never
// to alpha). Grey images are expanded to RGB; a missing alpha channel becomes 1. mimeType helps
// pick the reader when the bytes have no recognisable signature. On failure the texture is left
// unloaded (width = 0) and the message says why (without naming the file: the caller does).
Status decodeImageMemory(const unsigned char* data, size_t size, const std::string& mimeType,
                         bool srgb, Texture& texture);
Status decodeImageFile(const std::string& path, bool srgb, Texture& texture);

}  // namespace afterglow::scenes::detail
