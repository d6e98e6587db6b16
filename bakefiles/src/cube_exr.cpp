#include "afterglow/bakefiles/cube_exr.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <OpenImageIO/imageio.h>

namespace fs = std::filesystem;

namespace afterglow::bakefiles {

namespace {

// OIIO's name for OpenEXR's envmap = ENVMAP_CUBE (its OpenEXR writer turns one into the other).
constexpr const char* kCubeTextureFormat = "CubeFace Environment";
constexpr const char* kPrefilteredLevels = "afterglow:prefilteredLevels";
constexpr int kTileSize = 64;                 // exrenvmap's default
constexpr float kHalfMax = 65504.0f;          // the largest finite half

const char* faceName(int face) {
  static const char* names[] = {"+X", "-X", "+Y", "-Y", "+Z", "-Z"};
  return face >= 0 && face < runtime::kCubeFaceCount ? names[face] : "?";
}

// A one-file write for tools: the folder must exist (a typo must not create folders), and the
// file is renamed into place only once complete.
template <class Write>
Status writeNow(const std::string& path, Write write) {
  fs::path folder = fs::path(path).parent_path();
  if (folder.empty()) folder = ".";
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    return Status::error(path + ": cannot write: the folder " + folder.string() +
                         " does not exist");
  AtomicOutput out;  // its destructor removes the temporary on failure
  if (Status s = write(out); !s) return s;
  return out.commit();
}

// OpenEXR's level size for level m of a dimension n, rounding down.
int levelSize(int n, int m) { return std::max(1, n >> m); }

// The 2×2 box average of a w × h RGB image into OpenEXR's next level (sizes rounded down: with
// an odd dimension the last row or column is dropped, as rounding down implies).
std::vector<glm::vec3> halve(const std::vector<glm::vec3>& image, int w, int h) {
  const int w2 = std::max(1, w / 2), h2 = std::max(1, h / 2);
  std::vector<glm::vec3> out(size_t(w2) * size_t(h2));
  for (int y = 0; y < h2; ++y)
    for (int x = 0; x < w2; ++x) {
      glm::vec3 sum(0.0f);
      int n = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const int sx = std::min(w - 1, 2 * x + dx), sy = std::min(h - 1, 2 * y + dy);
          if ((w == 1 && dx == 1) || (h == 1 && dy == 1)) continue;  // no second column/row
          sum += image[size_t(sy) * size_t(w) + size_t(sx)];
          ++n;
        }
      out[size_t(y) * size_t(w2) + size_t(x)] = sum / float(n);
    }
  return out;
}

Status checkChain(const std::string& path, const std::vector<runtime::Cubemap>& mips) {
  if (mips.empty()) return Status::error(path + ": no mips to write");
  const int size = mips[0].size;
  if (size <= 0) return Status::error(format("%s: mip 0 has size %d", path.c_str(), size));
  const int n = int(mips.size());
  if (n > 1 && (n - 1 >= 31 || (size >> (n - 1)) << (n - 1) != size))
    return Status::error(format("%s: %d mips of a %d² cube: the size must be divisible by 2^%d "
                                "for every mip to be an OpenEXR cube level",
                                path.c_str(), n, size, n - 1));
  for (int m = 0; m < n; ++m) {
    const runtime::Cubemap& c = mips[size_t(m)];
    if (c.size != size >> m)
      return Status::error(format("%s: mip %d has size %d, OpenEXR's level %d of a %d² cube "
                                  "is %d",
                                  path.c_str(), m, c.size, m, size, size >> m));
    if (c.texels.size() != size_t(runtime::kCubeFaceCount) * size_t(c.size) * size_t(c.size))
      return Status::error(format("%s: mip %d has %zu texels, not 6 × %d²", path.c_str(), m,
                                  c.texels.size(), c.size));
    for (size_t i = 0; i < c.texels.size(); ++i) {
      const glm::vec3 t = c.texels[i];
      if (!std::isfinite(t.x) || !std::isfinite(t.y) || !std::isfinite(t.z)) {
        const size_t perFace = size_t(c.size) * size_t(c.size);
        const int face = int(i / perFace);
        const int y = int(i % perFace) / c.size, x = int(i % perFace) % c.size;
        return Status::error(format("%s: mip %d face %s texel (%d, %d) is not finite",
                                    path.c_str(), m, faceName(face), x, y));
      }
    }
  }
  return Status::ok();
}

}  // namespace

Status writeCubemapExr(const std::string& path, const std::vector<runtime::Cubemap>& mips,
                       AtomicOutput& out, ExrPixels pixelType) {
  if (Status s = checkChain(path, mips); !s) return s;
  const int size = mips[0].size;
  const int width = size, height = 6 * size;
  // OpenEXR's MIPMAP_LEVELS count with ROUND_DOWN: floor(log2(max(w, h))) + 1.
  int levels = 1;
  while ((height >> levels) >= 1) ++levels;

  const bool half = pixelType == ExrPixels::Half;
  OIIO::ImageSpec spec(width, height, 3, half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
  spec.tile_width = kTileSize;
  spec.tile_height = kTileSize;
  spec.attribute("textureformat", kCubeTextureFormat);
  spec.attribute("compression", "zip");
  spec.attribute(kPrefilteredLevels, int(mips.size()));

  const std::string temp = out.tempPath(path);
  auto writer = OIIO::ImageOutput::create("exr");
  if (!writer) return Status::error(path + ": no OpenEXR writer in OpenImageIO");
  if (!writer->supports("mipmap") || !writer->supports("tiles"))
    return Status::error(path + ": OpenImageIO's OpenEXR writer cannot write MIP-mapped tiles");

  std::vector<glm::vec3> level;
  int w = width, h = height;
  for (int m = 0; m < levels; ++m) {
    if (m < int(mips.size())) {
      level = mips[size_t(m)].texels;  // the faces stacked vertically: already the image
    } else {
      level = halve(level, w, h);
    }
    w = levelSize(width, m);
    h = levelSize(height, m);
    if (half)
      for (glm::vec3& t : level) t = glm::clamp(t, glm::vec3(-kHalfMax), glm::vec3(kHalfMax));
    OIIO::ImageSpec levelSpec = spec;
    levelSpec.width = levelSpec.full_width = w;
    levelSpec.height = levelSpec.full_height = h;
    const bool opened = m == 0 ? writer->open(temp, spec, OIIO::ImageOutput::Create)
                               : writer->open(temp, levelSpec, OIIO::ImageOutput::AppendMIPLevel);
    if (!opened || !writer->write_image(OIIO::TypeDesc::FLOAT, level.data()))
      return Status::error(format("%s: cannot write level %d: %s", path.c_str(), m,
                                  writer->geterror().c_str()));
  }
  if (!writer->close())
    return Status::error(path + ": cannot write: " + writer->geterror());
  return Status::ok();
}

Status writeCubemapExr(const std::string& path, const std::vector<runtime::Cubemap>& mips,
                       ExrPixels pixelType) {
  return writeNow(path, [&](AtomicOutput& out) {
    return writeCubemapExr(path, mips, out, pixelType);
  });
}

Result<std::vector<runtime::Cubemap>> readCubemapExr(const std::string& path) {
  using R = Result<std::vector<runtime::Cubemap>>;
  auto in = OIIO::ImageInput::open(path);
  if (!in) return R::error(path + ": cannot read: " + OIIO::geterror());
  if (std::string(in->format_name()) != "openexr")
    return R::error(path + ": not an OpenEXR file");
  const OIIO::ImageSpec& spec0 = in->spec(0, 0);
  if (spec0.get_string_attribute("textureformat") != kCubeTextureFormat)
    return R::error(path + ": not an OpenEXR cube environment map (no envmap = cube)");
  const int size = spec0.width;
  if (size <= 0 || spec0.height != 6 * size)
    return R::error(format("%s: a cube environment map must be N × 6N, this one is %d × %d",
                           path.c_str(), spec0.width, spec0.height));
  if (spec0.nchannels < 3)
    return R::error(format("%s: %d channels, RGB needed", path.c_str(), spec0.nchannels));
  int wanted = spec0.get_int_attribute(kPrefilteredLevels, 0);

  std::vector<runtime::Cubemap> mips;
  for (int m = 0; wanted <= 0 || m < wanted; ++m) {
    if (!in->seek_subimage(0, m)) break;
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width < 1 || spec.height != 6 * spec.width) {
      if (wanted > 0)
        return R::error(format("%s: level %d is %d × %d, not a cube, but the file says %d "
                               "levels are prefiltered",
                               path.c_str(), m, spec.width, spec.height, wanted));
      break;
    }
    runtime::Cubemap cube = runtime::makeCubemap(spec.width);
    if (!in->read_image(0, m, 0, 3, OIIO::TypeDesc::FLOAT, cube.texels.data()))
      return R::error(format("%s: cannot read level %d: %s", path.c_str(), m,
                             in->geterror().c_str()));
    mips.push_back(std::move(cube));
  }
  if (wanted > 0 && int(mips.size()) < wanted)
    return R::error(format("%s: the file says %d levels are prefiltered but has %zu",
                           path.c_str(), wanted, mips.size()));
  if (mips.empty()) return R::error(path + ": no level could be read");
  return mips;
}

Status writeDfgExr(const std::string& path, const std::vector<glm::vec2>& table, int size,
                   AtomicOutput& out) {
  if (size <= 0 || table.size() != size_t(size) * size_t(size))
    return Status::error(format("%s: a DFG table of %zu values is not %d × %d", path.c_str(),
                                table.size(), size, size));
  std::vector<glm::vec3> pixels(table.size());
  for (size_t i = 0; i < table.size(); ++i) {
    if (!std::isfinite(table[i].x) || !std::isfinite(table[i].y))
      return Status::error(format("%s: DFG value (%d, %d) is not finite", path.c_str(),
                                  int(i % size_t(size)), int(i / size_t(size))));
    pixels[i] = glm::vec3(table[i], 0.0f);
  }
  OIIO::ImageSpec spec(size, size, 3, OIIO::TypeDesc::FLOAT);
  spec.attribute("compression", "zip");
  spec.attribute("ImageDescription",
                 "split-sum DFG: R = scale, G = bias (F0 * scale + bias); x = NdotV, "
                 "y = perceptual roughness, texel centres at (i + 0.5) / size, row 0 smoothest");
  const std::string temp = out.tempPath(path);
  auto writer = OIIO::ImageOutput::create("exr");
  if (!writer) return Status::error(path + ": no OpenEXR writer in OpenImageIO");
  if (!writer->open(temp, spec) || !writer->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) ||
      !writer->close())
    return Status::error(path + ": cannot write: " + writer->geterror());
  return Status::ok();
}

Status writeDfgExr(const std::string& path, const std::vector<glm::vec2>& table, int size) {
  return writeNow(path, [&](AtomicOutput& out) { return writeDfgExr(path, table, size, out); });
}

}  // namespace afterglow::bakefiles
