// Reflection probes' capture and relighting (issue 15), GLM only.
//
// The bake casts one ray from each probe's capture position through the centre of every texel of
// its cubemap and keeps what the ray hit (a ReflectionHit): enough to shade that point again from
// the current lightmaps, materials, sky and probes, the way an engine shades it. The runtime
// (and the bake, through the same functions, so a relight equals a rebake) turns the hits into
// radiance cubemaps, one capture pass at a time:
//
//   texel radiance = diffuse × lightmap(uv1) + emission + specular           (a surface)
//                  = sky SH radiance in the texel's direction                 (a miss)
//   specular       = Σ_probes w · prefiltered(boxProject(R), roughness) · (F0 · scale + bias)
//
// - diffuse: the metallic-roughness BRDF's diffuse colour, baseColor · (1 − metallic) ·
//   (1 − max(dielectric F0)), textures applied at the hit; scaled by the material's current
//   albedo over its baked albedo (setAlbedo), channel by channel.
// - lightmap: the atlas pixels as published (resolved: padding, seams), read bilinearly at the
//   hit's lightmap UV, the E/π an engine's lightmap sampler returns.
// - emission: the material's current emitted radiance × its emissive texture at the hit.
// - specular: the standard split-sum image-based lighting (reflection_prefilter.h) with the
//   probes of the previous pass, blended and box-projected at the hit exactly as at run time
//   (reflection_probes.h); none in pass 0. R reflects the capture ray about the hit's shading
//   normal, V points back to the capture position. F0 = mix(dielectric F0, baseColor,
//   metallic).
//
// Pass 0 shows the diffuse part only; pass n lights the specular part with pass n − 1. With
// `bounces` passes after pass 0, two facing mirrors show each other `bounces` times (Unity's
// "Reflection Bounces"). Probe 0 is the sky: a cubemap of the sky SH, prefiltered like the rest.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/cubemap.h"
#include "afterglow/runtime/reflection_probes.h"

namespace afterglow::runtime {

struct TransportData;
struct ShL2;  // probe_sh.h (which includes transport.h, which includes this)

constexpr uint32_t kReflectionMiss = 0xffffffffu;  // ReflectionHit::material of a miss
constexpr uint16_t kReflectionNoAtlas = 0xffff;    // a surface without a lightmap
// The face size of probe 0, the sky: SH L2 is smooth, but 64 is the smallest face whose
// OpenEXR cube file holds all seven mips (64 >> 6 = 1).
constexpr uint32_t kReflectionSkyResolution = 64;

// What a capture ray hit, 44 bytes (half floats are IEEE binary16, transport.h's floatToHalf).
struct ReflectionHit {
  uint32_t material = kReflectionMiss;  // index into TransportData::materials, or a miss
  uint16_t atlas = kReflectionNoAtlas;  // lightmap atlas, or none (emission and specular only)
  uint16_t roughness = 0;               // half: perceptual roughness at the hit
  glm::vec2 lightmapUv{0.0f};           // the hit's TEXCOORD_1 (atlas space, [0, 1])
  uint16_t diffuse[3] = {0, 0, 0};      // half: diffuse colour at the hit, as baked
  uint16_t emission[3] = {0, 0, 0};     // half: emissive texture at the hit (0: does not emit
                                        //   toward the probe: single-sided back)
  uint16_t f0[3] = {0, 0, 0};           // half: specular colour at normal incidence
  uint16_t normal[3] = {0, 0, 0};       // half: unit shading normal, facing the probe
  float distance = 0.0f;                // from the capture position, metres
};
static_assert(sizeof(ReflectionHit) == 44, "the transport file stores hits as they are");

// One captured probe. Its hits are kCubeFaceCount · resolution² consecutive entries of
// ReflectionTransport::hits from firstHit, in cubemap texel order (cubemap.h).
struct ReflectionProbeCapture {
  std::string name;
  ReflectionProbeBox box;    // influence box, blend, importance, projection, capture position
  uint32_t resolution = 0;   // face size, a power of two
  uint64_t firstHit = 0;
};

struct ReflectionTransport {
  std::vector<ReflectionProbeCapture> probes;  // probe i + 1 of the blend (0 is the sky)
  std::vector<ReflectionHit> hits;
  // Per material, its albedo when baked (TransportData::materials[m].albedo then): hits' diffuse
  // colours scale by the current albedo over this.
  std::vector<glm::vec3> bakedAlbedo;
  uint32_t bounces = 1;  // capture passes after the diffuse-only pass 0

  size_t count() const { return probes.size(); }
  std::vector<ReflectionProbeBox> boxes() const;
  // Empty when consistent with `materials` materials and `atlases` atlases, else what is wrong.
  std::string validate(size_t materials, size_t atlases) const;
};

// What a GPU's linear sampler with clamp-to-edge returns from a width × height image (row-major,
// row 0 at v = 0) at uv: bilinear between pixel centres, edges clamped. The capture reads the
// lightmaps with it, the split sum its DFG table, `afterglow render` the lightmaps too.
template <class T>
T sampleClampedBilinear(const std::vector<T>& image, int width, int height, glm::vec2 uv) {
  const float x = uv.x * float(width) - 0.5f, y = uv.y * float(height) - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  auto at = [&](int px, int py) {
    px = std::clamp(px, 0, width - 1);
    py = std::clamp(py, 0, height - 1);
    return image[size_t(py) * size_t(width) + size_t(px)];
  };
  const int x0 = int(fx), y0 = int(fy);
  return glm::mix(glm::mix(at(x0, y0), at(x0 + 1, y0), tx),
                  glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), tx), ty);
}

// A probe's prefiltered radiance: mips 0.. of reflection_prefilter.h's chain.
using CubemapChain = std::vector<Cubemap>;

// The radiance an engine's trilinear lookup of a chain returns for perceptual roughness r:
// mip mipOfRoughness(r, chain size), bilinear within a mip (sampleCubemap), linear between the
// two mips around it. Black for an empty chain.
glm::vec3 sampleChain(const CubemapChain& chain, glm::vec3 direction, float perceptualRoughness);
// The chain's mips bordered (cubemap.h's withBorder): what the capture passes and the render
// read, through reflection taps below.
using BorderedChain = std::vector<BorderedCubemap>;
BorderedChain withBorders(const CubemapChain& chain);

// One probe's part in a point's specular lighting: its blend weight and the two box-projected
// directions its chain is read in (the reflection, and the normal for the normalisation).
struct ReflectionLookup {
  int probe = 0;               // 0 the sky, i + 1 boxes[i]
  float weight = 0.0f;
  glm::vec3 reflected{0.0f};   // where the probe's chain is read, at the roughness's mip
  glm::vec3 normal{0.0f};      // where its irradiance is read
};
// At most this many probes blend at a point: where more boxes overlap, the largest weights are
// kept and renormalised (engines blend two to four).
constexpr int kMaxReflectionBlend = 4;
// A point's lookups into out (kMaxReflectionBlend entries at most), for the unit shading normal
// and the unit direction to the viewer; 0 when the point faces away from the viewer.
int reflectionLookups(const std::vector<ReflectionProbeBox>& boxes, glm::vec3 position,
                      glm::vec3 normal, glm::vec3 toViewer, float perceptualRoughness,
                      ReflectionLookup out[kMaxReflectionBlend]);

// One probe's chain as the capture passes and the render read it: its mips bordered
// (cubemap.h's withBorder, so lookups never branch) and its irradiance E/π for the
// normalisation, from the chain's radiance SH (chainIrradianceSh) tabulated on a small cube:
// SH L2 irradiance is smooth, and a bilinear read of 16² faces is within 1% of the mean
// irradiance of evaluating it (0.8% around a sun: reflection_lighting_test.cpp), where the
// normalisation is a ratio scaled by roughness.
constexpr int kProbeIrradianceSize = 16;
struct ProbeLight {
  BorderedChain mips;
  BorderedCubemap irradiance;
  bool empty() const { return mips.empty(); }
};
ProbeLight probeLight(const CubemapChain& chain);

// A lookup resolved against its probe's chain shape: the texels and weights it reads, so a
// capture pass (which reads the same lookups every pass) does no address arithmetic. The
// trilinear read of the roughness's mip (sampleChain) is two bilinear reads of mips level[0]
// and level[1], weighted by the blend weight × (1 − f) and × f.
struct ReflectionTap {
  uint16_t probe = 0;
  uint8_t level[2] = {0, 0};
  BorderedBilinear at[2];        // in mips level[0] and level[1]
  float weight[2] = {0.0f, 0.0f};
  BorderedBilinear irradiance;   // in ProbeLight::irradiance, at the projected normal
};
// `mips` faces halving from `faceSize` (a probe's chain shape).
ReflectionTap reflectionTap(const ReflectionLookup& lookup, float perceptualRoughness,
                            int faceSize, int mips);

// The split-sum specular lighting at a point, from probes blended and box-projected as at run
// time: lights[0] is the sky, lights[i + 1] boxes[i]; dfg is dfgTable(dfgSize). `toViewer` is
// the unit direction from the point to the eye, `normal` the unit shading normal, `lightmap`
// (optional) the point's lightmap E/π. Three corrections engines apply to rough reflections
// (reflection_capture.cpp): the lookup along GGX's dominant direction, box projection faded out
// by α, and, with a lightmap, normalisation by the ratio of the lightmap's irradiance to the
// probes' (weighted by roughness). On McGuire's Cornell box they take a 128² probe's mirror mip
// from 9.6% to 4.7% RMSE against the path-traced reference (reflection_bake_test.cpp).
struct ReflectionLighting {
  const std::vector<ReflectionProbeBox>* boxes = nullptr;
  const std::vector<ProbeLight>* lights = nullptr;
  const std::vector<glm::vec2>* dfg = nullptr;
  int dfgSize = 0;

  glm::vec3 specular(glm::vec3 position, glm::vec3 normal, glm::vec3 toViewer, glm::vec3 f0,
                     float perceptualRoughness, const glm::vec3* lightmap = nullptr) const;
  // The radiance those probes show along the point's reflection (specular() before the split
  // sum's F0 · scale + bias): what a mirror shows, to compare with the light along the
  // reflected ray.
  glm::vec3 reflected(glm::vec3 position, glm::vec3 normal, glm::vec3 toViewer,
                      float perceptualRoughness, const glm::vec3* lightmap = nullptr) const;
  // The radiance of a point's taps (before F0 · scale + bias), normalised by `lightmap` when
  // given: the dynamic half of specular(). Taps of a probe without a chain yet read black.
  glm::vec3 radiance(const ReflectionTap* taps, int count, float perceptualRoughness,
                     const glm::vec3* lightmap) const;
};

// A chain's radiance SH L2 (from its mip nearest 16², by texel solid angle): its irradiance
// for the normalisation.
ShL2 chainIrradianceSh(const CubemapChain& chain);

// The static half of a probe's capture passes: per texel, its taps and its split-sum factor
// F0 · scale + bias (zero: no specular): 48 bytes a tap, 16 a texel, 5-12 MB for a 128²
// probe. Built once per probe (prepareReflectionShading), kept by the runtime; every pass
// reads it. Taps assume every chain has reflectionChain's shape (kReflectionMipCount mips from
// the probe's resolution, the sky's kReflectionSkyResolution).
struct ReflectionShadingSetup {
  std::vector<uint32_t> start;            // texels + 1: texel t's taps [start[t], start[t + 1])
  std::vector<ReflectionTap> taps;
  std::vector<glm::vec3> specular;        // per texel: F0 · scale + bias
  size_t bytes() const {
    return start.size() * sizeof(uint32_t) + taps.size() * sizeof(ReflectionTap) +
           specular.size() * sizeof(glm::vec3);
  }
};
ReflectionShadingSetup prepareReflectionShading(const TransportData& data, size_t probe,
                                                const std::vector<glm::vec2>& dfg, int dfgSize);

// (scale, bias) of a dfgTable of `size`, bilinear at (NdotV, r), clamped to the table.
glm::vec2 sampleDfg(const std::vector<glm::vec2>& table, int size, float nDotV,
                    float perceptualRoughness);

// A cubemap of `size` showing the sky SH's radiance (never negative: L2 rings below zero
// around a sun are clamped).
Cubemap skyCubemap(const glm::vec3 skySh[], int size);

// Probe `probe`'s radiance cubemap, one capture pass: its hits shaded with the lightmap images
// (`atlases`, per atlas width·height pixels as resolveAtlas makes them), the transport's current
// materials and sky, and the previous pass's probes (`previous`, null in pass 0) through the
// probe's `setup` (prepareReflectionShading; may be null in pass 0).
Cubemap shadeReflectionCapture(const TransportData& data, size_t probe,
                               const std::vector<std::vector<glm::vec3>>& atlases,
                               const ReflectionLighting* previous,
                               const ReflectionShadingSetup* setup);

// The bake's (and a from-scratch relight's) reflection probes: the sky chain, then pass 0 and
// `data.reflections.bounces` more passes, each prefiltered into a chain (reflectionChain).
// Returns chains: [0] the sky, [i + 1] probe i.
std::vector<CubemapChain> solveReflectionProbes(const TransportData& data,
                                                const std::vector<std::vector<glm::vec3>>& atlases,
                                                const std::vector<glm::vec2>& dfg, int dfgSize);

// The chain of a cubemap: prefilterChain's kReflectionMipCount mips (faces halving down to 1
// texel, Unity's mip/roughness mapping either way).
CubemapChain reflectionChain(const Cubemap& radiance);

}  // namespace afterglow::runtime
