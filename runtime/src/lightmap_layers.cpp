#include "afterglow/runtime/lightmap_layers.h"

#include <algorithm>
#include <cmath>

#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

namespace {

template <class T>
size_t bytesOf(const std::vector<T>& v) {
  return v.size() * sizeof(T);
}

}  // namespace

size_t LightmapLayers::directBytes() const {
  size_t b = bytesOf(directScale);
  for (const std::vector<uint16_t>& d : direct) b += bytesOf(d);
  return b;
}

size_t LightmapLayers::memoryBytes() const {
  size_t b = bytesOf(corners) + directBytes();
  for (const AtlasLayout& a : atlases)
    b += bytesOf(a.texelOfPixel) + bytesOf(a.mixPixel) + bytesOf(a.mixStart) +
         bytesOf(a.mixTexel) + bytesOf(a.mixWeight);
  return b;
}

std::string LightmapLayers::validate(size_t sources,
                                     const std::vector<AtlasLayout>& indirectAtlases) const {
  if (!active())
    return corners.empty() && direct.empty() && directScale.empty() && atlases.empty()
               ? std::string()
               : "lightmap layers without lightmap texels";
  if (corners.size() != texelCount)
    return "lightmap layers: " + std::to_string(corners.size()) + " corners for " +
           std::to_string(texelCount) + " lightmap texels";
  if (direct.size() != sources || directScale.size() != sources)
    return "lightmap layers: direct light for " + std::to_string(direct.size()) + " of " +
           std::to_string(sources) + " sources";
  for (size_t s = 0; s < sources; ++s) {
    if (!direct[s].empty() && direct[s].size() != texelCount)
      return "lightmap layers: source " + std::to_string(s) + " has direct light for " +
             std::to_string(direct[s].size()) + " of " + std::to_string(texelCount) + " texels";
    if (!std::isfinite(directScale[s]) || directScale[s] < 0.0f)
      return "lightmap layers: source " + std::to_string(s) + " has a bad scale";
  }
  for (size_t t = 0; t < corners.size(); ++t) {
    const IndirectCorners& c = corners[t];
    if (c.mask == 0) continue;
    if (c.atlas >= indirectAtlases.size())
      return "lightmap layers: texel " + std::to_string(t) + " reads indirect atlas " +
             std::to_string(c.atlas) + " of " + std::to_string(indirectAtlases.size());
    const AtlasLayout& a = indirectAtlases[c.atlas];
    for (int k = 0; k < 4; ++k)
      if ((c.mask >> k) & 1u) {
        const int x = c.x + (k & 1), y = c.y + (k >> 1);
        if (x >= a.width || y >= a.height)
          return "lightmap layers: texel " + std::to_string(t) + " reads pixel (" +
                 std::to_string(x) + ", " + std::to_string(y) + ") outside its indirect atlas";
      }
  }
  for (size_t a = 0; a < atlases.size(); ++a) {
    const AtlasLayout& l = atlases[a];
    if (l.width <= 0 || l.height <= 0 ||
        l.texelOfPixel.size() != size_t(l.width) * size_t(l.height))
      return "lightmap layers: atlas " + std::to_string(a) + " has a bad size";
    for (uint32_t t : l.texelOfPixel)
      if (t != kNoTexel && t >= texelCount)
        return "lightmap layers: atlas " + std::to_string(a) + " refers to texel " +
               std::to_string(t) + " of " + std::to_string(texelCount);
    if (l.mixStart.empty() || l.mixStart.size() != l.mixPixel.size() + 1 ||
        l.mixStart.back() != l.mixTexel.size() || l.mixTexel.size() != l.mixWeight.size())
      return "lightmap layers: atlas " + std::to_string(a) + " has inconsistent mixes";
    for (size_t i = 0; i + 1 < l.mixStart.size(); ++i)
      if (l.mixStart[i] > l.mixStart[i + 1])
        return "lightmap layers: atlas " + std::to_string(a) + " has inconsistent mixes";
    for (uint32_t p : l.mixPixel)
      if (p >= l.texelOfPixel.size())
        return "lightmap layers: atlas " + std::to_string(a) + " mixes a pixel outside it";
    for (uint32_t t : l.mixTexel)
      if (t >= texelCount)
        return "lightmap layers: atlas " + std::to_string(a) + " mixes texel " +
               std::to_string(t) + " of " + std::to_string(texelCount);
  }
  return {};
}

void cornerWeights(const IndirectCorners& c, const std::vector<AtlasLayout>& indirectAtlases,
                   uint32_t texel[4], float weight[4]) {
  const float fx = float(c.fraction & 15u) * (1.0f / 16.0f);
  const float fy = float(c.fraction >> 4) * (1.0f / 16.0f);
  const float bilinear[4] = {(1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy,
                             fx * fy};
  float sum = 0.0f;
  for (int k = 0; k < 4; ++k) {
    texel[k] = kNoTexel;
    weight[k] = 0.0f;
    if (!((c.mask >> k) & 1u)) continue;
    const AtlasLayout& a = indirectAtlases[c.atlas];
    const size_t x = size_t(c.x) + size_t(k & 1), y = size_t(c.y) + size_t(k >> 1);
    texel[k] = a.texelOfPixel[y * size_t(a.width) + x];
    if (texel[k] == kNoTexel) continue;
    weight[k] = bilinear[k];
    sum += bilinear[k];
  }
  if (sum > 0.0f) {
    const float inv = 1.0f / sum;
    for (int k = 0; k < 4; ++k) weight[k] *= inv;
    return;
  }
  // Only corners the point has no bilinear weight on count (its square's far side, when the
  // near one is buried): they share it equally.
  int counted = 0;
  for (int k = 0; k < 4; ++k) counted += texel[k] != kNoTexel;
  for (int k = 0; k < 4; ++k) weight[k] = texel[k] != kNoTexel ? 1.0f / float(counted) : 0.0f;
}

float encodeDirectLayer(const std::vector<float>& values, std::vector<uint16_t>& halves) {
  float largest = 0.0f;
  for (float v : values) largest = std::max(largest, v);
  const float scale = largest > 0.0f && std::isfinite(largest) ? largest : 1.0f;
  halves.resize(values.size());
  for (size_t t = 0; t < values.size(); ++t) halves[t] = floatToHalf(values[t] / scale);
  return scale;
}

}  // namespace afterglow::runtime
