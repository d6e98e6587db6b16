#include "texture_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>

namespace afterglow::scenes::detail {

namespace {

// Larger images are refused rather than risking gigabytes of float texels (16k × 16k is the
// largest texture a GPU takes; 64 Mtexels of RGBA float is already 1 GiB).
constexpr size_t kMaxTexels = size_t(1) << 26;
constexpr int kMaxDimension = 32768;

const std::array<float, 256>& srgbTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[size_t(i)] = srgbToLinear(float(i) / 255.0f);
    return t;
  }();
  return table;
}

// OpenImageIO picks its reader from the file name's extension; for bytes in memory we name
// them after their signature (or the glTF's mimeType).
std::string pseudoFileName(const unsigned char* data, size_t size, const std::string& mimeType) {
  if (size >= 8 && std::memcmp(data, "\x89PNG\r\n\x1a\n", 8) == 0) return "image.png";
  if (size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF) return "image.jpg";
  if (size >= 12 && std::memcmp(data, "RIFF", 4) == 0 && std::memcmp(data + 8, "WEBP", 4) == 0)
    return "image.webp";
  if (mimeType == "image/jpeg") return "image.jpg";
  if (mimeType == "image/webp") return "image.webp";
  return "image.png";
}

Status readImage(OIIO::ImageInput* in, bool srgb, Texture& texture) {
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    return Status::error("the image is empty");
  if (spec.width > kMaxDimension || spec.height > kMaxDimension ||
      size_t(spec.width) * size_t(spec.height) > kMaxTexels)
    return Status::error(format("the image is too large (%d x %d)", spec.width, spec.height));
  if (spec.depth > 1) return Status::error("volume images are not supported");
  const int channels = std::min(spec.nchannels, 4);
  const size_t texelCount = size_t(spec.width) * size_t(spec.height);
  // 8-bit images (nearly every glTF texture) decode through a table: exact and fast.
  const bool eightBit = spec.format == OIIO::TypeDesc::UINT8;
  std::vector<float> values(texelCount * size_t(channels));
  if (eightBit) {
    std::vector<unsigned char> bytes(values.size());
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, bytes.data()))
      return Status::error(in->geterror());
    const auto& table = srgbTable();
    for (size_t i = 0; i < bytes.size(); ++i) {
      const bool alpha = channels == 4 ? (i % 4 == 3) : (channels == 2 && i % 2 == 1);
      values[i] = (srgb && !alpha) ? table[bytes[i]] : float(bytes[i]) / 255.0f;
    }
  } else {
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, values.data()))
      return Status::error(in->geterror());
    if (srgb) {
      for (size_t i = 0; i < values.size(); ++i) {
        const bool alpha = channels == 4 ? (i % 4 == 3) : (channels == 2 && i % 2 == 1);
        if (!alpha) values[i] = srgbToLinear(values[i]);
      }
    }
  }
  texture.texels.resize(texelCount);
  for (size_t t = 0; t < texelCount; ++t) {
    const float* v = &values[t * size_t(channels)];
    glm::vec4 c;
    switch (channels) {
      case 1: c = glm::vec4(v[0], v[0], v[0], 1.0f); break;
      case 2: c = glm::vec4(v[0], v[0], v[0], v[1]); break;
      case 3: c = glm::vec4(v[0], v[1], v[2], 1.0f); break;
      default: c = glm::vec4(v[0], v[1], v[2], v[3]); break;
    }
    texture.texels[t] = c;
  }
  texture.width = spec.width;
  texture.height = spec.height;
  texture.srgb = srgb;
  return Status::ok();
}

void clear(Texture& texture) {
  texture.width = texture.height = 0;
  texture.texels.clear();
}

}  // namespace

float srgbToLinear(float encoded) {
  if (!(encoded > 0.0f)) return 0.0f;  // also maps NaN to 0
  if (encoded <= 0.04045f) return encoded / 12.92f;
  return float(std::pow((double(encoded) + 0.055) / 1.055, 2.4));
}

Status decodeImageMemory(const unsigned char* data, size_t size, const std::string& mimeType,
                         bool srgb, Texture& texture) {
  clear(texture);
  if (data == nullptr || size == 0) return Status::error("the image data is empty");
  OIIO::Filesystem::IOMemReader reader(data, size);
  auto in = OIIO::ImageInput::open(pseudoFileName(data, size, mimeType), nullptr, &reader);
  if (!in) {
    std::string why = OIIO::geterror();
    return Status::error(why.empty() ? "no image reader recognised the data" : why);
  }
  Status status = readImage(in.get(), srgb, texture);
  in->close();
  if (!status) clear(texture);
  return status;
}

Status decodeImageFile(const std::string& path, bool srgb, Texture& texture) {
  clear(texture);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return Status::error("the file does not exist");
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    std::string why = OIIO::geterror();
    return Status::error(why.empty() ? "no image reader recognised the file" : why);
  }
  Status status = readImage(in.get(), srgb, texture);
  in->close();
  if (!status) clear(texture);
  return status;
}

}  // namespace afterglow::scenes::detail
