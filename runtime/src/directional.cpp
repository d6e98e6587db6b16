#include "afterglow/runtime/directional.h"

#include <algorithm>
#include <cmath>

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#endif

#include "afterglow/runtime/lightmap_layers.h"

namespace afterglow::runtime {

namespace {

constexpr size_t kBlock = 2048;  // items per block of work, as the solver's

// w ω / cos θ for a link of weight w from `from` (facing `normal`) to `to`.
glm::vec3 linkFactor(glm::vec3 from, glm::vec3 normal, glm::vec3 to, float w) {
  glm::vec3 d = to - from;
  const float length = std::sqrt(glm::dot(d, d));
  if (!(length > 1e-6f) || !(w > 0.0f)) return glm::vec3(0.0f);
  d /= length;
  return d * (w / std::max(glm::dot(d, normal), DirectionalLight::kMinCosine));
}

#if defined(__SSE2__) || defined(_M_X64)
// The gradients as three 4-lane vectors (x, y, z; RGB and a spare lane each): one SSE
// multiply-add per axis and link.
struct Gradient4 {
  __m128 axis[3];
};
inline Gradient4 zero4() { return {{_mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps()}}; }
inline void addScaled(Gradient4& sum, const Gradient4& g, float w) {
  const __m128 s = _mm_set1_ps(w);
  for (int a = 0; a < 3; ++a) sum.axis[a] = _mm_add_ps(sum.axis[a], _mm_mul_ps(s, g.axis[a]));
}
inline void scale(Gradient4& g, float w) {
  const __m128 s = _mm_set1_ps(w);
  for (int a = 0; a < 3; ++a) g.axis[a] = _mm_mul_ps(g.axis[a], s);
}
inline LightGradient toGradient(const Gradient4& g) {
  LightGradient out;
  for (int a = 0; a < 3; ++a) {
    alignas(16) float v[4];
    _mm_store_ps(v, g.axis[a]);
    out.axis[a] = glm::vec3(v[0], v[1], v[2]);
  }
  return out;
}
// Σ over a row of links: factor[k] ⊗ R[target] (padding and the shared far field's link carry
// a zero factor, and a valid target: no branch).
static_assert(kLinkGroup % 2 == 0, "rows are padded to an even count of links");
inline void addLinks(const SparseLinks& links, size_t row, const glm::vec3* factor,
                     const glm::vec4* r, Gradient4& out) {
  const uint32_t mask = links.targetMask();
  const uint32_t* link = links.link.data();
  // Rows come in groups of kLinkGroup (padded): two links a step into two sets of sums, so the
  // adds do not wait on each other (one set measured twice as slow).
  __m128 b0 = _mm_setzero_ps(), b1 = b0, b2 = b0;
  for (uint32_t k = links.rowStart[row], end = links.rowStart[row + 1]; k < end; k += 2) {
    const __m128 r0 = _mm_load_ps(&r[link[k] & mask].x);
    const __m128 r1 = _mm_load_ps(&r[link[k + 1] & mask].x);
    const glm::vec3& f0 = factor[k];
    const glm::vec3& f1 = factor[k + 1];
    out.axis[0] = _mm_add_ps(out.axis[0], _mm_mul_ps(_mm_set1_ps(f0.x), r0));
    out.axis[1] = _mm_add_ps(out.axis[1], _mm_mul_ps(_mm_set1_ps(f0.y), r0));
    out.axis[2] = _mm_add_ps(out.axis[2], _mm_mul_ps(_mm_set1_ps(f0.z), r0));
    b0 = _mm_add_ps(b0, _mm_mul_ps(_mm_set1_ps(f1.x), r1));
    b1 = _mm_add_ps(b1, _mm_mul_ps(_mm_set1_ps(f1.y), r1));
    b2 = _mm_add_ps(b2, _mm_mul_ps(_mm_set1_ps(f1.z), r1));
  }
  out.axis[0] = _mm_add_ps(out.axis[0], b0);
  out.axis[1] = _mm_add_ps(out.axis[1], b1);
  out.axis[2] = _mm_add_ps(out.axis[2], b2);
}
#else
struct Gradient4 {
  glm::vec4 axis[3];
};
inline Gradient4 zero4() { return {{glm::vec4(0.0f), glm::vec4(0.0f), glm::vec4(0.0f)}}; }
inline void addScaled(Gradient4& sum, const Gradient4& g, float w) {
  for (int a = 0; a < 3; ++a) sum.axis[a] += w * g.axis[a];
}
inline void scale(Gradient4& g, float w) {
  for (int a = 0; a < 3; ++a) g.axis[a] *= w;
}
inline LightGradient toGradient(const Gradient4& g) {
  LightGradient out;
  for (int a = 0; a < 3; ++a) out.axis[a] = glm::vec3(g.axis[a]);
  return out;
}
inline void addLinks(const SparseLinks& links, size_t row, const glm::vec3* factor,
                     const glm::vec4* r, Gradient4& out) {
  const uint32_t mask = links.targetMask();
  for (uint32_t k = links.rowStart[row]; k < links.rowStart[row + 1]; ++k) {
    const glm::vec4 radiance = r[links.link[k] & mask];
    for (int a = 0; a < 3; ++a) out.axis[a] += factor[k][a] * radiance;
  }
}
#endif

}  // namespace

glm::vec3 shadeDirectional(glm::vec3 lightmap, const LightGradient& g, glm::vec3 n, glm::vec3 n0) {
  const glm::vec3 dn = n - n0;
  const glm::vec3 change = g.axis[0] * dn.x + g.axis[1] * dn.y + g.axis[2] * dn.z;
  // The first-order change as a ratio r of the lightmap's own light, per channel: 1 + r from
  // half the light to twice it, below half an exponential tail of the same value and slope
  // (never negative: a normal map's groove tilted 65 degrees away from the light took more than
  // all of it, and a channel clamped at 0 alone tinted Sponza's arches).
  glm::vec3 out;
  for (int c = 0; c < 3; ++c) {
    const float light = lightmap[c];
    if (!(light > 0.0f)) {
      out[c] = std::max(light, 0.0f);
      continue;
    }
    const float r = change[c] / light;
    out[c] = light * (r < -0.5f ? 0.5f * std::exp(2.0f * (r + 0.5f)) : std::min(1.0f + r, 2.0f));
  }
  return out;
}

template <class Body>
void DirectionalLight::forRange(size_t items, const Body& body) const {
  const size_t blocks = (items + kBlock - 1) / kBlock;
  auto run = [&](size_t begin, size_t end) {
    for (size_t b = begin; b < end; ++b) body(b * kBlock, std::min(items, (b + 1) * kBlock));
  };
  if (parallelFor_ && blocks > 1) parallelFor_(blocks, run);
  else run(0, blocks);
}

DirectionalLight::DirectionalLight(const TransportData& data) : data_(data) {
  // Without directions (an invalid use) every gradient stays 0 rather than reading past them.
  const uint32_t points = data.hasDirections() ? data.gatherPointCount : 0;
  const uint32_t clusters = data.clusterCount;
  const uint32_t sharedBase = data.sharedFarBase();
  // Where every link target lies: clusters, then far clusters (their clusters' mix).
  std::vector<glm::vec3> target(sharedBase, glm::vec3(0.0f));
  for (uint32_t c = 0; c < clusters && c < data.clusterPosition.size(); ++c)
    target[c] = data.clusterPosition[c];
  const bool positions = data.clusterPosition.size() == clusters;
  const SparseMatrix& far = data.farClusters;
  for (size_t f = 0; f < far.rows(); ++f) {
    glm::vec3 sum(0.0f);
    float weight = 0.0f;
    for (uint32_t k = far.rowStart[f]; k < far.rowStart[f + 1] && positions; ++k) {
      sum += far.weight[k] * data.clusterPosition[far.column[k]];
      weight += far.weight[k];
    }
    target[clusters + f] = weight > 0.0f ? sum / weight : sum;
  }
  // The gather points' rows; a link to a shared far field is kept apart.
  const SparseLinks& links = data.links;
  const uint32_t mask = links.targetMask();
  linkFactor_.assign(points > 0 ? links.rowStart[points] : 0, glm::vec3(0.0f));
  pointShared_.assign(points, kNoTexel);
  pointSharedWeight_.assign(points, 0.0f);
  const size_t groups = data.sharedFar.rows();
  std::vector<glm::vec3> groupPosition(groups, glm::vec3(0.0f)), groupNormal(groups, glm::vec3(0.0f));
  std::vector<float> groupPoints(groups, 0.0f);
  for (uint32_t p = 0; p < points; ++p)
    for (uint32_t k = links.rowStart[p]; k < links.rowStart[p + 1]; ++k) {
      const uint32_t t = links.link[k] & mask;
      const float w = links.weightAt(p, k);
      if (w <= 0.0f) continue;  // padding
      if (t >= sharedBase) {
        const uint32_t g = t - sharedBase;
        pointShared_[p] = g;
        pointSharedWeight_[p] = w;
        groupPosition[g] += data.pointPosition[p];
        groupNormal[g] += data.pointNormal[p];
        groupPoints[g] += 1.0f;
      } else {
        linkFactor_[k] = linkFactor(data.pointPosition[p], data.pointNormal[p], target[t], w);
      }
    }
  // The shared far fields' rows, seen from the mean of their points.
  const SparseLinks& shared = data.sharedFar;
  const uint32_t sharedMask = shared.targetMask();
  sharedFactor_.assign(shared.size(), glm::vec3(0.0f));
  for (size_t g = 0; g < groups; ++g) {
    if (groupPoints[g] == 0.0f) continue;
    const glm::vec3 from = groupPosition[g] / groupPoints[g];
    const float n = glm::length(groupNormal[g]);
    if (!(n > 0.0f)) continue;
    const glm::vec3 normal = groupNormal[g] / n;
    for (uint32_t k = shared.rowStart[g]; k < shared.rowStart[g + 1]; ++k)
      sharedFactor_[k] =
          linkFactor(from, normal, target[shared.link[k] & sharedMask], shared.weightAt(g, k));
  }
  shared_.resize(groups * 3);
  points_.resize(size_t(data.gatherPointCount) * 3);
  filtered_.resize(size_t(data.gatherPointCount) * 3);
  pointShared_.resize(data.gatherPointCount, kNoTexel);
  pointSharedWeight_.resize(data.gatherPointCount, 0.0f);
  linkFactor_.resize(data.gatherPointCount > 0 ? data.links.rowStart[data.gatherPointCount] : 0,
                     glm::vec3(0.0f));
}

void DirectionalLight::texels(const Solver& solver, LightGradient* out) const {
  const glm::vec4* r = solver.linkTargetRadiance().data();
  const SparseLinks& shared = data_.sharedFar;
  Gradient4* sharedSums = reinterpret_cast<Gradient4*>(shared_.data());
  Gradient4* points = reinterpret_cast<Gradient4*>(points_.data());
  Gradient4* filtered = reinterpret_cast<Gradient4*>(filtered_.data());
  const size_t pointCount = data_.gatherPointCount;
  forRange(shared.rows(), [&](size_t first, size_t last) {
    for (size_t g = first; g < last; ++g) {
      Gradient4 sum = zero4();
      addLinks(shared, g, sharedFactor_.data(), r, sum);
      sharedSums[g] = sum;
    }
  });
  forRange(pointCount, [&](size_t first, size_t last) {
    for (size_t p = first; p < last; ++p) {
      Gradient4 g = zero4();
      addLinks(data_.links, p, linkFactor_.data(), r, g);
      if (pointShared_[p] != kNoTexel) addScaled(g, sharedSums[pointShared_[p]], pointSharedWeight_[p]);
      points[p] = g;
    }
  });
  // The smoothing passes and the texels' mix, as the light's (Solver::filteredPoints,
  // mixTexels).
  const Gradient4* in = points;
  const SparseMatrix& filter = data_.pointFilter;
  if (data_.filterPasses > 0 && filter.rows() == pointCount) {
    for (int pass = 0; pass < data_.filterPasses; ++pass) {
      Gradient4* dst = in == filtered ? points : filtered;
      forRange(pointCount, [&](size_t first, size_t last) {
        for (size_t p = first; p < last; ++p) {
          Gradient4 sum = zero4();
          for (uint32_t k = filter.rowStart[p]; k < filter.rowStart[p + 1]; ++k)
            addScaled(sum, in[filter.column[k]], filter.weight[k]);
          dst[p] = sum;
        }
      });
      in = dst;
    }
  }
  const SparseMatrix& gather = data_.texelGather;
  const float intensity = data_.indirectIntensity;
  forRange(data_.texelCount, [&](size_t first, size_t last) {
    for (size_t t = first; t < last; ++t) {
      Gradient4 sum = zero4();
      for (uint32_t k = gather.rowStart[t]; k < gather.rowStart[t + 1]; ++k)
        addScaled(sum, in[gather.column[k]], gather.weight[k]);
      scale(sum, intensity);
      out[t] = toGradient(sum);
    }
  });
}

void DirectionalLight::upsample(const LightGradient* grid, LightGradient* lightmap) const {
  const LightmapLayers& layers = data_.lightmap;
  forRange(layers.texelCount, [&](size_t first, size_t last) {
    for (size_t t = first; t < last; ++t) {
      uint32_t texel[4];
      float weight[4];
      cornerWeights(layers.corners[t], data_.atlases, texel, weight);
      LightGradient sum;
      for (int k = 0; k < 4; ++k)
        if (weight[k] > 0.0f)
          for (int a = 0; a < 3; ++a) sum.axis[a] += weight[k] * grid[texel[k]].axis[a];
      lightmap[t] = sum;
    }
  });
}

}  // namespace afterglow::runtime
