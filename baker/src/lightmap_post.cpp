#include "lightmap_post.h"

#include <algorithm>
#include <utility>

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::kNeighbourOffsets;

// A pixel's value as texel weights while the mixes grow.
using Mix = std::vector<std::pair<uint32_t, float>>;

// The average of neighbour mixes, merged by texel, trimmed to the kMaxMix strongest entries.
Mix averageOf(const std::vector<const Mix*>& parts) {
  Mix merged;
  for (const Mix* part : parts)
    for (const auto& [texel, weight] : *part) merged.push_back({texel, weight / float(parts.size())});
  std::sort(merged.begin(), merged.end());
  Mix out;
  for (const auto& e : merged) {
    if (!out.empty() && out.back().first == e.first) out.back().second += e.second;
    else out.push_back(e);
  }
  if (out.size() > kMaxMix) {
    // Strongest first (ties by texel, so the choice does not depend on anything else).
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
      return a.second != b.second ? a.second > b.second : a.first < b.first;
    });
    out.resize(kMaxMix);
    float sum = 0.0f;
    for (const auto& e : out) sum += e.second;
    for (auto& e : out) e.second /= sum;
    std::sort(out.begin(), out.end());
  }
  return out;
}

// Grows mixes ring by ring into the pixels `open` allows: each pixel reached in a ring
// averages the mixes its 8-neighbours had before that ring (so the result does not depend on
// visiting order), counting only neighbours `joins` allows. Stops after `rings` rings or when
// nothing grows.
template <class Joins>
void grow(int width, int height, std::vector<Mix>& mix, std::vector<uint8_t>& has,
          const std::vector<uint8_t>& open, int rings, Joins&& joins) {
  auto neighbours = [&](size_t p, auto&& visit) {
    const int x = int(p % size_t(width)), y = int(p / size_t(width));
    for (const auto& o : kNeighbourOffsets) {
      const int nx = x + o[0], ny = y + o[1];
      if (nx >= 0 && ny >= 0 && nx < width && ny < height)
        visit(size_t(ny) * size_t(width) + size_t(nx));
    }
  };
  // The first ring: open pixels next to a mix.
  std::vector<size_t> ring;
  std::vector<uint8_t> queued(has.size(), 0);
  for (size_t p = 0; p < has.size(); ++p) {
    if (has[p] || !open[p]) continue;
    bool next = false;
    neighbours(p, [&](size_t q) { next = next || (has[q] && joins(p, q)); });
    if (next) ring.push_back(p), queued[p] = 1;
  }
  for (int r = 0; r < rings && !ring.empty(); ++r) {
    std::vector<Mix> grown(ring.size());
    std::vector<const Mix*> parts;
    for (size_t i = 0; i < ring.size(); ++i) {
      parts.clear();
      neighbours(ring[i], [&](size_t q) {
        if (has[q] && joins(ring[i], q)) parts.push_back(&mix[q]);
      });
      grown[i] = averageOf(parts);
    }
    for (size_t i = 0; i < ring.size(); ++i) {
      mix[ring[i]] = std::move(grown[i]);
      has[ring[i]] = 1;
    }
    std::vector<size_t> next;
    for (size_t p : ring)
      neighbours(p, [&](size_t q) {
        if (!has[q] && open[q] && !queued[q] && joins(q, p)) next.push_back(q), queued[q] = 1;
      });
    std::sort(next.begin(), next.end());
    ring.swap(next);
  }
}

}  // namespace

void computeAtlasMixes(TexelSet& texels, int dilation) {
  for (runtime::AtlasLayout& layout : texels.atlases) {
    const int w = layout.width, h = layout.height;
    const size_t pixels = size_t(w) * size_t(h);
    std::vector<Mix> mix(pixels);
    std::vector<uint8_t> has(pixels, 0);
    for (size_t p = 0; p < pixels; ++p) {
      const uint32_t t = layout.texelOfPixel[p];
      if (t != kNoTexel && texels.valid[t]) {
        mix[p] = {{t, 1.0f}};
        has[p] = 1;
      }
    }
    // Invalid texels from valid ones of their own instance, however far (a buried texel never
    // takes light from a neighbouring chart across the padding).
    std::vector<uint8_t> open(pixels, 0);
    for (size_t p = 0; p < pixels; ++p) {
      const uint32_t t = layout.texelOfPixel[p];
      open[p] = t != kNoTexel && !texels.valid[t];
    }
    grow(w, h, mix, has, open, w + h, [&](size_t p, size_t q) {
      const uint32_t a = layout.texelOfPixel[p], b = layout.texelOfPixel[q];
      return a != kNoTexel && b != kNoTexel && texels.instance[a] == texels.instance[b];
    });
    // Padding, `dilation` pixels deep, from whatever chart is nearest.
    for (size_t p = 0; p < pixels; ++p) open[p] = layout.texelOfPixel[p] == kNoTexel;
    grow(w, h, mix, has, open, dilation, [](size_t, size_t) { return true; });

    layout.mixPixel.clear();
    layout.mixStart.assign(1, 0);
    layout.mixTexel.clear();
    layout.mixWeight.clear();
    for (size_t p = 0; p < pixels; ++p) {
      const uint32_t own = layout.texelOfPixel[p];
      if (own != kNoTexel && texels.valid[own]) continue;  // copies its texel
      // An invalid texel nothing reached gets an empty mix: black, not its untrusted value.
      if (!has[p] && own == kNoTexel) continue;
      layout.mixPixel.push_back(uint32_t(p));
      for (const auto& [texel, weight] : mix[p]) {
        layout.mixTexel.push_back(texel);
        layout.mixWeight.push_back(weight);
      }
      layout.mixStart.push_back(uint32_t(layout.mixTexel.size()));
    }
  }
}

}  // namespace afterglow::baker
