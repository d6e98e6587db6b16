#include "afterglow/runtime/solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#include <xmmintrin.h>
#define AFTERGLOW_SSE2 1
#endif
// GCC and Clang on x86-64: kernels built for AVX2 beside the baseline's, picked at run time.
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define AFTERGLOW_AVX2_DISPATCH 1
#endif


namespace afterglow::runtime {

namespace {

// Half to float for normal and subnormal halves (the sky transfer holds no Inf or NaN): the
// bits shifted into a float's place are the value × 2^-112, rescaled by one multiply.
inline float halfBits(uint16_t h) {
  const uint32_t bits = uint32_t(h & 0x7fffu) << 13;
  float f;
  std::memcpy(&f, &bits, 4);
  f *= 5.192296858534828e+33f;  // 2^112
  return (h & 0x8000u) ? -f : f;
}

// Σ sh[i] · transfer[i] over one texel's or cluster's half-float sky transfer.
glm::vec3 evalSky(const glm::vec3 sh[kShCount], const uint16_t* transfer) {
  glm::vec3 sum(0.0f);
  for (int i = 0; i < kShCount; ++i) sum += sh[i] * halfBits(transfer[i]);
  return sum;
}

// Σ weight[k] · x[column[k]] over a row of a SparseMatrix of vec4 values.
inline glm::vec4 mixRow(const uint32_t* rowStart, const uint32_t* column, const float* weight,
                        size_t row, const glm::vec4* x) {
#ifdef AFTERGLOW_SSE2
  // Four lanes at once, in the scalar loop's order (the same bits). Most rows hold one or two
  // entries (a cluster's gather points, a texel's): the first one starts the sum instead of an
  // add to zero, which measured 15% off a pass.
  uint32_t k = rowStart[row];
  const uint32_t end = rowStart[row + 1];
  glm::vec4 out(0.0f);
  if (k == end) return out;
  __m128 sum = _mm_mul_ps(_mm_set1_ps(weight[k]), _mm_loadu_ps(&x[column[k]].x));
  for (++k; k < end; ++k)
    sum = _mm_add_ps(sum, _mm_mul_ps(_mm_set1_ps(weight[k]), _mm_loadu_ps(&x[column[k]].x)));
  _mm_storeu_ps(&out.x, sum);
  return out;
#else
  glm::vec4 sum(0.0f);
  for (uint32_t k = rowStart[row]; k < rowStart[row + 1]; ++k) sum += weight[k] * x[column[k]];
  return sum;
#endif
}

inline glm::vec4 mixRow(const SparseMatrix& m, size_t row, const glm::vec4* x) {
  return mixRow(m.rowStart.data(), m.column.data(), m.weight.data(), row, x);
}

// The same over rows [first, last) into out, with the arrays' pointers held once (the per-pass
// loops over every cluster).
inline void mixRows(const SparseMatrix& m, size_t first, size_t last, const glm::vec4* x,
                    glm::vec4* out) {
  const uint32_t* rowStart = m.rowStart.data();
  const uint32_t* column = m.column.data();
  const float* weight = m.weight.data();
  for (size_t row = first; row < last; ++row) out[row] = mixRow(rowStart, column, weight, row, x);
}

}  // namespace

glm::vec3 boostAlbedo(glm::vec3 albedo, float boost) {
  if (boost <= 1.0f) return albedo;
  glm::vec3 a = glm::clamp(albedo, glm::vec3(0.0f), glm::vec3(1.0f));
  return glm::pow(a, glm::vec3(1.0f / boost));
}

void constantSkySh(glm::vec3 radiance, glm::vec3 sh[kShCount]) {
  // Y00 = 1 / (2 sqrt(pi)); projecting a constant L gives L * sqrt(4 pi) * ... = L * 2 sqrt(pi).
  for (int i = 0; i < kShCount; ++i) sh[i] = glm::vec3(0.0f);
  sh[0] = radiance * (2.0f * std::sqrt(3.14159265358979f));
}

namespace {
void probeBounceGeneric(const SparseLinks& links, size_t firstRow, uint32_t bins,
                        const uint8_t* groupRegion, const glm::vec4* binSh, const glm::vec4* r,
                        float* sums, glm::vec4 out[kShCount]);
#ifdef AFTERGLOW_AVX2_DISPATCH
void probeBounceAvx2(const SparseLinks& links, size_t firstRow, uint32_t bins,
                     const uint8_t* groupRegion, const glm::vec4* binSh, const glm::vec4* r,
                     float* sums, glm::vec4 out[kShCount]);
#endif
}  // namespace

Solver::Solver(const TransportData& data) : data_(data) {
  const size_t clusters = data.clusterCount, rows = data.links.rows();
  albedo_.resize(clusters);
  clusterDirect_.resize(clusters);
  clusterSky_.resize(clusters);
  reflected_.assign(clusters, glm::vec3(0.0f));
  reflected4_.assign(data.linkTargetCount(), glm::vec4(0.0f));
  gathered_.assign(rows, glm::vec4(0.0f));
  filtered_.assign(data.gatherPointCount, glm::vec4(0.0f));
  scratch_.assign(data.gatherPointCount, glm::vec4(0.0f));
  blockChange_.assign((clusters + kBlock - 1) / kBlock, 0.0f);
  sourceScale_.resize(data.sources.size());
  directScale_.resize(data.sources.size());
  // The probes' region weights, paired (probeBounceGeneric); an odd last region pairs with
  // zeros.
  const uint32_t bins = data.probes.bins;
  probeBinSh_.assign(size_t((bins + 1) / 2) * kShCount * 2, glm::vec4(0.0f));
  for (uint32_t b = 0; b < bins && data.probes.binSh.size() >= size_t(bins) * kShCount; ++b)
    for (int i = 0; i < kShCount; ++i)
      probeBinSh_[(size_t(b / 2) * kShCount + size_t(i)) * 2 + (b & 1)] =
          glm::vec4(data.probes.binSh[size_t(b) * kShCount + size_t(i)]);
  // Per group of four links, its region (the row's index within its probe).
  const SparseLinks& links = data.probes.links;
  probeGroupRegion_.assign(links.size() / kLinkGroup, 0);
  for (size_t row = 0; bins > 0 && row < links.rows(); ++row)
    for (uint32_t k = links.rowStart[row]; k < links.rowStart[row + 1]; k += kLinkGroup)
      probeGroupRegion_[k / kLinkGroup] = uint8_t(row % bins);
  probeBounce_ = probeBounceGeneric;
#ifdef AFTERGLOW_AVX2_DISPATCH
  // AFTERGLOW_NO_AVX2 (any value) keeps the baseline kernels, as on a CPU without AVX2: to
  // compare the two, or to have the same bits on every machine.
  if (!std::getenv("AFTERGLOW_NO_AVX2") && __builtin_cpu_supports("avx2") &&
      __builtin_cpu_supports("fma"))
    probeBounce_ = probeBounceAvx2;
#endif
  prepare();
}

void Solver::prepare(unsigned changed) {
  const uint32_t n = data_.clusterCount;
  // Emissive sources' scales follow their materials: every source's is recomputed (a few).
  for (size_t i = 0; i < data_.sources.size(); ++i) {
    sourceScale_[i] = sourceScale(data_, data_.sources[i]);
    directScale_[i] = directScale(data_, data_.sources[i]);
  }
  if (changed & kMaterialsChanged)
    for (uint32_t c = 0; c < n; ++c) {
      const MaterialParams& m = data_.materials[data_.clusterMaterial[c]];
      albedo_[c] = boostAlbedo(m.albedo * data_.clusterAlbedoTexture[c], data_.albedoBoost);
    }
  if (changed & kSkyChanged)
    for (uint32_t c = 0; c < n; ++c)
      clusterSky_[c] = data_.clusterSky.empty()
                           ? glm::vec3(0.0f)
                           : evalSky(data_.skySh, &data_.clusterSky[size_t(c) * kShCount]);
  // The sky first, then the sources in order: the same sum whatever changed.
  std::copy(clusterSky_.begin(), clusterSky_.end(), clusterDirect_.begin());
  for (size_t i = 0; i < data_.sources.size(); ++i) {
    const Source& s = data_.sources[i];
    glm::vec3 scale = sourceScale_[i];
    if (s.kind == SourceKind::Light) scale *= s.bounceIntensity;
    if (scale == glm::vec3(0.0f) || s.clusterTransfer.empty()) continue;
    for (uint32_t c = 0; c < n; ++c) clusterDirect_[c] += scale * s.clusterTransfer[c];
  }
}

void Solver::reset() {
  std::fill(reflected_.begin(), reflected_.end(), glm::vec3(0.0f));
  std::fill(reflected4_.begin(), reflected4_.end(), glm::vec4(0.0f));
  std::fill(gathered_.begin(), gathered_.end(), glm::vec4(0.0f));
}


namespace {

// Σ link weight × R[target] over one row of links (the hot loop of a bounce).
inline glm::vec4 linkRow(const SparseLinks& links, size_t row, const glm::vec4* r) {
  const uint32_t* link = links.link.data();
  const uint32_t mask = links.targetMask(), bits = links.targetBits;
  const uint32_t begin = links.rowStart[row], end = links.rowStart[row + 1];
#ifdef AFTERGLOW_SSE2
  // Four links at a time (rows are padded to fours: no tail): their weight codes converted
  // together (through a store: broadcasting them from memory is cheaper than shuffling them out
  // of a register), their targets cut out with scalar instructions (which run beside the vector
  // ones), four accumulators (so the adds do not wait on each other), R padded to 16 bytes for
  // aligned loads. (Prefetching R in software measured slower, and R in half floats no faster
  // for the precision it loses.)
  const __m128i bitsV = _mm_cvtsi32_si128(int(bits));
  alignas(16) float w[4];
  __m128 a0 = _mm_setzero_ps(), a1 = a0, a2 = a0, a3 = a0;
  for (uint32_t k = begin; k < end; k += kLinkGroup) {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(link + k));
    _mm_store_ps(w, _mm_cvtepi32_ps(_mm_srl_epi32(v, bitsV)));
    uint64_t lo, hi;
    std::memcpy(&lo, link + k, 8);
    std::memcpy(&hi, link + k + 2, 8);
    const uint32_t t0 = uint32_t(lo) & mask, t1 = uint32_t(lo >> 32) & mask;
    const uint32_t t2 = uint32_t(hi) & mask, t3 = uint32_t(hi >> 32) & mask;
    a0 = _mm_add_ps(a0, _mm_mul_ps(_mm_set1_ps(w[0]), _mm_load_ps(&r[t0].x)));
    a1 = _mm_add_ps(a1, _mm_mul_ps(_mm_set1_ps(w[1]), _mm_load_ps(&r[t1].x)));
    a2 = _mm_add_ps(a2, _mm_mul_ps(_mm_set1_ps(w[2]), _mm_load_ps(&r[t2].x)));
    a3 = _mm_add_ps(a3, _mm_mul_ps(_mm_set1_ps(w[3]), _mm_load_ps(&r[t3].x)));
  }
  const __m128 sum = _mm_add_ps(_mm_add_ps(a0, a1), _mm_add_ps(a2, a3));
  glm::vec4 out;
  _mm_storeu_ps(&out.x, _mm_mul_ps(sum, _mm_set1_ps(links.rowScale[row])));
  return out;
#else
  glm::vec4 sum(0.0f);
  for (uint32_t k = begin; k < end; ++k) sum += float(link[k] >> bits) * r[link[k] & mask];
  return sum * links.rowScale[row];
#endif
}

// A probe's bounced light as SH (four channels per coefficient): each region's mean radiance
// (its row of links) spread over the nine coefficients by the region's weights. `binSh` holds
// the weights of regions 2q and 2q + 1 side by side, each repeated in four lanes ([q][i][2]
// vec4s), so one load serves a multiply without a broadcast.
//
// A probe's regions hold few links each (0 to 3 groups of four, unpredictably), so a loop per
// row would mispredict its exit every other row. Instead one loop runs over the probe's
// groups, each adding its four links into its region's sum (groupRegion: per group of links,
// its region), then the regions' sums are spread over the coefficients. Each group's weight
// codes are scaled by its row's scale as they are converted, so the sums come out final and
// the spread is a bare multiply-add per coefficient.
//
// `sums` (four floats a region, for bins rounded up to even, 32-byte aligned) is the caller's:
// zero on entry, and the spread leaves it zero again, so a run of probes zeroes it once.
//
// The links stream from memory (Sponza's probes hold 58 MB of them, 870 bytes a probe), and
// both kernels prefetch them kProbeStreamAhead entries ahead: the spread's few hundred
// instructions between one probe's links and the next's keep the processor from running ahead
// to the next probe's links on its own. (Prefetching the R entries those links will read as
// well measured slower: what R a probe reads mostly sits in L2 already.)
constexpr uint32_t kProbeStreamAhead = 512;  // 2 KB

#ifdef AFTERGLOW_SSE2
// Prefetches the links kProbeStreamAhead entries after k (the last group's near the end).
inline void prefetchLinks(const uint32_t* link, size_t k, size_t lastGroup) {
  _mm_prefetch(reinterpret_cast<const char*>(link + std::min<size_t>(k + kProbeStreamAhead, lastGroup)),
               _MM_HINT_T0);
}
#endif

void probeBounceGeneric(const SparseLinks& links, size_t firstRow, uint32_t bins,
                        const uint8_t* groupRegion, const glm::vec4* binSh, const glm::vec4* r,
                        float* sums, glm::vec4 out[kShCount]) {
  const uint32_t* link = links.link.data();
  const float* scale = links.rowScale.data() + firstRow;
  const uint32_t mask = links.targetMask(), bits = links.targetBits;
  const uint32_t begin = links.rowStart[firstRow], end = links.rowStart[firstRow + bins];
#ifdef AFTERGLOW_SSE2
  const size_t lastGroup = links.size() - kLinkGroup;  // the prefetch stays inside the links
  const __m128i bitsV = _mm_cvtsi32_si128(int(bits));
  alignas(16) float w[4];
  for (uint32_t k = begin; k < end; k += kLinkGroup) {
    prefetchLinks(link, k, lastGroup);
    const uint32_t region = groupRegion[k / kLinkGroup];
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(link + k));
    const __m128 codes = _mm_cvtepi32_ps(_mm_srl_epi32(v, bitsV));
    _mm_store_ps(w, _mm_mul_ps(codes, _mm_set1_ps(scale[region])));
    const __m128 s01 = _mm_add_ps(_mm_mul_ps(_mm_set1_ps(w[0]), _mm_load_ps(&r[link[k] & mask].x)),
                                  _mm_mul_ps(_mm_set1_ps(w[1]), _mm_load_ps(&r[link[k + 1] & mask].x)));
    const __m128 s23 = _mm_add_ps(_mm_mul_ps(_mm_set1_ps(w[2]), _mm_load_ps(&r[link[k + 2] & mask].x)),
                                  _mm_mul_ps(_mm_set1_ps(w[3]), _mm_load_ps(&r[link[k + 3] & mask].x)));
    float* sum = sums + 4 * region;
    _mm_store_ps(sum, _mm_add_ps(_mm_load_ps(sum), _mm_add_ps(s01, s23)));
  }
  // The first region starts the coefficients' sums (zeroing them first compiled to a slow
  // rep stos; bins >= 1 with probes).
  __m128 wv = _mm_load_ps(sums);
  _mm_store_ps(sums, _mm_setzero_ps());
  __m128 acc[kShCount];
  for (int i = 0; i < kShCount; ++i) acc[i] = _mm_mul_ps(_mm_load_ps(&binSh[2 * i].x), wv);
  for (uint32_t b = 1; b < bins; ++b) {
    wv = _mm_load_ps(sums + 4 * b);
    _mm_store_ps(sums + 4 * b, _mm_setzero_ps());
    const glm::vec4* y = binSh + size_t(b / 2) * kShCount * 2 + (b & 1);
    for (int i = 0; i < kShCount; ++i)
      acc[i] = _mm_add_ps(acc[i], _mm_mul_ps(_mm_load_ps(&y[2 * i].x), wv));
  }
  for (int i = 0; i < kShCount; ++i) _mm_storeu_ps(&out[i].x, acc[i]);
#else
  for (uint32_t k = begin; k < end; ++k) {
    const uint32_t region = groupRegion[k / kLinkGroup];
    const float w = float(link[k] >> bits) * scale[region];
    const glm::vec4& x = r[link[k] & mask];
    for (int c = 0; c < 4; ++c) sums[4 * region + c] += w * x[c];
  }
  for (int i = 0; i < kShCount; ++i) out[i] = glm::vec4(0.0f);
  for (uint32_t b = 0; b < bins; ++b) {
    const glm::vec4 w(sums[4 * b], sums[4 * b + 1], sums[4 * b + 2], sums[4 * b + 3]);
    const glm::vec4* y = binSh + size_t(b / 2) * kShCount * 2 + (b & 1);
    for (int i = 0; i < kShCount; ++i) out[i] += y[2 * i] * w;
    for (int c = 0; c < 4; ++c) sums[4 * b + c] = 0.0f;
  }
#endif
}

#ifdef AFTERGLOW_AVX2_DISPATCH
// R's entries at the two byte offsets packed in `offsets`, in one 8-lane vector.
__attribute__((target("avx2,fma"))) inline __m256 loadPair(const char* r, uint64_t offsets) {
  return _mm256_insertf128_ps(
      _mm256_castps128_ps256(_mm_load_ps(reinterpret_cast<const float*>(r + uint32_t(offsets)))),
      _mm_load_ps(reinterpret_cast<const float*>(r + (offsets >> 32))), 1);
}

// sum += Σ of one group of four links: `offsets` their byte offsets into R, their weights the
// lanes of w that spread01 and spread23 repeat over the halves of 8-lane vectors.
__attribute__((target("avx2,fma"))) inline void addGroup(float* sum, const char* r, __m128i offsets,
                                                         __m256 w, __m256i spread01,
                                                         __m256i spread23) {
  const __m256 r01 = loadPair(r, uint64_t(_mm_cvtsi128_si64(offsets)));
  const __m256 r23 = loadPair(r, uint64_t(_mm_extract_epi64(offsets, 1)));
  const __m256 s = _mm256_fmadd_ps(_mm256_permutevar8x32_ps(w, spread01), r01,
                                   _mm256_mul_ps(_mm256_permutevar8x32_ps(w, spread23), r23));
  _mm_store_ps(sum, _mm_add_ps(_mm_load_ps(sum), _mm_add_ps(_mm256_castps256_ps128(s),
                                                              _mm256_extractf128_ps(s, 1))));
}

// probeBounceGeneric with AVX2 and FMA: two groups a step (their weight codes converted and
// scaled as one 8-lane vector, their targets cut out together: 6% faster than a group a step),
// two links per multiply-add (R's two entries loaded into one 8-lane vector, their weights
// spread over its halves by one permute), and two regions per multiply-add over the
// coefficients.
__attribute__((target("avx2,fma"))) void probeBounceAvx2(const SparseLinks& links, size_t firstRow,
                                                         uint32_t bins, const uint8_t* groupRegion,
                                                         const glm::vec4* binSh,
                                                         const glm::vec4* r, float* sums,
                                                         glm::vec4 out[kShCount]) {
  const uint32_t* link = links.link.data();
  const float* scale = links.rowScale.data() + firstRow;
  const uint32_t begin = links.rowStart[firstRow], end = links.rowStart[firstRow + bins];
  const size_t lastGroup = links.size() - kLinkGroup;  // the prefetch stays inside the links
  const __m128i bits = _mm_cvtsi32_si128(int(links.targetBits));
  const __m256i mask = _mm256_set1_epi32(int(links.targetMask()));
  const __m256i lanes0 = _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1);
  const __m256i lanes1 = _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3);
  const __m256i lanes2 = _mm256_setr_epi32(4, 4, 4, 4, 5, 5, 5, 5);
  const __m256i lanes3 = _mm256_setr_epi32(6, 6, 6, 6, 7, 7, 7, 7);
  const char* base = reinterpret_cast<const char*>(r);
  uint32_t k = begin;
  for (; k + 2 * kLinkGroup <= end; k += 2 * kLinkGroup) {
    prefetchLinks(link, k, lastGroup);
    const uint32_t a = groupRegion[k / kLinkGroup], b = groupRegion[k / kLinkGroup + 1];
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(link + k));
    const __m256 rowScales = _mm256_insertf128_ps(
        _mm256_castps128_ps256(_mm_broadcast_ss(scale + a)), _mm_broadcast_ss(scale + b), 1);
    const __m256 w = _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srl_epi32(v, bits)), rowScales);
    const __m256i offsets = _mm256_slli_epi32(_mm256_and_si256(v, mask), 4);  // bytes into R
    addGroup(sums + 4 * a, base, _mm256_castsi256_si128(offsets), w, lanes0, lanes1);
    addGroup(sums + 4 * b, base, _mm256_extracti128_si256(offsets, 1), w, lanes2, lanes3);
  }
  if (k < end) {  // an odd last group
    const uint32_t a = groupRegion[k / kLinkGroup];
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(link + k));
    const __m256 w = _mm256_castps128_ps256(
        _mm_mul_ps(_mm_cvtepi32_ps(_mm_srl_epi32(v, bits)), _mm_broadcast_ss(scale + a)));
    const __m128i offsets = _mm_slli_epi32(_mm_and_si128(v, _mm256_castsi256_si128(mask)), 4);
    addGroup(sums + 4 * a, base, offsets, w, lanes0, lanes1);
  }
  // The first pair of regions starts the coefficients' sums (zeroing them first compiled to a
  // slow rep stos; bins >= 1 with probes).
  const float* y = &binSh[0].x;
  __m256 w = _mm256_load_ps(sums);
  _mm256_store_ps(sums, _mm256_setzero_ps());
  __m256 acc[kShCount];
  for (int i = 0; i < kShCount; ++i) acc[i] = _mm256_mul_ps(_mm256_loadu_ps(y + 8 * i), w);
  for (uint32_t b = 2; b < bins; b += 2) {
    y += 8 * kShCount;
    w = _mm256_load_ps(sums + 4 * b);
    _mm256_store_ps(sums + 4 * b, _mm256_setzero_ps());
    for (int i = 0; i < kShCount; ++i) acc[i] = _mm256_fmadd_ps(_mm256_loadu_ps(y + 8 * i), w, acc[i]);
  }
  for (int i = 0; i < kShCount; ++i)
    _mm_storeu_ps(&out[i].x, _mm_add_ps(_mm256_castps256_ps128(acc[i]), _mm256_extractf128_ps(acc[i], 1)));
}
#endif

}  // namespace

void Solver::gatherRows(const SparseLinks& links, glm::vec4* gathered) {
  const glm::vec4* r = reflected4_.data();
  forBlocks(links.rows(), [&](size_t first, size_t last) {
    for (size_t row = first; row < last; ++row) gathered[row] = linkRow(links, row, r);
  });
}

void Solver::probeRadiance(size_t first, size_t count, ShL2* out) const {
  const ProbeTransport& probes = data_.probes;
  const size_t n = probes.count();
  if (first >= n) return;
  count = std::min(count, n - first);
  bool hasSky = false;
  for (int i = 0; i < kShCount; ++i) hasSky = hasSky || data_.skySh[i] != glm::vec3(0.0f);
  const uint32_t bins = probes.bins;
  const float indirect = data_.indirectIntensity;
  const glm::vec4* r = reflected4_.data();
#ifdef AFTERGLOW_SSE2
  __m128 sky4[kShCount];
  for (int i = 0; i < kShCount; ++i)
    sky4[i] = _mm_setr_ps(data_.skySh[i].x, data_.skySh[i].y, data_.skySh[i].z, 0.0f);
#endif
  forBlocks(count, [&](size_t begin, size_t end) {
    alignas(32) float sums[(kMaxProbeRegions + 1) * 4] = {};  // the kernel leaves it zero
    for (size_t k = begin; k < end; ++k) {
      const size_t p = first + k;
      glm::vec4 acc[kShCount];
      probeBounce_(probes.links, p * bins, bins, probeGroupRegion_.data(), probeBinSh_.data(), r,
                   sums, acc);
      // The bounced light, the sources' and the sky's, four lanes a coefficient (the fourth
      // stays 0 and is dropped): as glm::vec3 arithmetic this compiled to scalar code with
      // spills, an eighth of the refresh.
#ifdef AFTERGLOW_SSE2
      __m128 sh[kShCount];
      for (int i = 0; i < kShCount; ++i)
        sh[i] = _mm_mul_ps(_mm_loadu_ps(&acc[i].x), _mm_set1_ps(indirect));
      for (size_t s = 0; s < data_.sources.size(); ++s) {
        const std::vector<float>& transfer = data_.sources[s].probeTransfer;
        const glm::vec3 scale = directScale_[s];
        if (transfer.empty() || scale == glm::vec3(0.0f)) continue;
        const __m128 scale4 = _mm_setr_ps(scale.x, scale.y, scale.z, 0.0f);
        const float* t = &transfer[p * kShCount];
        for (int i = 0; i < kShCount; ++i)
          sh[i] = _mm_add_ps(sh[i], _mm_mul_ps(scale4, _mm_set1_ps(t[i])));
      }
      if (hasSky) {
        // K is symmetric: each stored entry (row by row, j >= i) serves K_ij and K_ji.
        const uint16_t* k2 = &probes.sky[p * kProbeSkyCount];
        for (int i = 0; i < kShCount; ++i) {
          sh[i] = _mm_add_ps(sh[i], _mm_mul_ps(_mm_set1_ps(halfBits(*k2++)), sky4[i]));
          for (int j = i + 1; j < kShCount; ++j) {
            const __m128 kij = _mm_set1_ps(halfBits(*k2++));
            sh[i] = _mm_add_ps(sh[i], _mm_mul_ps(kij, sky4[j]));
            sh[j] = _mm_add_ps(sh[j], _mm_mul_ps(kij, sky4[i]));
          }
        }
      }
      // Three floats a coefficient: each store's fourth lane is overwritten by the next.
      float packed[kShCount * 3 + 1];
      for (int i = 0; i < kShCount; ++i) _mm_storeu_ps(packed + 3 * i, sh[i]);
      std::memcpy(out[k].c, packed, sizeof(out[k].c));
#else
      ShL2 sh;
      for (int i = 0; i < kShCount; ++i) sh.c[i] = indirect * glm::vec3(acc[i]);
      for (size_t s = 0; s < data_.sources.size(); ++s) {
        const std::vector<float>& transfer = data_.sources[s].probeTransfer;
        const glm::vec3 scale = directScale_[s];
        if (transfer.empty() || scale == glm::vec3(0.0f)) continue;
        for (int i = 0; i < kShCount; ++i) sh.c[i] += scale * transfer[p * kShCount + size_t(i)];
      }
      if (hasSky) {
        const uint16_t* k2 = &probes.sky[p * kProbeSkyCount];
        for (int i = 0; i < kShCount; ++i) {
          sh.c[i] += halfBits(*k2++) * data_.skySh[i];
          for (int j = i + 1; j < kShCount; ++j) {
            const float kij = halfBits(*k2++);
            sh.c[i] += kij * data_.skySh[j];
            sh.c[j] += kij * data_.skySh[i];
          }
        }
      }
      out[k] = sh;
#endif
    }
  });
}

float Solver::iterate() {
  const SparseMatrix& take = data_.clusterGather;
  forBlocks(data_.clusterCount, [&](size_t first, size_t last) {
    // First what each cluster takes in (into R's slots), then R and its change.
    glm::vec4* r4 = reflected4_.data();
    mixRows(take, first, last, gathered_.data(), r4);
    const glm::vec3* albedo = albedo_.data();
    const glm::vec3* direct = clusterDirect_.data();
    glm::vec3* reflected = reflected_.data();
    float maxChange = 0.0f;
    for (size_t c = first; c < last; ++c) {
      const glm::vec3 r = albedo[c] * (direct[c] + glm::vec3(r4[c]));
      const glm::vec3 diff = glm::abs(r - reflected[c]);
      const float mag = std::max(r.x, std::max(r.y, r.z));
      const float change = std::max(diff.x, std::max(diff.y, diff.z));
      if (mag > 1e-20f) maxChange = std::max(maxChange, change / mag);
      reflected[c] = r;
      r4[c] = glm::vec4(r, 0.0f);
    }
    blockChange_[first / kBlock] = maxChange;
  });
  // The far clusters' reflected light, the mean of their clusters', after the clusters'.
  const SparseMatrix& far = data_.farClusters;
  glm::vec4* farReflected = reflected4_.data() + data_.clusterCount;
  forBlocks(far.rows(), [&](size_t first, size_t last) {
    mixRows(far, first, last, reflected4_.data(), farReflected);
  });
  // The shared far fields (R's last slots) from the far clusters, then every row.
  gatherRows(data_.sharedFar, reflected4_.data() + data_.sharedFarBase());
  gatherRows(data_.links, gathered_.data());
  float maxChange = 0.0f;
  for (float c : blockChange_) maxChange = std::max(maxChange, c);
  return maxChange;
}

int Solver::solve(const SolveOptions& options) {
  const int limit = options.maxBounces > 0 ? options.maxBounces : 1000;
  int passes = 0;
  while (passes < limit) {
    const float change = iterate();
    ++passes;
    if (options.maxBounces <= 0 && change < options.tolerance) break;
  }
  return passes;
}

void Solver::skyTexels(glm::vec3* sky) const {
  // A black sky (a level lit by its lights alone) skips the per-texel transfer altogether.
  bool hasSky = false;
  for (int i = 0; i < kShCount; ++i) hasSky = hasSky || data_.skySh[i] != glm::vec3(0.0f);
  hasSky = hasSky && !data_.texelSky.empty();
  forBlocks(data_.texelCount, [&](size_t first, size_t last) {
    for (size_t t = first; t < last; ++t) {
      glm::vec3 s(0.0f);
      if (hasSky) s = evalSky(data_.skySh, &data_.texelSky[t * kShCount]);
      sky[t] = s;
    }
  });
}

void Solver::directTexels(glm::vec3* direct, bool withSky) const {
  if (withSky) skyTexels(direct);
  forBlocks(data_.texelCount, [&](size_t first, size_t last) {
    if (!withSky) std::fill(direct + first, direct + last, glm::vec3(0.0f));
    for (size_t i = 0; i < data_.sources.size(); ++i) {
      const std::vector<float>& transfer = data_.sources[i].texelTransfer;
      const glm::vec3 scale = directScale_[i];
      if (transfer.empty() || scale == glm::vec3(0.0f)) continue;
      for (size_t t = first; t < last; ++t) direct[t] += scale * transfer[t];
    }
  });
}

const glm::vec4* Solver::filteredPoints() const {
  // Smoothing passes over the gather points (each texel's mix of them follows).
  const size_t points = data_.gatherPointCount;
  if (data_.filterPasses <= 0 || data_.pointFilter.rows() != points) return gathered_.data();
  const glm::vec4* in = gathered_.data();  // the gather points' rows come first
  for (int pass = 0; pass < data_.filterPasses; ++pass) {
    forBlocks(points, [&](size_t first, size_t last) {
      mixRows(data_.pointFilter, first, last, in, scratch_.data());
    });
    filtered_.swap(scratch_);
    in = filtered_.data();
  }
  return in;
}

template <class Store>
void Solver::mixTexels(const Store& store) const {
  const glm::vec4* source = filteredPoints();
  const float scale = data_.indirectIntensity;
  const SparseMatrix& gather = data_.texelGather;
  forBlocks(data_.texelCount, [&](size_t first, size_t last) {
    const uint32_t* rowStart = gather.rowStart.data();
    const uint32_t* column = gather.column.data();
    const float* weight = gather.weight.data();
    for (size_t t = first; t < last; ++t)
      store(t, scale * glm::vec3(mixRow(rowStart, column, weight, t, source)));
  });
}

void Solver::indirectTexels(glm::vec3* indirect) const {
  mixTexels([indirect](size_t t, glm::vec3 v) { indirect[t] = v; });
}

void Solver::addIndirectTexels(const glm::vec3* direct, glm::vec3* sum) const {
  mixTexels([direct, sum](size_t t, glm::vec3 v) { sum[t] = direct[t] + v; });
}

void Solver::lightmapDirect(glm::vec3* direct) const {
  const LightmapLayers& layers = data_.lightmap;
  forBlocks(layers.texelCount, [&](size_t first, size_t last) {
    std::fill(direct + first, direct + last, glm::vec3(0.0f));
    for (size_t i = 0; i < data_.sources.size(); ++i) {
      const std::vector<uint16_t>& halves = layers.direct[i];
      const glm::vec3 scale = directScale_[i] * layers.directScale[i];
      if (halves.empty() || scale == glm::vec3(0.0f)) continue;
      for (size_t t = first; t < last; ++t) direct[t] += scale * halfToFloat(halves[t]);
    }
  });
}

namespace {

// Lightmap texel t's indirect light from the grid's values.
glm::vec3 upsampled(const TransportData& data, size_t t, const glm::vec3* grid) {
  uint32_t texel[4];
  float weight[4];
  cornerWeights(data.lightmap.corners[t], data.atlases, texel, weight);
  glm::vec3 sum(0.0f);
  for (int k = 0; k < 4; ++k)
    if (weight[k] > 0.0f) sum += weight[k] * grid[texel[k]];
  return sum;
}

}  // namespace

void Solver::upsampleIndirect(const glm::vec3* grid, glm::vec3* indirect) const {
  forBlocks(data_.lightmap.texelCount, [&](size_t first, size_t last) {
    for (size_t t = first; t < last; ++t) indirect[t] = upsampled(data_, t, grid);
  });
}

void Solver::composeLightmap(const glm::vec3* direct, const glm::vec3* grid,
                             glm::vec3* lightmap) const {
  forBlocks(data_.lightmap.texelCount, [&](size_t first, size_t last) {
    for (size_t t = first; t < last; ++t) lightmap[t] = direct[t] + upsampled(data_, t, grid);
  });
}

void Solver::gatherTexels(std::vector<glm::vec3>& direct, std::vector<glm::vec3>& indirect) const {
  direct.resize(data_.texelCount);
  indirect.resize(data_.texelCount);
  directTexels(direct.data());
  indirectTexels(indirect.data());
}

void Solver::gatherTexels(std::vector<glm::vec3>& texels) const {
  std::vector<glm::vec3> indirect;
  gatherTexels(texels, indirect);
  for (size_t t = 0; t < texels.size(); ++t) texels[t] += indirect[t];
}

}  // namespace afterglow::runtime
