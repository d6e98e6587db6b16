#include "post/lightmap_post.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "post/seams.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::kNeighbourOffsets;

using Mix = PixelMix;

// The average of neighbour mixes, trimmed to the kMaxMix strongest entries.
Mix averageOf(const std::vector<const Mix*>& parts) {
  std::vector<std::pair<const Mix*, float>> scaled;
  for (const Mix* part : parts) scaled.push_back({part, 1.0f / float(parts.size())});
  return combineMixes(scaled, kMaxMix);
}

// Keeps the `cap` entries largest in magnitude of a texel-sorted mix; see combineMixes.
void trimMix(Mix& mix, size_t cap) {
  if (mix.size() <= cap) return;
  float total = 0.0f;
  for (const auto& e : mix) total += e.second;
  // Strongest first (ties by texel, so the choice does not depend on anything else).
  std::sort(mix.begin(), mix.end(), [](const auto& a, const auto& b) {
    const float wa = std::abs(a.second), wb = std::abs(b.second);
    return wa != wb ? wa > wb : a.first < b.first;
  });
  mix.resize(cap);
  float kept = 0.0f, magnitude = 0.0f;
  for (const auto& e : mix) kept += e.second, magnitude += std::abs(e.second);
  // Spread by magnitude rather than scaling by total/kept: stitched mixes may hold negative
  // weights, and their kept sum can be near zero.
  if (magnitude > 0.0f)
    for (auto& e : mix) e.second += (total - kept) * std::abs(e.second) / magnitude;
  std::sort(mix.begin(), mix.end());
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

// Whether a pixel can go without a mix: it holds a valid texel and takes exactly that texel's
// value (a stitched pixel mixes in others).
bool copiesTexel(const Mix& mix, uint32_t own, const TexelSet& texels) {
  return own != kNoTexel && texels.valid[own] && mix.size() == 1 && mix[0].first == own &&
         mix[0].second == 1.0f;
}

}  // namespace

Mix combineMixes(const std::vector<std::pair<const Mix*, float>>& parts, size_t cap) {
  // Every mix is sorted by texel, so each part merges in one pass (no sort: stitching combines
  // millions of mixes).
  Mix out, merged;
  for (const auto& [part, scale] : parts) {
    merged.clear();
    auto a = out.begin();
    auto b = part->begin();
    while (a != out.end() || b != part->end()) {
      if (b == part->end() || (a != out.end() && a->first < b->first)) {
        merged.push_back(*a++);
      } else if (a == out.end() || b->first < a->first) {
        merged.push_back({b->first, b->second * scale});
        ++b;
      } else {
        merged.push_back({a->first, a->second + b->second * scale});
        ++a, ++b;
      }
    }
    out.swap(merged);
  }
  // Exact cancellations add nothing to any pixel; dropping them keeps mixes small.
  out.erase(std::remove_if(out.begin(), out.end(), [](const auto& e) { return e.second == 0.0f; }),
            out.end());
  trimMix(out, cap);
  return out;
}

PostStats computeAtlasMixes(TexelSet& texels, const scenes::Scene& scene,
                            const PostOptions& options) {
  PostStats stats;
  const std::vector<std::vector<Seam>> seams =
      options.stitchSeams ? findSeams(scene, texels.atlases, options.stitchMaxAngleDeg)
                          : std::vector<std::vector<Seam>>(texels.atlases.size());
  for (size_t a = 0; a < texels.atlases.size(); ++a) {
    runtime::AtlasLayout& layout = texels.atlases[a];
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
    grow(w, h, mix, has, open, options.dilation, [](size_t, size_t) { return true; });
    // Last, so that seam footprints reaching into the padding read dilated pixels.
    stitchSeams(seams[a], w, h, options, mix, has, stats);

    layout.mixPixel.clear();
    layout.mixStart.assign(1, 0);
    layout.mixTexel.clear();
    layout.mixWeight.clear();
    for (size_t p = 0; p < pixels; ++p) {
      const uint32_t own = layout.texelOfPixel[p];
      if (copiesTexel(mix[p], own, texels)) continue;
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
  return stats;
}

}  // namespace afterglow::baker
