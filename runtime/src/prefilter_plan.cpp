// A PrefilterPlan's stored rows and applying them to a source (prefilter_plan.h); building
// the rows is prefilter_plan_build.cpp.
#include "afterglow/runtime/prefilter_plan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace afterglow::runtime {

namespace {

// The taps' 16-bit floats, relative to their row's largest magnitude: radiance weights
// unsigned, a 5-bit exponent e and an 11-bit mantissa m for (1 + m/2048) · 2^(e − 31)
// (2^−30 to 1, 2.4e-4 apart relative; 0, a linear tap's dropped weight, reads as 2^−31),
// moments the same with a sign bit and a 10-bit mantissa. Relative, not fixed-point: a row's
// smallest weights, far out in the lobe, may fall on the brightest texels of the environment.
// A float's exponent field is the 16-bit one plus 127 − 31, so decoding is one addition and one
// shift.
float bitsToFloat(uint32_t bits) {
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

float decodeWeight(uint16_t w) { return bitsToFloat((uint32_t(w) + (96u << 11)) << 12); }

float decodeMoment(uint16_t w) {
  return bitsToFloat((uint32_t(w & 0x8000u) << 16) | ((uint32_t(w & 0x7FFFu) + (96u << 10)) << 13));
}

// v ∈ [0, 1] to the nearest 16-bit weight (0 below 2^−30, which no row keeps).
uint16_t encodeWeight(double v) {
  int e = 0;
  const double f = std::frexp(v, &e);  // v = f 2^e, f ∈ [0.5, 1)
  if (!(v > 0.0) || e - 1 + 31 < 1) return 0;
  int biased = e - 1 + 31;
  int m = int(std::lround((2.0 * f - 1.0) * 2048.0));
  if (m == 2048) m = 0, ++biased;
  if (biased > 31) biased = 31, m = 2047;
  return uint16_t((biased << 11) | m);
}

uint16_t encodeMoment(double v) {
  int e = 0;
  const double f = std::frexp(std::abs(v), &e);
  if (v == 0.0 || e - 1 + 31 < 1) return 0;
  int biased = e - 1 + 31;
  int m = int(std::lround((2.0 * f - 1.0) * 1024.0));
  if (m == 1024) m = 0, ++biased;
  if (biased > 31) biased = 31, m = 1023;
  return uint16_t((v < 0.0 ? 0x8000 : 0) | (biased << 10) | m);
}

// A running Σ weight · texel over a texel's four lanes. With glm's operators GCC sees only
// three lanes used in the end and splits every product into a two-lane and a one-lane
// multiply; four-lane SSE operations (every x86-64 has them) do half the arithmetic.
struct Sum {
#if defined(__SSE2__)
  __m128 v = _mm_setzero_ps();
  void add(float w, const glm::vec4& texel) {
    v = _mm_add_ps(v, _mm_mul_ps(_mm_set1_ps(w), _mm_loadu_ps(&texel.x)));
  }
  void add(const Sum& o) { v = _mm_add_ps(v, o.v); }
  glm::vec4 value() const {
    glm::vec4 out;
    _mm_storeu_ps(&out.x, v);
    return out;
  }
#else
  glm::vec4 v{0.0f};
  void add(float w, const glm::vec4& texel) { v += w * texel; }
  void add(const Sum& o) { v += o.v; }
  glm::vec4 value() const { return v; }
#endif
};

// Σ weight · s[index] over radiance taps [t, end), the indices stepped from `index`.
Sum dotRadiance(const PrefilterPlanTap* t, const PrefilterPlanTap* end, uint32_t index,
                const uint32_t*& escape, const glm::vec4* s) {
  auto next = [&](const PrefilterPlanTap& tap) -> const glm::vec4& {
    index = tap.step == 0xFFFFu ? *escape++ : index + tap.step;
    return s[index];
  };
  // Four partial sums: one would wait on the previous addition at every tap.
  Sum sum0, sum1, sum2, sum3;
  for (; end - t >= 4; t += 4) {
    sum0.add(decodeWeight(t[0].weight), next(t[0]));
    sum1.add(decodeWeight(t[1].weight), next(t[1]));
    sum2.add(decodeWeight(t[2].weight), next(t[2]));
    sum3.add(decodeWeight(t[3].weight), next(t[3]));
  }
  for (; t != end; ++t) sum0.add(decodeWeight(t->weight), next(*t));
  sum0.add(sum1);
  sum2.add(sum3);
  sum0.add(sum2);
  return sum0;
}

// The linear taps [t, end): each a coarse texel's radiance into `radiance` and its two
// moments into `moments`.
void dotLinear(const PrefilterPlanLinearTap* t, const PrefilterPlanLinearTap* end, uint32_t index,
               const uint32_t*& escape, const glm::vec4* s, Sum& radiance, Sum& moments) {
  Sum r0, r1, m0, m1;
  auto one = [&](const PrefilterPlanLinearTap& tap, Sum& r, Sum& m) {
    index = tap.step == 0xFFFFu ? *escape++ : index + tap.step;
    const glm::vec4* texel = s + index;
    r.add(decodeWeight(tap.radiance), texel[0]);
    m.add(decodeMoment(tap.moment[0]), texel[1]);
    m.add(decodeMoment(tap.moment[1]), texel[2]);
  };
  for (; end - t >= 2; t += 2) {
    one(t[0], r0, m0);
    one(t[1], r1, m1);
  }
  for (; t != end; ++t) one(*t, r0, m0);
  radiance.add(r0);
  radiance.add(r1);
  moments.add(m0);
  moments.add(m1);
}

}  // namespace

bool PrefilterPlan::supports(int sourceSize) {
  return sourceSize >= 1 && sourceSize <= kMaxPrefilterPlanSize &&
         (sourceSize & (sourceSize - 1)) == 0;
}

size_t PrefilterPlan::tapCount(int mip) const {
  if (mip < 1 || mip >= mipCount_) return 0;
  const Row& a = rows_[mipRowBase_[size_t(mip)]];
  const Row& b = rows_[mipRowBase_[size_t(mip) + 1]];
  return (b.tap - a.tap) + (b.linear - a.linear);
}

bool PrefilterPlan::isRadiance(uint32_t index, int* level) const {
  int k = 0;
  while (k + 1 < int(levelOffset_.size()) - 1 && index >= levelOffset_[size_t(k) + 1]) ++k;
  if (level) *level = k;
  return k == 0 || (index - levelOffset_[size_t(k)]) % 3 == 0;
}

size_t PrefilterPlan::bytes() const {
  size_t b = packed_.size() * sizeof(Tap) + linear_.size() * sizeof(LinearTap) +
             rows_.size() * sizeof(Row) + escapes_.size() * sizeof(uint32_t) +
             mipRowBase_.size() * sizeof(size_t) + levelOffset_.size() * sizeof(size_t);
  for (const std::vector<Child>& c : children_) b += c.size() * sizeof(Child);
  return b;
}

void PrefilterPlan::append(const std::vector<CubemapTap>& taps) {
  // taps: sorted by index, so a coarse texel's radiance, X and Y are consecutive. A texel with
  // moment weights becomes one linear tap, any other weight a radiance tap.
  std::vector<CubemapTap> radiance;
  std::vector<std::array<CubemapTap, 3>> linear;
  for (size_t i = 0; i < taps.size(); ++i) {
    int level = 0;
    if (!isRadiance(taps[i].index, &level)) continue;  // taken with its texel's radiance
    const uint32_t base = taps[i].index;
    float w[3] = {taps[i].weight, 0.0f, 0.0f};
    size_t j = i + 1;
    for (; level > 0 && j < taps.size() && taps[j].index < base + 3; ++j)
      w[taps[j].index - base] = taps[j].weight;
    if (w[1] != 0.0f || w[2] != 0.0f)
      linear.push_back(
          {CubemapTap{base, w[0]}, CubemapTap{base + 1, w[1]}, CubemapTap{base + 2, w[2]}});
    else
      radiance.push_back(taps[i]);
  }
  // Moments without their texel's radiance (dropped): linear taps of radiance weight 0.
  for (size_t i = 0; i < taps.size(); ++i) {
    if (isRadiance(taps[i].index)) continue;
    const uint32_t base = taps[i].index - (taps[i].index - levelOffset_[1]) % 3;
    if (i > 0 && taps[i - 1].index >= base && taps[i - 1].index < taps[i].index) continue;
    float w[3] = {0.0f, 0.0f, 0.0f};
    for (size_t j = i; j < taps.size() && taps[j].index < base + 3; ++j)
      w[taps[j].index - base] = taps[j].weight;
    linear.push_back(
        {CubemapTap{base, w[0]}, CubemapTap{base + 1, w[1]}, CubemapTap{base + 2, w[2]}});
  }
  std::sort(linear.begin(), linear.end(),
            [](const auto& a, const auto& b) { return a[0].index < b[0].index; });

  Row row{};
  row.tap = uint32_t(packed_.size());
  row.linear = uint32_t(linear_.size());
  row.escape = uint32_t(escapes_.size());
  row.first = radiance.empty() ? 0u : radiance[0].index;
  row.linearFirst = linear.empty() ? 0u : linear[0][0].index;
  double radianceMax = 0.0, momentMax = 0.0;
  for (const CubemapTap& t : radiance)
    if (t.weight > radianceMax) radianceMax = t.weight, row.correctionIndex = t.index;
  for (const auto& l : linear) {
    if (l[0].weight > radianceMax) radianceMax = l[0].weight, row.correctionIndex = l[0].index;
    momentMax = std::max({momentMax, std::abs(double(l[1].weight)), std::abs(double(l[2].weight))});
  }
  row.radianceScale = float(radianceMax);
  row.momentScale = float(momentMax);
  // Each weight to the nearest 16-bit float; what the radiance weights then miss of 1 goes on
  // the largest, in full precision, so that a constant stays constant.
  double sum = 0.0;
  auto radianceWeight = [&](float w) {
    const uint16_t q = w > 0.0f ? encodeWeight(w / row.radianceScale) : 0;
    if (q) sum += double(decodeWeight(q)) * row.radianceScale;
    return q;
  };
  auto momentWeight = [&](float w) {
    return w != 0.0f ? encodeMoment(w / row.momentScale) : uint16_t(0);
  };
  auto step = [&](uint32_t& previous, uint32_t index) {
    const uint32_t d = index - previous;
    previous = index;
    if (d < 0xFFFFu) return uint16_t(d);
    escapes_.push_back(index);
    return uint16_t(0xFFFFu);
  };
  uint32_t previous = row.first;
  for (const CubemapTap& t : radiance)
    packed_.push_back({step(previous, t.index), radianceWeight(t.weight)});
  previous = row.linearFirst;
  for (const auto& l : linear)
    linear_.push_back({step(previous, l[0].index), radianceWeight(l[0].weight),
                       momentWeight(l[1].weight), momentWeight(l[2].weight)});
  row.correction = radianceMax > 0.0 ? float(1.0 - sum) : 0.0f;
  rows_.push_back(row);
}

PrefilterPlanRow PrefilterPlan::row(int mip, size_t texel) const {
  PrefilterPlanRow out;
  if (mip < 1 || mip >= mipCount_) return out;
  const size_t r = mipRowBase_[size_t(mip)] + texel;
  if (r >= mipRowBase_[size_t(mip) + 1]) return out;
  const Row& row = rows_[r];
  uint32_t escape = row.escape;
  auto radiance = [&](uint32_t index, uint16_t w) {
    const float correction = index == row.correctionIndex ? row.correction : 0.0f;
    if (w || correction != 0.0f)
      out.radiance.push_back(
          {index, (w ? decodeWeight(w) * row.radianceScale : 0.0f) + correction});
  };
  uint32_t index = row.first;
  for (uint32_t i = row.tap; i < rows_[r + 1].tap; ++i) {
    const Tap& t = packed_[i];
    index = t.step == 0xFFFFu ? escapes_[escape++] : index + t.step;
    radiance(index, t.weight);
  }
  index = row.linearFirst;
  for (uint32_t i = row.linear; i < rows_[r + 1].linear; ++i) {
    const LinearTap& t = linear_[i];
    index = t.step == 0xFFFFu ? escapes_[escape++] : index + t.step;
    radiance(index, t.radiance);
    for (int k = 0; k < 2; ++k)
      if (t.moment[k])
        out.moments.push_back({index + 1 + k, decodeMoment(t.moment[k]) * row.momentScale});
  }
  return out;
}

void PrefilterPlan::prefilter(const Cubemap& source, std::vector<Cubemap>& chain,
                              std::vector<glm::vec4>& scratch) const {
  if (empty() || source.size != sourceSize_) {
    chain.clear();
    return;
  }
  scratch.resize(scratchSize_);
  glm::vec4* s = scratch.data();
  for (size_t i = 0; i < source.texels.size(); ++i) s[i] = glm::vec4(source.texels[i], 0.0f);
  // Each coarser level from the one below: C = Σ w C', and the moments about the parent's
  // centroid X = Σ w (X' + C' dx) (the children's own moments moved to the parent's centroid;
  // level 0's texels have none).
  for (size_t k = 0; k < children_.size(); ++k) {
    const int n = sourceSize_ >> k;
    const int m = n / 2;
    const size_t stride = k == 0 ? 1 : 3;
    const glm::vec4* fine = s + levelOffset_[k];
    glm::vec4* coarse = s + levelOffset_[k + 1];
    const Child* ch = children_[k].data();
    for (int face = 0; face < kCubeFaceCount; ++face) {
      const size_t fb = size_t(face) * size_t(n) * size_t(n);
      const size_t cb = size_t(face) * size_t(m) * size_t(m);
      for (int y = 0; y < m; ++y)
        for (int x = 0; x < m; ++x) {
          glm::vec4 c(0.0f), mx(0.0f), my(0.0f);
          for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) {
              const size_t xy = size_t((2 * y + j) * n + 2 * x + i);
              const Child& d = ch[xy];
              const glm::vec4* f = fine + stride * (fb + xy);
              const glm::vec4 v = d.weight * f[0];
              c += v;
              mx += d.dx * v;
              my += d.dy * v;
              if (stride == 3) {
                mx += d.weight * f[1];
                my += d.weight * f[2];
              }
            }
          glm::vec4* out = coarse + 3 * (cb + size_t(y * m + x));
          out[0] = c;
          out[1] = mx;
          out[2] = my;
        }
    }
  }
  chain.resize(size_t(mipCount_));
  chain[0].size = source.size;
  chain[0].texels = source.texels;
  for (int mip = 1; mip < mipCount_; ++mip) {
    Cubemap& out = chain[size_t(mip)];
    out.size = std::max(1, sourceSize_ >> mip);
    out.texels.resize(size_t(kCubeFaceCount) * size_t(out.size) * size_t(out.size));
    const size_t base = mipRowBase_[size_t(mip)];
    for (size_t r = 0; r < out.texels.size(); ++r) {
      const Row& row = rows_[base + r];
      const Row& next = rows_[base + r + 1];
      const uint32_t* escape = escapes_.data() + row.escape;
      Sum radiance =
          dotRadiance(packed_.data() + row.tap, packed_.data() + next.tap, row.first, escape, s);
      Sum moments;
      dotLinear(linear_.data() + row.linear, linear_.data() + next.linear, row.linearFirst, escape,
                s, radiance, moments);
      out.texels[r] =
          glm::vec3(row.radianceScale * radiance.value() + row.momentScale * moments.value() +
                    row.correction * s[row.correctionIndex]);
    }
  }
}

std::vector<Cubemap> PrefilterPlan::prefilter(const Cubemap& source) const {
  std::vector<Cubemap> chain;
  std::vector<glm::vec4> scratch;
  prefilter(source, chain, scratch);
  return chain;
}

std::shared_ptr<const PrefilterPlan> sharedPrefilterPlan(int sourceSize, int mipCount) {
  if (!PrefilterPlan::supports(sourceSize) || mipCount < 1) return nullptr;
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::shared_ptr<const PrefilterPlan>> plans;
  const std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<const PrefilterPlan>& plan = plans[{sourceSize, mipCount}];
  if (!plan)
    plan = std::make_shared<const PrefilterPlan>(PrefilterPlan::build(sourceSize, mipCount));
  return plan;
}

}  // namespace afterglow::runtime
