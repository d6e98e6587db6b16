#include "afterglow/runtime/probe_sh_file.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace afterglow::runtime {

namespace {

constexpr uint32_t kFloatsPerProbe = 3 * kShCount;
constexpr uint32_t kDeringed = 1u;
constexpr uint32_t kDirections = 2u;
constexpr uint32_t kDepth = 4u;
constexpr uint32_t kFloatsPerDirection = 6;

void put32(std::vector<uint8_t>& out, size_t at, uint32_t v) {
  for (int k = 0; k < 4; ++k) out[at + size_t(k)] = uint8_t(v >> (8 * k));
}
uint32_t get32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
void putFloat(std::vector<uint8_t>& out, size_t at, float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  put32(out, at, bits);
}
float getFloat(const uint8_t* p) {
  const uint32_t bits = get32(p);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

}  // namespace

std::vector<uint8_t> serializeProbeSh(const ProbeShFile& file) {
  const ProbeDirectionList& dirs = file.directions;
  const bool withDirections = !dirs.start.empty() && dirs.count() == file.sh.size();
  size_t size = kProbeShHeaderSize + file.sh.size() * kFloatsPerProbe * 4;
  if (withDirections) size += 4 + dirs.start.size() * 4 + dirs.lights.size() * kFloatsPerDirection * 4;
  const bool withDepth = !file.depth.empty() && file.depth.size() == file.sh.size() * kProbeDepthValues;
  if (withDepth) size += file.depth.size() * 2;
  std::vector<uint8_t> out(size, 0);
  std::memcpy(out.data(), kProbeShMagic, 8);
  put32(out, 8, kProbeShVersion);
  put32(out, 12, uint32_t(file.sh.size()));
  put32(out, 16, kFloatsPerProbe);
  put32(out, 20, (file.deringWindow > 0.0f ? kDeringed : 0u) | (withDirections ? kDirections : 0u) |
                     (withDepth ? kDepth : 0u));
  putFloat(out, 24, file.deringWindow > 0.0f ? file.deringWindow : 0.0f);
  size_t at = kProbeShHeaderSize;
  for (const ShL2& sh : file.sh)
    for (int i = 0; i < kShCount; ++i)
      for (int c = 0; c < 3; ++c, at += 4) putFloat(out, at, sh.c[i][c]);
  if (withDirections) {
    put32(out, at, uint32_t(dirs.lights.size()));
    at += 4;
    for (uint32_t s : dirs.start) put32(out, at, s), at += 4;
    for (const ProbeDirection& d : dirs.lights)
      for (float v : {d.direction.x, d.direction.y, d.direction.z, d.power.x, d.power.y, d.power.z})
        putFloat(out, at, v), at += 4;
  }
  if (withDepth)
    for (uint16_t v : file.depth) out[at] = uint8_t(v), out[at + 1] = uint8_t(v >> 8), at += 2;
  return out;
}

bool parseProbeSh(const uint8_t* bytes, size_t size, ProbeShFile& out, std::string* error) {
  auto fail = [&](const std::string& why) {
    if (error) *error = why;
    out = ProbeShFile();
    return false;
  };
  if (size < kProbeShHeaderSize || std::memcmp(bytes, kProbeShMagic, 8) != 0)
    return fail(size >= 8 && std::memcmp(bytes, kProbeShMagic, 8) == 0
                    ? "truncated: " + std::to_string(size) + " bytes, the header alone has 32"
                    : "not an afterglow light probe SH file");
  const uint32_t version = get32(bytes + 8), count = get32(bytes + 12);
  const uint32_t floats = get32(bytes + 16), flags = get32(bytes + 20);
  if (version != 1 && version != kProbeShVersion)
    return fail("version " + std::to_string(version) + "; this reader reads versions 1 and " +
                std::to_string(kProbeShVersion));
  if (floats != kFloatsPerProbe)
    return fail(std::to_string(floats) + " floats per probe, expected " +
                std::to_string(kFloatsPerProbe));
  const bool withDirections = (flags & kDirections) != 0;
  const bool withDepth = (flags & kDepth) != 0;
  const uint64_t depthBytes = withDepth ? uint64_t(count) * kProbeDepthValues * 2 : 0;
  const uint64_t shEnd = uint64_t(kProbeShHeaderSize) + uint64_t(count) * kFloatsPerProbe * 4;
  // Version 1 has no directions; the sizes are checked before any count read is trusted.
  uint64_t expected = shEnd;
  uint32_t directionCount = 0;
  if (withDirections && version >= 2) {
    if (uint64_t(size) < shEnd + 4)
      return fail(std::to_string(size) + " bytes, " + std::to_string(count) +
                  " probes and their directions need more than " + std::to_string(shEnd + 4));
    directionCount = get32(bytes + shEnd);
    expected = shEnd + 4 + (uint64_t(count) + 1) * 4 + uint64_t(directionCount) * kFloatsPerDirection * 4;
  }
  expected += depthBytes;
  if (uint64_t(size) != expected)
    return fail(std::to_string(size) + " bytes, " + std::to_string(count) + " probes need " +
                std::to_string(expected));
  const float window = getFloat(bytes + 24);
  const uint32_t known = kDeringed | (version >= 2 ? kDirections | kDepth : 0u);
  if ((flags & ~known) != 0 || !std::isfinite(window) || window < 0.0f ||
      ((flags & kDeringed) != 0) != (window > 0.0f))
    return fail("bad flags or deringing window");
  ProbeShFile file;
  file.deringWindow = window;
  file.sh.resize(count);
  const uint8_t* p = bytes + kProbeShHeaderSize;
  for (uint32_t n = 0; n < count; ++n)
    for (int i = 0; i < kShCount; ++i)
      for (int c = 0; c < 3; ++c, p += 4) {
        const float v = getFloat(p);
        if (!std::isfinite(v))
          return fail("probe " + std::to_string(n) + ": coefficient " + std::to_string(i) +
                      " is not finite");
        file.sh[n].c[i][c] = v;
      }
  if (withDirections) {
    p += 4;
    file.directions.start.resize(size_t(count) + 1);
    for (uint32_t n = 0; n <= count; ++n, p += 4) {
      const uint32_t s = get32(p);
      if ((n == 0 && s != 0) || (n > 0 && s < file.directions.start[n - 1]) ||
          s > directionCount || (n == count && s != directionCount))
        return fail("probe " + std::to_string(n) + ": its directions start at " +
                    std::to_string(s) + ", out of order or past the " +
                    std::to_string(directionCount) + " directions");
      file.directions.start[n] = s;
    }
    file.directions.lights.resize(directionCount);
    for (uint32_t k = 0; k < directionCount; ++k) {
      float v[kFloatsPerDirection];
      for (float& x : v) x = getFloat(p), p += 4;
      ProbeDirection& d = file.directions.lights[k];
      d.direction = glm::vec3(v[0], v[1], v[2]);
      d.power = glm::vec3(v[3], v[4], v[5]);
      bool finite = true;
      for (float x : v) finite = finite && std::isfinite(x);
      if (!finite || std::abs(glm::length(d.direction) - 1.0f) > 1e-3f)
        return fail("direction " + std::to_string(k) + " is not a finite unit vector and power");
    }
  }
  if (withDepth) {
    file.depth.resize(size_t(count) * kProbeDepthValues);
    for (size_t k = 0; k < file.depth.size(); ++k, p += 2) {
      file.depth[k] = uint16_t(p[0] | p[1] << 8);
      const float v = halfToFloat(file.depth[k]);
      if (!std::isfinite(v) || v < 0.0f)
        return fail("probe " + std::to_string(k / kProbeDepthValues) +
                    ": its depth map holds a negative or non-finite distance");
    }
  }
  out = std::move(file);
  return true;
}

bool readProbeSh(const std::string& path, ProbeShFile& out, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (error) *error = path + ": cannot open";
    return false;
  }
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
  std::string why;
  if (!parseProbeSh(bytes.data(), bytes.size(), out, &why)) {
    if (error) *error = path + ": " + why;
    return false;
  }
  return true;
}

}  // namespace afterglow::runtime
