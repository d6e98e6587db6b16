// Stage 2 of the precompute: texels grouped into clusters, the nodes of the radiosity system.
//
// A cluster holds texels of one instance and one material within a normal cone, at most about
// clusterSize across. Where the texels' gather rays travel short distances (corners, gaps,
// under furniture) light changes over short distances too, so clusters there are kept smaller
// than adaptiveScale × the harmonic mean ray distance, and texels whose distances differ by
// more than maxDistanceRatio are not averaged together: the ceiling inside the 1 cm gap above
// the Cornell box's lamp must not share a cluster with the ceiling the room sees, or the room
// would be lit by the gap's trapped light.
//
// Double-sided surfaces have two sides but texels on the front only. Where the gather saw their
// back, their texels are clustered a second time for the back side (reversed normals, the ray
// distances seen from behind), into clusters that take part in the bounces and are never
// written to a lightmap.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/gather.h"
#include "afterglow/baker/texels.h"

namespace afterglow::baker {

class RayTracer;

struct ClusterOptions {
  float clusterSize = 0.5f;        // metres: largest extent of a cluster
  // ... and at most this many texels across (Unity's "cluster resolution" the other way up): a
  // finer lightmap resolves bounced light more finely, so its radiosity nodes shrink with it.
  float clusterTexels = 4.0f;      // texel edges (<= 0: off)
  float maxNormalAngleDeg = 35.0f; // degrees: texels in a cluster stay within this normal cone
  int minTexels = 1;               // count: clusters are not split below this
  float adaptiveScale = 0.25f;     // clusters stay within this × their texels' median
                                   //   harmonic ray distance (<= 0: off)
  float maxDistanceRatio = 4.0f;   // texels whose ray distances differ by more are split
                                   //   apart (<= 1: off)
  // Far clusters (LinkOptions::farDistance), for the links of far-away hits: farLevels levels
  // of the same clustering, each farScale times wider than the one below. 0 levels or a
  // scale <= 1: none.
  float farScale = 4.0f;
  int farLevels = 1;
};

// The options of far cluster level `level` (1 = the first above the clusters): the clusters'
// sizes scaled by farScale^level.
ClusterOptions farClusterOptions(const ClusterOptions& options, int level = 1);

struct Clusters {
  std::vector<uint32_t> texelCluster;  // per texel: its (front) cluster (kNoTexel for invalid)
  std::vector<uint32_t> texelBackCluster;  // per texel: its back-side cluster (kNoTexel for
                                           //   invalid texels and single-sided surfaces)
  // Per cluster:
  std::vector<glm::vec3> position;     // area-weighted centre
  std::vector<glm::vec3> normal;       // area-weighted mean normal (unit); reversed for backs
  std::vector<float> area;             // m²
  std::vector<uint32_t> material;      // index into Scene::materials (of its texels); ~0u for
                                       //   glTF's default material (primitive material -1)
  std::vector<glm::vec3> albedo;       // mean diffuse albedo (texture × factor), linear
  std::vector<glm::vec3> emission;     // mean emitted radiance, linear
  std::vector<uint8_t> back;           // 1 for the back side of a double-sided surface
  std::vector<uint32_t> firstTexel;    // texels of cluster c: memberTexels[firstTexel[c] ..
  std::vector<uint32_t> memberTexels;  //   firstTexel[c+1])

  uint32_t size() const { return uint32_t(area.size()); }
  // The cluster a gather hit code (TexelGather) lands in: its texel's front cluster, or its
  // back-side cluster; kNoTexel for a miss.
  uint32_t ofHit(uint32_t code) const {
    if (code == TexelGather::kNoHit) return runtime::kNoTexel;
    const uint32_t t = code & TexelGather::kTexelMask;
    return (code & TexelGather::kBackSide) ? texelBackCluster[t] : texelCluster[t];
  }
};

// Groups the valid texels into clusters: front sides first, then the back sides of
// double-sided surfaces. With a gather, its harmonic ray distances drive the adaptive
// subdivision and only backs it saw get clusters (without one, every double-sided texel's
// back does); with a tracer, texels that a wall separates from the rest of their cluster are
// split off. Deterministic.
Clusters computeClusters(const scenes::Scene& scene, const RayTracer* tracer,
                         const TexelSet& texels, const TexelGather* gather = nullptr,
                         const ClusterOptions& options = {});

// The bounce albedo of one point of a material, from its inputs with textures applied (Unity's
// meta pass, UnityLightmappingAlbedo, with glTF's dielectric reflectance):
//   dielectricF0 = min(F0(ior) × specularColor, 1) × specular,  F0(ior) = ((ior − 1)/(ior + 1))²
//   specColor    = mix(dielectricF0, baseColor, metallic)
//   albedo       = baseColor × (1 − metallic) × (1 − max(dielectricF0.rgb))
//                + specColor × roughness² × 0.5
// roughness is glTF's perceptual roughness. The result never exceeds 1 for valid inputs (proof
// at the definition). Linear RGB.
struct AlbedoInputs {
  glm::vec3 baseColor{1.0f};          // baseColorFactor × baseColorTexture
  float metallic = 1.0f;              // metallicFactor × metallicRoughnessTexture.b
  float roughness = 1.0f;             // roughnessFactor × metallicRoughnessTexture.g (perceptual)
  float ior = 1.5f;                   // KHR_materials_ior (0 = F0 of 1, as the extension says)
  float specular = 1.0f;              // KHR_materials_specular: factor × specularTexture.a
  glm::vec3 specularColor{1.0f};      //   specularColorFactor × specularColorTexture.rgb
};
glm::vec3 bounceAlbedo(const AlbedoInputs& in);
// glTF's dielectric F0 colour: min(F0(ior) × specularColor, 1) × specular.
glm::vec3 dielectricF0(float ior, float specular, glm::vec3 specularColor);

// The diffuse albedo the baker uses for a material at a UV: bounceAlbedo of its factors and
// textures, linear RGB. `nearest`: the textures' nearest texels (Texture::fetch), not bilinear.
glm::vec3 diffuseAlbedo(const scenes::Scene& scene, int material, glm::vec2 uv0,
                        bool nearest = false);
// Whether a texture enters a material's diffuse albedo (else it is the same everywhere).
bool albedoTextured(const scenes::Material& material);
// bounceAlbedo of a material's factors alone (every texture read as 1): the transport's
// material albedo, which the per-cluster texture ratios multiply.
glm::vec3 diffuseAlbedoFactor(const scenes::Material& material);
// The base colour whose diffuseAlbedoFactor is `albedo`, the material's other factors kept
// (metallic, roughness, ior, specular, specular colour). Per channel the factor is affine in
// the base colour, a0 + (a1 − a0) × base with a0, a1 the factor at base 0 and 1, so the base is
// (albedo − a0) / (a1 − a0), nudged by a few ulps where that makes the factor equal `albedo`
// exactly. False, with *baseColor unchanged, when some channel has no base colour in [0, 1]
// (glTF's range for baseColorFactor): a1 == a0 ≠ albedo (a mirror metal, roughness 0, whose
// base colour only tints a specular share its roughness removes), or albedo outside [a0, a1].
bool baseColorForAlbedoFactor(const scenes::Material& material, glm::vec3 albedo,
                              glm::vec3* baseColor);
// The metallic-roughness BRDF of a material at a UV, as an engine shades it (glTF's
// metallic-roughness model with KHR_materials_ior and KHR_materials_specular), linear RGB:
//   diffuse   = baseColor × (1 − metallic) × (1 − max(dielectricF0.rgb))
//   f0        = mix(dielectricF0, baseColor, metallic)     (Schlick's specular colour)
//   roughness = perceptual roughness, roughnessFactor × metallicRoughnessTexture.g
// The reflection probes' capture shades with it; bounceAlbedo folds part of the specular into
// the bounce albedo instead, which an engine's probes would count twice.
struct SurfaceBrdf {
  glm::vec3 diffuse{0.0f};
  glm::vec3 f0{0.0f};
  float roughness = 1.0f;
};
SurfaceBrdf surfaceBrdf(const scenes::Scene& scene, int material, glm::vec2 uv0);
// Emitted radiance of a material at a UV, linear RGB.
glm::vec3 emittedRadiance(const scenes::Scene& scene, int material, glm::vec2 uv0);

}  // namespace afterglow::baker
