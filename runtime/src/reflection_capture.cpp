// Reflection probes' capture passes: hits shaded into radiance cubemaps (reflection_capture.h).
#include "afterglow/runtime/reflection_capture.h"

#include <algorithm>
#include <cmath>

#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/transport.h"
#include "printable_name.h"

namespace afterglow::runtime {

namespace {

glm::vec3 halves(const uint16_t* h) {
  return glm::vec3(halfToFloat(h[0]), halfToFloat(h[1]), halfToFloat(h[2]));
}

}  // namespace

std::vector<ReflectionProbeBox> ReflectionTransport::boxes() const {
  std::vector<ReflectionProbeBox> out;
  out.reserve(probes.size());
  for (const ReflectionProbeCapture& p : probes) out.push_back(p.box);
  return out;
}

std::string ReflectionTransport::validate(size_t materials, size_t atlases) const {
  if (probes.empty() && hits.empty()) return {};
  if (bakedAlbedo.size() != materials)
    return "reflection probes: " + std::to_string(bakedAlbedo.size()) + " baked albedos for " +
           std::to_string(materials) + " materials";
  if (bounces > 64) return "reflection probes: " + std::to_string(bounces) + " bounces (at most 64)";
  uint64_t next = 0;
  for (size_t i = 0; i < probes.size(); ++i) {
    const ReflectionProbeCapture& p = probes[i];
    const std::string name = "reflection probe " + std::to_string(i) + " '" + printableName(p.name) + "'";
    if (p.resolution == 0 || p.resolution > 2048 || (p.resolution & (p.resolution - 1)) != 0)
      return name + ": resolution " + std::to_string(p.resolution) +
             " is not a power of two up to 2048";
    if (p.firstHit != next) return name + ": its hits start at " + std::to_string(p.firstHit) +
                                   ", not after the previous probe's (" + std::to_string(next) + ")";
    next += uint64_t(kCubeFaceCount) * p.resolution * p.resolution;
    const ReflectionProbeBox& b = p.box;
    bool finite = std::isfinite(b.blendDistance);
    for (int a = 0; a < 3; ++a)
      finite = finite && std::isfinite(b.centre[a]) && std::isfinite(b.halfSize[a]) &&
               std::isfinite(b.capturePosition[a]) && std::isfinite(b.projectionCentre[a]) &&
               std::isfinite(b.projectionHalfSize[a]) && std::isfinite(b.axes[a].x) &&
               std::isfinite(b.axes[a].y) && std::isfinite(b.axes[a].z);
    if (!finite) return name + ": a box value is not finite";
  }
  if (next != hits.size())
    return "reflection probes: " + std::to_string(hits.size()) + " hits, the probes need " +
           std::to_string(next);
  for (size_t k = 0; k < hits.size(); ++k) {
    const ReflectionHit& h = hits[k];
    if (h.material == kReflectionMiss) continue;
    if (h.material >= materials || (h.atlas != kReflectionNoAtlas && h.atlas >= atlases) ||
        !std::isfinite(h.distance) || !std::isfinite(h.lightmapUv.x) ||
        !std::isfinite(h.lightmapUv.y))
      return "reflection probes: hit " + std::to_string(k) +
             " has a bad material, atlas, distance or lightmap UV";
  }
  return {};
}

glm::vec3 sampleChain(const CubemapChain& chain, glm::vec3 direction, float perceptualRoughness) {
  if (chain.empty()) return glm::vec3(0.0f);
  const int mips = int(chain.size());
  const float mip = std::min(mipOfRoughness(perceptualRoughness, kReflectionMipCount),
                             float(mips - 1));
  const int level = std::min(int(mip), mips - 1);
  const glm::vec3 a = sampleCubemap(chain[size_t(level)], direction);
  const float f = mip - float(level);
  if (f <= 0.0f || level + 1 >= mips) return a;
  return glm::mix(a, sampleCubemap(chain[size_t(level + 1)], direction), f);
}

BorderedChain withBorders(const CubemapChain& chain) {
  BorderedChain out;
  out.reserve(chain.size());
  for (const Cubemap& m : chain) out.push_back(withBorder(m));
  return out;
}

glm::vec2 sampleDfg(const std::vector<glm::vec2>& table, int size, float nDotV,
                    float perceptualRoughness) {
  if (size <= 0 || table.size() < size_t(size) * size_t(size)) return glm::vec2(0.0f);
  return sampleClampedBilinear(table, size, size,
                               glm::vec2(glm::clamp(nDotV, 0.0f, 1.0f),
                                         glm::clamp(perceptualRoughness, 0.0f, 1.0f)));
}

int reflectionLookups(const std::vector<ReflectionProbeBox>& boxes, glm::vec3 position,
                      glm::vec3 normal, glm::vec3 toViewer, float perceptualRoughness,
                      ReflectionLookup out[kMaxReflectionBlend]) {
  const float nDotV = glm::dot(normal, toViewer);
  if (!(nDotV > 0.0f)) return 0;
  const float r = glm::clamp(perceptualRoughness, 0.0f, 1.0f), alpha = r * r;
  const glm::vec3 reflected = 2.0f * nDotV * normal - toViewer;
  // 1. The lobe's dominant direction (Lagarde & de Rousiers 2014, "Moving Frostbite to PBR",
  //    4.9.3): GGX's lobe leans from R toward N as it widens.
  const float lean = (1.0f - alpha) * (std::sqrt(1.0f - alpha) + alpha);
  const glm::vec3 dominant = glm::normalize(glm::mix(normal, reflected, lean));
  std::vector<ProbeWeight> weights = reflectionProbesAt(boxes, position);
  if (weights.size() > size_t(kMaxReflectionBlend)) {
    std::stable_sort(weights.begin(), weights.end(),
                     [](const ProbeWeight& a, const ProbeWeight& b) { return a.weight > b.weight; });
    weights.resize(size_t(kMaxReflectionBlend));
    float sum = 0.0f;
    for (const ProbeWeight& w : weights) sum += w.weight;
    for (ProbeWeight& w : weights) w.weight /= sum;
  }
  int count = 0;
  for (const ProbeWeight& w : weights) {
    const ReflectionProbeBox* box = w.probe == 0 ? nullptr : &boxes[size_t(w.probe - 1)];
    ReflectionLookup& l = out[count++];
    l.probe = w.probe;
    l.weight = w.weight;
    // 2. Box projection corrects a sharp reflection's parallax; a rough lobe looked up around
    //    the projected direction gathers, from the capture position, light the surface cannot
    //    see (a lamp beside a ceiling), so the lookup fades back to the plain direction by α.
    l.reflected = box ? glm::normalize(glm::mix(boxProject(*box, position, dominant), dominant, alpha))
                      : dominant;
    l.normal = box ? boxProject(*box, position, normal) : normal;
  }
  return count;
}

ProbeLight probeLight(const CubemapChain& chain) {
  ProbeLight light;
  if (chain.empty()) return light;
  light.mips = withBorders(chain);
  const ShL2 sh = chainIrradianceSh(chain);
  Cubemap irradiance = makeCubemap(kProbeIrradianceSize);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < kProbeIrradianceSize; ++y)
      for (int x = 0; x < kProbeIrradianceSize; ++x)
        irradiance.at(face, x, y) = glm::max(
            irradianceOverPi(sh, cubemapTexelDirection(face, x, y, kProbeIrradianceSize)),
            glm::vec3(0.0f));
  light.irradiance = withBorder(irradiance);
  return light;
}

ReflectionTap reflectionTap(const ReflectionLookup& lookup, float perceptualRoughness,
                            int faceSize, int mips) {
  ReflectionTap tap;
  tap.probe = uint16_t(lookup.probe);
  // sampleChain's mips and fraction.
  const float mip = std::min(mipOfRoughness(glm::clamp(perceptualRoughness, 0.0f, 1.0f),
                                            kReflectionMipCount),
                             float(mips - 1));
  const int level = std::clamp(int(mip), 0, mips - 1);
  const float f = level + 1 < mips ? std::max(mip - float(level), 0.0f) : 0.0f;
  const int next = f > 0.0f ? level + 1 : level;
  tap.level[0] = uint8_t(level);
  tap.level[1] = uint8_t(next);
  const CubeFaceUv at = cubemapFaceUv(lookup.reflected);
  tap.at[0] = borderedBilinear(std::max(1, faceSize >> level), at);
  tap.at[1] = borderedBilinear(std::max(1, faceSize >> next), at);
  tap.weight[0] = lookup.weight * (1.0f - f);
  tap.weight[1] = lookup.weight * f;
  tap.irradiance = borderedBilinear(kProbeIrradianceSize, cubemapFaceUv(lookup.normal));
  return tap;
}

glm::vec3 ReflectionLighting::radiance(const ReflectionTap* taps, int count,
                                       float perceptualRoughness, const glm::vec3* lightmap) const {
  const float r = glm::clamp(perceptualRoughness, 0.0f, 1.0f);
  glm::vec3 radiance(0.0f), irradiance(0.0f);
  for (int k = 0; k < count; ++k) {
    const ReflectionTap& t = taps[k];
    if (size_t(t.probe) >= lights->size()) continue;
    const ProbeLight& light = (*lights)[t.probe];
    if (size_t(t.level[1]) >= light.mips.size()) continue;  // no chain yet: black
    radiance += t.weight[0] * sampleBordered(light.mips[t.level[0]], t.at[0]) +
                t.weight[1] * sampleBordered(light.mips[t.level[1]], t.at[1]);
    if (lightmap) irradiance += (t.weight[0] + t.weight[1]) * sampleBordered(light.irradiance, t.irradiance);
  }
  // 3. Normalisation by the lightmap: the probes saw the room from their capture position, the
  //    lightmap saw it from the surface; scaling a rough reflection by the ratio of the two
  //    irradiances (by roughness: a mirror keeps its probe's image) puts back the surface's own
  //    occlusion. The probes' irradiance is their radiance SH's (ProbeLight) in the
  //    box-projected normal. The ratio is clamped to [0, 4] against a probe that saw nearly
  //    nothing.
  if (lightmap)
    for (int c = 0; c < 3; ++c) {
      const float ratio =
          irradiance[c] > 1e-8f ? std::min((*lightmap)[c] / irradiance[c], 4.0f) : 1.0f;
      radiance[c] *= 1.0f + r * (ratio - 1.0f);
    }
  return radiance;
}

glm::vec3 ReflectionLighting::reflected(glm::vec3 position, glm::vec3 normal, glm::vec3 toViewer,
                                        float perceptualRoughness,
                                        const glm::vec3* lightmap) const {
  if (!boxes || !lights || lights->empty()) return glm::vec3(0.0f);
  ReflectionLookup lookups[kMaxReflectionBlend];
  const int count = reflectionLookups(*boxes, position, normal, toViewer, perceptualRoughness, lookups);
  ReflectionTap taps[kMaxReflectionBlend];
  int used = 0;
  for (int k = 0; k < count; ++k) {
    if (size_t(lookups[k].probe) >= lights->size()) continue;
    const ProbeLight& light = (*lights)[size_t(lookups[k].probe)];
    if (light.empty()) continue;
    taps[used++] = reflectionTap(lookups[k], perceptualRoughness, light.mips[0].size,
                                 int(light.mips.size()));
  }
  if (used == 0) return glm::vec3(0.0f);
  return radiance(taps, used, perceptualRoughness, lightmap);
}

glm::vec3 ReflectionLighting::specular(glm::vec3 position, glm::vec3 normal, glm::vec3 toViewer,
                                       glm::vec3 f0, float perceptualRoughness,
                                       const glm::vec3* lightmap) const {
  if (!boxes || !lights || !dfg || lights->empty()) return glm::vec3(0.0f);
  if (f0 == glm::vec3(0.0f)) return glm::vec3(0.0f);
  const glm::vec3 l = reflected(position, normal, toViewer, perceptualRoughness, lightmap);
  if (l == glm::vec3(0.0f)) return l;
  const glm::vec2 sb = sampleDfg(*dfg, dfgSize, glm::dot(normal, toViewer), perceptualRoughness);
  return l * (f0 * sb.x + sb.y);
}

ShL2 chainIrradianceSh(const CubemapChain& chain) {
  ShL2 sh;
  if (chain.empty()) return sh;
  size_t mip = 0;
  while (mip + 1 < chain.size() && chain[mip].size > 16) ++mip;
  const Cubemap& cube = chain[mip];
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < cube.size; ++y)
      for (int x = 0; x < cube.size; ++x)
        projectRadiance(cubemapTexelDirection(face, x, y, cube.size), cube.at(face, x, y),
                        cubemapTexelSolidAngle(x, y, cube.size), sh);
  return sh;
}

ReflectionShadingSetup prepareReflectionShading(const TransportData& data, size_t probe,
                                                const std::vector<glm::vec2>& dfg, int dfgSize) {
  const ReflectionTransport& refl = data.reflections;
  const ReflectionProbeCapture& p = refl.probes[probe];
  const int size = int(p.resolution);
  const std::vector<ReflectionProbeBox> boxes = refl.boxes();
  ReflectionShadingSetup setup;
  const size_t texels = size_t(kCubeFaceCount) * size_t(size) * size_t(size);
  setup.start.reserve(texels + 1);
  setup.start.push_back(0);
  setup.specular.assign(texels, glm::vec3(0.0f));
  const ReflectionHit* hits = refl.hits.data() + p.firstHit;
  size_t k = 0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x, ++k) {
        const ReflectionHit& h = hits[k];
        const glm::vec3 f0 = halves(h.f0);
        if (h.material != kReflectionMiss && f0 != glm::vec3(0.0f)) {
          const glm::vec3 dir = cubemapTexelDirection(face, x, y, size);
          const glm::vec3 normal = halves(h.normal);
          const float roughness = halfToFloat(h.roughness);
          ReflectionLookup lookups[kMaxReflectionBlend];
          const int count = reflectionLookups(boxes, p.box.capturePosition + h.distance * dir,
                                              normal, -dir, roughness, lookups);
          if (count > 0) {
            const glm::vec2 sb = sampleDfg(dfg, dfgSize, glm::dot(normal, -dir), roughness);
            setup.specular[k] = f0 * sb.x + sb.y;
            for (int l = 0; l < count; ++l) {
              const int faceSize = lookups[l].probe == 0
                                       ? int(kReflectionSkyResolution)
                                       : int(refl.probes[size_t(lookups[l].probe - 1)].resolution);
              setup.taps.push_back(reflectionTap(lookups[l], roughness, faceSize, kReflectionMipCount));
            }
          }
        }
        setup.start.push_back(uint32_t(setup.taps.size()));
      }
  return setup;
}

Cubemap skyCubemap(const glm::vec3 skySh[], int size) {
  Cubemap cube = makeCubemap(size);
  ShL2 sh;
  for (int i = 0; i < kShCount; ++i) sh.c[i] = skySh[i];
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x)
        cube.at(face, x, y) =
            glm::max(evalRadiance(sh, cubemapTexelDirection(face, x, y, size)), glm::vec3(0.0f));
  return cube;
}

Cubemap shadeReflectionCapture(const TransportData& data, size_t probe,
                               const std::vector<std::vector<glm::vec3>>& atlases,
                               const ReflectionLighting* previous,
                               const ReflectionShadingSetup* setup) {
  const ReflectionTransport& refl = data.reflections;
  const ReflectionProbeCapture& p = refl.probes[probe];
  const int size = int(p.resolution);
  Cubemap cube = makeCubemap(size);
  ShL2 sky;
  for (int i = 0; i < kShCount; ++i) sky.c[i] = data.skySh[i];
  // Per material, how far setAlbedo moved the diffuse colour from the baked one.
  std::vector<glm::vec3> albedoScale(data.materials.size(), glm::vec3(1.0f));
  for (size_t m = 0; m < albedoScale.size() && m < refl.bakedAlbedo.size(); ++m)
    for (int c = 0; c < 3; ++c)
      if (refl.bakedAlbedo[m][c] > 0.0f)
        albedoScale[m][c] = data.materials[m].albedo[c] / refl.bakedAlbedo[m][c];
  const ReflectionHit* hits = refl.hits.data() + p.firstHit;
  size_t k = 0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x, ++k) {
        const ReflectionHit& h = hits[k];
        if (h.material == kReflectionMiss) {
          cube.at(face, x, y) =
              glm::max(evalRadiance(sky, cubemapTexelDirection(face, x, y, size)), glm::vec3(0.0f));
          continue;
        }
        const MaterialParams& mat = data.materials[h.material];
        glm::vec3 radiance(0.0f);
        if (mat.emission != glm::vec3(0.0f)) radiance = halves(h.emission) * mat.emission;
        glm::vec3 lightmap(0.0f);
        if (h.atlas != kReflectionNoAtlas) {
          const AtlasLayout& layout = data.lightmapAtlases()[h.atlas];
          lightmap = sampleClampedBilinear(atlases[h.atlas], layout.width, layout.height,
                                           h.lightmapUv);
          radiance += halves(h.diffuse) * albedoScale[h.material] * lightmap;
        }
        if (previous && setup && setup->start[k] < setup->start[k + 1]) {
          const uint32_t first = setup->start[k];
          radiance += previous->radiance(&setup->taps[first], int(setup->start[k + 1] - first),
                                         halfToFloat(h.roughness),
                                         h.atlas != kReflectionNoAtlas ? &lightmap : nullptr) *
                      setup->specular[k];
        }
        cube.at(face, x, y) = radiance;
      }
  return cube;
}

CubemapChain reflectionChain(const Cubemap& radiance) {
  return prefilterChain(radiance, kReflectionMipCount);
}

std::vector<CubemapChain> solveReflectionProbes(const TransportData& data,
                                                const std::vector<std::vector<glm::vec3>>& atlases,
                                                const std::vector<glm::vec2>& dfg, int dfgSize) {
  const ReflectionTransport& refl = data.reflections;
  std::vector<CubemapChain> chains(refl.count() + 1);
  if (refl.count() == 0) return chains;
  chains[0] = reflectionChain(skyCubemap(data.skySh, int(kReflectionSkyResolution)));
  const std::vector<ReflectionProbeBox> boxes = refl.boxes();
  std::vector<ReflectionShadingSetup> setups;
  if (refl.bounces > 0)
    for (size_t i = 0; i < refl.count(); ++i)
      setups.push_back(prepareReflectionShading(data, i, dfg, dfgSize));
  // The chains a pass reads, as capture passes read them: [0] the sky, [i + 1] probe i.
  std::vector<ProbeLight> previous(refl.count() + 1);
  for (uint32_t pass = 0; pass <= refl.bounces; ++pass) {
    // Every probe of this pass reads the previous pass's chains, none of this pass's.
    if (pass > 0)
      for (size_t i = 0; i < chains.size(); ++i)
        if (pass == 1 || i > 0) previous[i] = probeLight(chains[i]);
    ReflectionLighting lighting{&boxes, &previous, &dfg, dfgSize};
    for (size_t i = 0; i < refl.count(); ++i)
      chains[i + 1] = reflectionChain(shadeReflectionCapture(
          data, i, atlases, pass == 0 ? nullptr : &lighting, pass == 0 ? nullptr : &setups[i]));
  }
  return chains;
}

}  // namespace afterglow::runtime
