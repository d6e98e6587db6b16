#include "afterglow/bakefiles/images.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imageio.h>

#include "afterglow/core/math.h"

namespace afterglow::bakefiles {

namespace {

float srgbEncode(float x) {
  x = std::clamp(x, 0.0f, 1.0f);
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

Status writeImage(const std::string& path, const std::string& format, const OIIO::ImageSpec& spec,
                  OIIO::TypeDesc dataType, const void* data, AtomicOutput& out) {
  const std::string temp = out.tempPath(path);
  auto writer = OIIO::ImageOutput::create(format);
  if (!writer) return Status::error(path + ": no " + format + " writer in OpenImageIO");
  if (!writer->open(temp, spec) || !writer->write_image(dataType, data) || !writer->close())
    return Status::error(path + ": cannot write: " + writer->geterror());
  return Status::ok();
}

}  // namespace

Result<LightmapImage> readLinearImage(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return Status::error(path + ": cannot read the lightmap (" + OIIO::geterror() + ")");
  const OIIO::ImageSpec spec = in->spec();
  LightmapImage image;
  image.width = spec.width;
  image.height = spec.height;
  const int channels = spec.nchannels;
  if (image.width <= 0 || image.height <= 0 || channels < 1)
    return Status::error(path + ": empty lightmap");
  std::vector<float> data(size_t(image.width) * size_t(image.height) * size_t(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, data.data()))
    return Status::error(path + ": cannot decode the lightmap (" + in->geterror() + ")");
  image.pixels.resize(size_t(image.width) * size_t(image.height));
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const float* p = &data[i * size_t(channels)];
    image.pixels[i] = channels >= 3 ? glm::vec3(p[0], p[1], p[2]) : glm::vec3(p[0]);
  }
  return image;
}

float autoExposure(const std::vector<glm::vec3>& pixels, const std::vector<uint8_t>& mask) {
  std::vector<float> lum;
  lum.reserve(pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i)
    if (mask.empty() || mask[i]) {
      const float l = luminance(pixels[i]);
      if (std::isfinite(l) && l > 0.0f) lum.push_back(l);
    }
  if (lum.empty()) return 1.0f;
  const size_t k = std::min(lum.size() - 1, size_t(double(lum.size()) * 0.99));
  std::nth_element(lum.begin(), lum.begin() + std::ptrdiff_t(k), lum.end());
  // Reinhard x / (1 + x) = 0.8 at x = 4.
  return 4.0f / lum[k];
}

Status writeExr(const std::string& path, int width, int height,
                const std::vector<glm::vec3>& pixels, AtomicOutput& out, ExrPixels pixelType) {
  OIIO::ImageSpec spec(width, height, 3,
                       pixelType == ExrPixels::Float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::HALF);
  spec.attribute("compression", "zip");
  return writeImage(path, "exr", spec, OIIO::TypeDesc::FLOAT, pixels.data(), out);
}

Status writeLinearRgbaPng(const std::string& path, int width, int height,
                          const std::vector<glm::vec4>& pixels, AtomicOutput& out) {
  std::vector<uint8_t> bytes(pixels.size() * 4);
  for (size_t i = 0; i < pixels.size(); ++i)
    for (int k = 0; k < 4; ++k)
      bytes[4 * i + size_t(k)] = uint8_t(std::lround(255.0f * std::clamp(pixels[i][k], 0.0f, 1.0f)));
  OIIO::ImageSpec spec(width, height, 4, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", "Linear");
  return writeImage(path, "png", spec, OIIO::TypeDesc::UINT8, bytes.data(), out);
}

Status writeTonemappedPng(const std::string& path, int width, int height,
                          const std::vector<glm::vec3>& pixels, float exposure,
                          AtomicOutput& out) {
  std::vector<uint8_t> bytes(pixels.size() * 3);
  for (size_t i = 0; i < pixels.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      float x = std::max(0.0f, pixels[i][k] * exposure);
      if (!std::isfinite(x)) x = 0.0f;
      const float mapped = x / (1.0f + x);
      bytes[i * 3 + size_t(k)] = uint8_t(std::lround(srgbEncode(mapped) * 255.0f));
    }
  }
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  return writeImage(path, "png", spec, OIIO::TypeDesc::UINT8, bytes.data(), out);
}

}  // namespace afterglow::bakefiles
