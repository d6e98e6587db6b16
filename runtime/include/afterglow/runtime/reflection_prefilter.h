// Reflection probes' prefiltering: the split-sum approximation of GGX specular image-based
// lighting (Karis 2013, "Real Shading in Unreal Engine 4"), GLM only.
//
// A probe's specular radiance is stored as a chain of cubemaps (cubemap.h's layout), mip m
// holding the source radiance prefiltered for perceptual roughness roughnessOfMip(m): the
// engine reads mip mipOfRoughness(r) trilinearly in the reflected direction R, and multiplies
// by the DFG term F0 · scale + bias from dfgTable at (NdotV, r).
//
// Roughness. "Perceptual" roughness r ∈ [0, 1] is the material parameter (glTF's
// roughnessFactor); GGX's α = r². The mip of a roughness is Unity's mapping (the one its
// standard shaders use, UNITY_SPECCUBE_LOD_STEPS = 6 for 7 mips):
//   mip = r · (1.7 − 0.7 r) · (mipCount − 1),
// so mip 0 is the mirror (r = 0) and the last mip r = 1.
//
// Prefiltered radiance (the split sum's first factor), with the split sum's N = V = R:
//   L̃(R) = ∫ L(l) (n·l)⁺ p(l) dl / ∫ (n·l)⁺ p(l) dl,   n = v = R,
// p(l) = D(h) (n·h) / (4 (v·h)) = D(h) / 4 the density of l = reflect(−v, h) for GGX-sampled
// half vectors h, D(h) = α² / (π ((n·h)² (α² − 1) + 1)²). It is estimated with a fixed
// Hammersley set of half vectors, in one thread (deterministic: the same bits on every run of
// the same build) and *filtered importance sampling* (Křivánek & Colbert 2008, "Real-time
// Shading with Filtered Importance Sampling"): each sample reads the source's mip chain (2×2
// averages weighted by texel solid angle) at the level whose texel solid angle matches the
// sample's share of the sphere, 1 / (samples · p(l)), one level blurrier than that (their
// bias of 1); so a single very bright texel (a sun) becomes a smooth lobe at any sample count
// instead of a few fireflies. A whole chain (prefilterChain) is instead integrated by a
// precomputed operator, exactly up to a stated tolerance and fast enough to redo every frame
// (prefilter_plan.h).
//
// DFG (the split sum's second factor), for the full specular BRDF
//   f(l, v) = D(h) · Vis(l, v) · F(v·h),
//   Vis = G2 / (4 (n·l)(n·v)) = 0.5 / ((n·l) √((n·v)²(1 − α²) + α²) + (n·v) √((n·l)²(1 − α²) + α²))
// (Smith's height-correlated masking-shadowing, Heitz 2014; Lagarde & de Rousiers 2014,
// "Moving Frostbite to PBR") and Schlick's Fresnel F = F0 + (1 − F0)(1 − v·h)⁵:
//   ∫ f(l, v) (n·l) dl = F0 · scale + bias,
//   scale = ∫ D Vis (1 − (1 − v·h)⁵) (n·l) dl,   bias = ∫ D Vis (1 − v·h)⁵ (n·l) dl.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/cubemap.h"

namespace afterglow::runtime {

// The DFG table's size the bake and the runtime shade reflections with (64 × 64).
constexpr int kDfgSize = 64;
// Unity's probe mip count (mips 0..6).
constexpr int kReflectionMipCount = 7;
// Default GGX samples per output texel of prefilterGgx: with filtered importance sampling the
// error of fewer samples is extra blur, not noise; 1024 keeps a one-texel sun's lobe within a
// few percent of its converged shape (tests/runtime/reflection_prefilter_test.cpp).
constexpr int kPrefilterSamples = 1024;

// The mip (fractional, in [0, mipCount − 1]) for perceptual roughness r (clamped to [0, 1]).
float mipOfRoughness(float perceptualRoughness, int mipCount = kReflectionMipCount);

// The perceptual roughness of a (fractional) mip: the root in [0, 1] of
// 0.7 r² − 1.7 r + mip / (mipCount − 1) = 0, i.e. r = (1.7 − √(2.89 − 2.8 m)) / 1.4 with
// m = mip / (mipCount − 1) clamped to [0, 1]. 0 for mipCount ≤ 1.
float roughnessOfMip(float mip, int mipCount = kReflectionMipCount);

// The prefiltered radiance L̃ above for perceptual roughness r, at every texel centre of an
// `outSize` cubemap, from `samples` GGX half vectors per texel. r = 0 (the mirror) resamples
// the source: a copy when outSize == source.size, otherwise the source's mip chain read
// trilinearly at the level matching outSize. An empty source or outSize ≤ 0 gives an empty
// cubemap.
Cubemap prefilterGgx(const Cubemap& source, float perceptualRoughness, int outSize,
                     int samples = kPrefilterSamples);

// The probe's whole chain: mip m is L̃ for roughnessOfMip(m, mipCount) at the texel centres of
// max(1, source.size >> m), so mip 0 is the source itself.
//  - samples ≤ 0 (the default): integrated by the shared PrefilterPlan of the source's size
//    (prefilter_plan.h: built on the first call for a size and kept, ~0.7 s and 29 MB at
//    128², then ~8 ms a chain on one thread, a one-texel sun's lobe within 2% of the exact
//    integral) when the size is a power of two ≤ kMaxPrefilterPlanSize; otherwise as with
//    samples = kPrefilterSamples.
//  - samples > 0: mip m is prefilterGgx(source, roughnessOfMip(m, mipCount),
//    max(1, source.size >> m), samples), sampled (~1.9 s a 128² chain at 1024 samples).
std::vector<Cubemap> prefilterChain(const Cubemap& source, int mipCount = kReflectionMipCount,
                                    int samples = 0);

// The split sum's DFG term (scale, bias) at one NdotV ∈ (0, 1] (clamped to ≥ 1e-4) and
// perceptual roughness r, from `samples` half vectors at Hammersley points drawn from the GGX
// distribution of normals visible from v (Heitz 2018): each sample's weight F · G2 / G1(v) is
// at most 1, so grazing NdotV converges as fast as normal incidence (sampling D alone weighs
// samples by up to 4 Vis (n·l)(v·h) / (n·h), and 1024 of them still miss by 2% at NdotV < 0.1).
glm::vec2 integrateDfg(float nDotV, float perceptualRoughness, int samples = 1024);

// The DFG table, size × size (scale, bias) pairs, row-major with rows of constant roughness:
//   table[row · size + column] = integrateDfg(NdotV = (column + 0.5) / size,
//                                             r     = (row + 0.5) / size)
// i.e. x (u) is NdotV and y (v) is perceptual roughness, texel centres at (i + 0.5)/size, row 0
// the smoothest: the layout engines sample as a 2D texture at (NdotV, r) with row 0 at v = 0.
// scale, bias ≥ 0 and scale + bias ≤ 1 (the BRDF's directional albedo with F0 = 1).
std::vector<glm::vec2> dfgTable(int size = 64, int samples = 1024);

}  // namespace afterglow::runtime
