// Material evaluation: what a glTF metallic-roughness material reflects and emits at a point,
// with its textures applied. One definition for every user: the precompute's clusters and
// gather, the reference path tracer, the reflection probes' capture, `render` and `relight`.
#pragma once

#include <glm/glm.hpp>

#include "afterglow/scenes/scene.h"

namespace afterglow::scenes {

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
glm::vec3 diffuseAlbedo(const Scene& scene, int material, glm::vec2 uv0,
                        bool nearest = false);
// Whether a texture enters a material's diffuse albedo (else it is the same everywhere).
bool albedoTextured(const Material& material);
// bounceAlbedo of a material's factors alone (every texture read as 1): the transport's
// material albedo, which the per-cluster texture ratios multiply.
glm::vec3 diffuseAlbedoFactor(const Material& material);
// The base colour whose diffuseAlbedoFactor is `albedo`, the material's other factors kept
// (metallic, roughness, ior, specular, specular colour). Per channel the factor is affine in
// the base colour, a0 + (a1 − a0) × base with a0, a1 the factor at base 0 and 1, so the base is
// (albedo − a0) / (a1 − a0), nudged by a few ulps where that makes the factor equal `albedo`
// exactly. False, with *baseColor unchanged, when some channel has no base colour in [0, 1]
// (glTF's range for baseColorFactor): a1 == a0 ≠ albedo (a mirror metal, roughness 0, whose
// base colour only tints a specular share its roughness removes), or albedo outside [a0, a1].
bool baseColorForAlbedoFactor(const Material& material, glm::vec3 albedo,
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
SurfaceBrdf surfaceBrdf(const Scene& scene, int material, glm::vec2 uv0);
// Emitted radiance of a material at a UV, linear RGB.
glm::vec3 emittedRadiance(const Scene& scene, int material, glm::vec2 uv0);
// A triangle's tangent space in world space where its TEXCOORD_0 has none given (glTF: a
// client computes one; per triangle, as MikkTSpace starts before it smooths): the tangent along
// increasing u made orthogonal to the normal n, the bitangent up the image (against v, glTF's
// +Y of a normal texture). False where the UVs are degenerate.
bool triangleTangents(const Scene& scene, uint32_t instance, uint32_t primitive, uint32_t triangle,
                      glm::vec3 n, glm::vec3* t, glm::vec3* b);
// The shading normal the material's normal texture gives at a surface point whose normal is n
// and whose tangent space (glTF: +X along the texture's u, +Y up the image, i.e. against v) is
// t and b: normalize(x·s·t + y·s·b + z·n) with (x, y, z) = 2 × rgb − 1 and s the texture's
// scale. n itself without a normal texture (or one that is not loaded).
glm::vec3 normalMapped(const Scene& scene, int material, glm::vec2 uv0, glm::vec3 n, glm::vec3 t,
                       glm::vec3 b);

// What a surface lets through at a point, glass: alphaMode BLEND lets 1 − alpha through (alpha =
// baseColorFactor.a × baseColorTexture.a), KHR_materials_transmission its transmission
// (transmissionFactor × transmissionTexture.r), a material with both 1 − alpha × (1 −
// transmission); what passes is tinted by the base colour (baseColorFactor.rgb ×
// baseColorTexture.rgb). The rest, 1 − open, meets the surface, which reflects it with its
// bounce albedo as an opaque surface would: BLEND glass reflects its alpha's share, as an engine
// blends it. MASK cut-outs are no transmission (the ray tracer takes them out below
// alphaCutoff; above it, alpha counts as 1), nor is an OPAQUE material's alpha.
struct Transmission {
  float open = 0.0f;     // the fraction of light that passes, [0, 1]
  glm::vec3 tint{1.0f};  // its colour, linear RGB
  // The light that passes, per channel: what the reference path tracer carries.
  glm::vec3 rgb() const { return open * tint; }
  // The same as one number, the mean over the channels: what the precompute carries, since
  // its transport is scalar per source and per link. Exact for neutral glass; for tinted glass
  // white light keeps its power through it, and its colour is the light's own.
  float grey() const { return open * (tint.x + tint.y + tint.z) / 3.0f; }
};
// `blend`: whether alphaMode BLEND counts (false where BLEND is cut out as MASK instead:
// trace::RayTracerOptions::blendAsMask).
Transmission transmission(const Scene& scene, int material, glm::vec2 uv0, bool blend = true);
// Whether transmission can let anything through anywhere on a material: BLEND with an alpha
// below 1 (its factor's, or some texel's of its base colour texture), or a transmissionFactor
// above 0. False for every other material, whose surfaces are opaque.
bool transmissive(const Scene& scene, int material, bool blend = true);

}  // namespace afterglow::scenes
