// The reflection probes' GGX prefilter as a precomputed sparse linear operator, so that a
// probe's whole mip chain can be recomputed every frame (GLM only).
//
// What it computes. Mip m of the chain (m ≥ 1, max(1, size >> m) texels a side) is the split
// sum's prefiltered radiance L̃ of reflection_prefilter.h for perceptual roughness
// roughnessOfMip(m) at its texel centres, mip 0 the source itself: what prefilterChain's
// sampled path estimates, but integrated instead of sampled. The source is read as the
// function sampleCubemap defines (bilinear between texel centres, across face edges too), the
// function the sampled path's filtered importance sampling converges to; there is no sample
// count and no filtering blur.
//
// The operator. For a fixed source size every output texel is a fixed weighted sum of the
// source (the lobe's weights depend on geometry only), so the plan stores, once, each output
// texel's weights ("row") over
//   - the source's chain: level 0 the source, level k + 1 the 2 × 2 solid-angle-weighted means
//     of level k (as the sampled path's chain), and
//   - the chain's first moments: for each texel of level k ≥ 1, Σ (Ω_j/Ω) L_j (p_j − c) over
//     the source texels j it covers, p_j their centres and c their solid-angle-weighted
//     centroid in face-plane coordinates (a, b) = (2u − 1, 2v − 1),
// and an update is: build the chain and its moments from the source (~0.2 ms at 128²), then
// one sparse dot product per output texel. A row is built by descending a quadtree from each
// face's top-level texel. A texel over which the lobe density f (D(n·h) (n·l)⁺ of
// reflection_prefilter.h) is close enough to a constant takes one weight (∫ f over it, by
// Simpson's rule on a 3 × 3 grid); close enough to a linear function, three (the radiance and
// the two moments: they carry where in the texel the radiance is, so a point light inside a
// coarse texel still gets the weight of where it is, and the error is second-order in the
// texel's size instead of first); otherwise its four children are tried. A source texel
// over which f bends too much for that (the core of a lobe a few texels wide, or any lobe
// narrower than a texel) gets the exact weight ∫ f · tent of its bilinear reconstruction, from
// sub-samples spread by sampleCubemap's own weights (cubemapBilinearTaps). Each weight is the
// integral of one density (f smoothed by a texel's box, which is what a tent weight
// integrates) over its own disjoint region, so the treatments agree where they meet.
//
// Error control ("close enough"). At the nine grid points and at the texel's point nearest n,
// the model may miss f by tolerance · √(max(f, floor · f(0)) · f(0)): for a point light that
// bounds each output texel's error against its lobe's peak, allowing more (relative to f) away
// from the peak in proportion to √f, the allocation that minimises the taps for a given RMS
// error over the lobe (taps ∝ curvature / error, against a budget of ∫ error²; f^(1/4) and f
// were measured worse). The tolerance halves with each mip from mip 2 on (a mip has a quarter
// of the previous one's texels, so it costs little there); mip 1's lobe core is integrated
// texel by texel, and its own tolerance governs its tail. Simpson's rule must also agree with
// the midpoint rule to 1% of the row's total (else a grid point near a peak narrower than the
// texel would weigh the texel far beyond its share). Then the taps that can move the output
// least are dropped, up to dropBelow of the row's total together (a radiance weight moves it
// by at most its weight times the largest radiance), and the radiance weights are renormalised
// to sum to 1: a constant environment stays constant (the moments of a constant are 0).
//
// Figures (tests/runtime/prefilter_plan_test.cpp; afterglow_bench reflection), 128² source,
// 7 mips, default options, one thread:
//   - 4.9 M stored taps (a linear texel is one tap of three weights; per output texel, mips 1
//     to 6: 116, 198, 334, 586, 819, 958), 28.9 MB;
//   - built in ~0.5-0.8 s; a chain in ~8 ms (the sampled path at 1024 samples: ~2 s);
//   - a one-texel sun 10⁴ times the sky: its lobe within 1.7% of the exact integral at every
//     mip, at six places on the cube (relative RMS over the texels where the lobe is ≥ 1% of
//     its peak; the worst place per mip: 1.7, 1.7, 1.4, 0.8, 0.4, 1.0%); a smooth environment
//     within 0.5%; a constant environment constant to 1e-6.
// The plan is for power-of-two sources up to kMaxPrefilterPlanSize: a 256² plan would hold
// 22 M taps, 142 MB, build in 3.3 s and take ~60 ms a chain (the lobes of the sharp mips span
// four times the texels).
//
// Storage. A row's taps are kept in increasing index order, each a 16-bit step from the
// previous tap's index (0xFFFF: the index is in a side table) and 16-bit floats relative to the
// row's largest weight: radiance weights with an 11-bit mantissa (2.4e-4 apart), moments with a
// sign and a 10-bit mantissa. Relative, not fixed-point, because a row's smallest weights, far
// out in its lobe, may land on the brightest texels of the environment (a 16-bit fixed point
// left 1% errors beside a sun 10³ times brighter than the rest). What the rounded radiance
// weights miss of 1 is stored in full precision on the largest. A radiance tap is 4 bytes, a
// linear tap 8; coarse levels keep each texel's radiance and moments side by side (the scratch
// layout below) so a linear tap reads them at once.
//
// Rows related by one of the cube's 48 symmetries (the signed permutations of the axes, which
// map faces to faces and texels to texels at every level) have the same weights on related
// texels, with the moments' plane axes permuted and signed: the plan builds one row per orbit
// and maps it to the others, ~1/48 of the work. (A row on a symmetry plane is itself symmetric
// only to the method's tolerance, ~1e-4 of its value; at mip 1's cube corners ~2e-3, because
// sampleCubemap reads a corner's missing fourth texel from one of two neighbours.)
//
// Threads. A plan is immutable once built: any number of threads may prefilter with one plan
// at once, each with its own chain and scratch. Results are deterministic: the same bits on
// every run of the same build, whatever the threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/cubemap.h"
#include "afterglow/runtime/reflection_prefilter.h"

namespace afterglow::runtime {

// The largest source a plan is built for (and sharedPrefilterPlan / prefilterChain use one
// for); larger probes use prefilterChain's sampled path.
constexpr int kMaxPrefilterPlanSize = 128;

// How close the plan's quadrature keeps to the exact prefilter (see the header's error
// control); the defaults give the figures above.
struct PrefilterPlanOptions {
  // The point error allowed at mip 2, relative to √(f · f(0)); each further mip halves it
  // (they have a quarter of the texels each, so it costs little there).
  float tolerance = 0.07f;
  // Mip 1's: its lobe's core is integrated texel by texel, so this governs its tail only.
  float firstMipTolerance = 0.12f;
  // Below this fraction of the lobe's peak, errors are held to the floor's allowance.
  float floor = 0.01f;
  // The share of a row's total its dropped taps may move the output by, together.
  float dropBelow = 0.002f;
};

// Stored taps of a PrefilterPlan's row: see Storage above.
struct PrefilterPlanTap {
  uint16_t step;
  uint16_t weight;
};
struct PrefilterPlanLinearTap {
  uint16_t step;
  uint16_t radiance;
  uint16_t moment[2];
};

// One output texel's weights, decoded (PrefilterPlan::row): indices into the plan's scratch.
struct PrefilterPlanRow {
  std::vector<CubemapTap> radiance;  // on chain texels; ≥ 0, summing to 1
  std::vector<CubemapTap> moments;   // on the chain's moments
};

class PrefilterPlan {
 public:
  PrefilterPlan() = default;

  // Power-of-two sizes from 1 to kMaxPrefilterPlanSize.
  static bool supports(int sourceSize);

  // The plan for a source of `sourceSize` and a chain of `mipCount` mips (Unity's mapping of
  // reflection_prefilter.h). Empty for an unsupported size or mipCount < 1.
  static PrefilterPlan build(int sourceSize, int mipCount = kReflectionMipCount,
                             const PrefilterPlanOptions& options = {});

  int sourceSize() const { return sourceSize_; }
  int mipCount() const { return mipCount_; }
  bool empty() const { return sourceSize_ <= 0; }

  // Stored taps, all or mip m's (m ≥ 1), and the plan's whole memory.
  size_t tapCount() const { return packed_.size() + linear_.size(); }
  size_t tapCount(int mip) const;
  size_t bytes() const;

  // The chain of `source` (its size must be sourceSize(), else `chain` is left empty) into
  // `chain`, mipCount() cubemaps, mip 0 a copy of the source. `scratch` holds the source's
  // chain and moments (scratchSize() texels); reusing `chain` and `scratch` from one call to
  // the next allocates nothing.
  void prefilter(const Cubemap& source, std::vector<Cubemap>& chain,
                 std::vector<glm::vec4>& scratch) const;
  std::vector<Cubemap> prefilter(const Cubemap& source) const;
  size_t scratchSize() const { return scratchSize_; }

  // Output texel `texel` of mip m's weights (empty out of range). The scratch layout (of a plan
  // that is not empty): level k's texels (face-major like a Cubemap of size sourceSize() >> k)
  // from levelOffset(k), level 0 one slot each, coarser levels three (radiance, moment along a,
  // moment along b); levels 0 to levelCount() − 1, levelOffset(levelCount()) = scratchSize().
  PrefilterPlanRow row(int mip, size_t texel) const;
  int levelCount() const { return int(levelOffset_.size()) - 1; }
  size_t levelOffset(int level) const { return levelOffset_[size_t(level)]; }
  // Whether a scratch index holds radiance (not a moment), and its level.
  bool isRadiance(uint32_t index, int* level = nullptr) const;

 private:
  struct Builder;
  using Tap = PrefilterPlanTap;
  using LinearTap = PrefilterPlanLinearTap;
  struct Row {
    uint32_t tap;              // first radiance tap in packed_
    uint32_t linear;           // first linear tap in linear_
    uint32_t escape;           // first escape in escapes_ (the radiance taps', then the linear's)
    uint32_t first;            // index of the first radiance tap
    uint32_t linearFirst;      // index of the first linear tap
    float radianceScale;       // the largest radiance weight (the stored ones are relative to it)
    float momentScale;         // the largest moment weight's magnitude
    uint32_t correctionIndex;  // the largest radiance weight's index
    float correction;          // what the stored radiance weights miss of 1, added there
  };
  // The child's share of its parent texel, for building the chain and its moments.
  struct Child {
    float weight;  // Ω_child / Ω_parent
    float dx, dy;  // child's centroid − parent's (face-plane coordinates)
  };

  void append(const std::vector<CubemapTap>& taps);

  int sourceSize_ = 0;
  int mipCount_ = 0;
  std::vector<size_t> levelOffset_;  // per level, plus the scratch's end
  size_t scratchSize_ = 0;
  std::vector<std::vector<Child>> children_;  // per level k below the top, per (x, y)
  std::vector<size_t> mipRowBase_;            // mip m's rows start at rows_[mipRowBase_[m]]
  std::vector<Row> rows_;                     // plus one past the end
  std::vector<Tap> packed_;
  std::vector<LinearTap> linear_;
  std::vector<uint32_t> escapes_;
};

// A process-wide plan per (size, mip count), built on first use (under a lock: the first
// caller waits ~0.7 s at 128²) and kept until exit; null for an unsupported size.
std::shared_ptr<const PrefilterPlan> sharedPrefilterPlan(int sourceSize,
                                                         int mipCount = kReflectionMipCount);

}  // namespace afterglow::runtime
