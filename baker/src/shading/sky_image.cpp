#include "afterglow/baker/sky.h"

#include <cmath>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "afterglow/core/math.h"

#include "shading/sampling.h"

namespace afterglow::baker {

Status projectEquirectSky(const std::string& path, glm::vec3 sh[runtime::kShCount]) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return Status::error(format("%s: cannot read the sky image (%s)", path.c_str(),
                                       OIIO::geterror().c_str()));
  const OIIO::ImageSpec spec = in->spec();
  const int w = spec.width, h = spec.height, channels = spec.nchannels;
  if (w <= 0 || h <= 0 || channels <= 0)
    return Status::error(format("%s: the sky image is empty", path.c_str()));
  std::vector<float> pixels(size_t(w) * size_t(h) * size_t(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, pixels.data()))
    return Status::error(format("%s: cannot decode the sky image (%s)", path.c_str(),
                                in->geterror().c_str()));
  in->close();
  // Doubles: a 4k sky sums 8M terms.
  double acc[runtime::kShCount][3] = {};
  for (int y = 0; y < h; ++y) {
    const double theta = kPiDouble * (y + 0.5) / h;
    const double solidAngle = (2.0 * kPiDouble / w) * (kPiDouble / h) * std::sin(theta);
    for (int x = 0; x < w; ++x) {
      const double phi = 2.0 * kPiDouble * (x + 0.5) / w;
      const glm::vec3 d(float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                        float(std::sin(theta) * std::sin(phi)));
      const float* p = &pixels[(size_t(y) * size_t(w) + size_t(x)) * size_t(channels)];
      const glm::vec3 radiance = channels >= 3 ? glm::vec3(p[0], p[1], p[2]) : glm::vec3(p[0]);
      if (!std::isfinite(radiance.x) || !std::isfinite(radiance.y) || !std::isfinite(radiance.z))
        continue;
      float basis[runtime::kShCount];
      sampling::shBasis(d, basis);
      for (int i = 0; i < runtime::kShCount; ++i)
        for (int k = 0; k < 3; ++k) acc[i][k] += double(radiance[k]) * basis[i] * solidAngle;
    }
  }
  for (int i = 0; i < runtime::kShCount; ++i)
    sh[i] = glm::vec3(float(acc[i][0]), float(acc[i][1]), float(acc[i][2]));
  return Status::ok();
}

}  // namespace afterglow::baker
