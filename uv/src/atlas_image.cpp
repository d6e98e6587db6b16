// Atlas pictures: one PNG per atlas, chart footprints in distinct colours with darker outlines,
// overlapping texels in white so a broken layout stands out.
#include "afterglow/uv/atlas_image.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "scene_charts.h"

namespace afterglow::uv {
namespace {

constexpr int kMaxSide = 2048;  // pixels, long side of a big atlas's picture
constexpr int kMinSide = 256;   // pixels, tiny atlases are enlarged (nearest) to at least this
constexpr uint8_t kBackground = 40;

uint32_t hash32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

// A saturated colour from the instance and its chart, stable from run to run.
void chartColour(int instance, int chart, uint8_t rgb[3]) {
  const uint32_t h = hash32(uint32_t(instance) * 0x9e3779b9U ^ hash32(uint32_t(chart) + 0x632be5abU));
  const double hue = (h & 0xffff) / 65536.0 * 6.0;
  const double sat = 0.55 + 0.35 * ((h >> 16) & 0xff) / 255.0;
  const double val = 0.75 + 0.25 * ((h >> 24) & 0xff) / 255.0;
  const int sector = int(hue) % 6;
  const double f = hue - std::floor(hue);
  const double p = val * (1 - sat), q = val * (1 - sat * f), t = val * (1 - sat * (1 - f));
  double r = 0, g = 0, b = 0;
  switch (sector) {
    case 0: r = val, g = t, b = p; break;
    case 1: r = q, g = val, b = p; break;
    case 2: r = p, g = val, b = t; break;
    case 3: r = p, g = q, b = val; break;
    case 4: r = t, g = p, b = val; break;
    default: r = val, g = p, b = q; break;
  }
  rgb[0] = uint8_t(std::lround(r * 255));
  rgb[1] = uint8_t(std::lround(g * 255));
  rgb[2] = uint8_t(std::lround(b * 255));
}

}  // namespace

Result<std::vector<std::string>> writeAtlasPictures(const scenes::Scene& scene,
                                                    const std::string& pathPrefix,
                                                    AtomicOutput& output) {
  const detail::SceneCharts charts = detail::labelCharts(scene);
  std::vector<std::string> written;
  for (int a = 0; a < charts.atlasCount; ++a) {
    const detail::AtlasCoverage cov = detail::rasterizeAtlas(scene, charts, a);
    const int W = cov.width, H = cov.height;
    if (W <= 0 || H <= 0) continue;
    // Full-resolution picture first, then nearest resampling to the output size.
    std::vector<uint8_t> full(size_t(W) * H * 3, kBackground);
    std::vector<uint8_t> colours(size_t(charts.chartCount) * 3);
    for (int c = 0; c < charts.chartCount; ++c)
      chartColour(charts.chartInstance[c], charts.chartLocal[c], &colours[size_t(c) * 3]);
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const size_t i = size_t(y) * W + x;
        const int32_t own = cov.owner[i];
        if (own < 0) continue;
        uint8_t* px = &full[i * 3];
        if (cov.shared[i]) {
          px[0] = px[1] = px[2] = 255;
          continue;
        }
        auto other = [&](int xx, int yy) {
          return xx < 0 || yy < 0 || xx >= W || yy >= H || cov.owner[size_t(yy) * W + xx] != own;
        };
        const bool edge = other(x - 1, y) || other(x + 1, y) || other(x, y - 1) || other(x, y + 1);
        for (int k = 0; k < 3; ++k)
          px[k] = edge ? uint8_t(colours[size_t(own) * 3 + k] * 11 / 20) : colours[size_t(own) * 3 + k];
      }
    const int longSide = std::max(W, H);
    int outW = W, outH = H;
    if (longSide > kMaxSide) {
      outW = std::max(1, int(std::lround(double(W) * kMaxSide / longSide)));
      outH = std::max(1, int(std::lround(double(H) * kMaxSide / longSide)));
    } else if (longSide < kMinSide) {
      const int factor = (kMinSide + longSide - 1) / longSide;
      outW = W * factor;
      outH = H * factor;
    }
    std::vector<uint8_t> pixels(size_t(outW) * outH * 3);
    for (int oy = 0; oy < outH; ++oy) {
      const int sy = int(int64_t(oy) * H / outH);
      for (int ox = 0; ox < outW; ++ox) {
        const int sx = int(int64_t(ox) * W / outW);
        std::copy_n(&full[(size_t(sy) * W + sx) * 3], 3, &pixels[(size_t(oy) * outW + ox) * 3]);
      }
    }
    const std::string path = pathPrefix + std::to_string(a) + ".png";
    const std::string temp = output.tempPath(path);
    auto out = OIIO::ImageOutput::create("png");
    if (!out) return Result<std::vector<std::string>>::error(path + ": no PNG writer in OpenImageIO");
    const OIIO::ImageSpec spec(outW, outH, 3, OIIO::TypeDesc::UINT8);
    if (!out->open(temp, spec) || !out->write_image(OIIO::TypeDesc::UINT8, pixels.data()) ||
        !out->close())
      return Result<std::vector<std::string>>::error(path + ": cannot write PNG: " +
                                                     out->geterror());
    written.push_back(path);
  }
  return written;
}

}  // namespace afterglow::uv
