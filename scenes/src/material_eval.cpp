// Material evaluation: the bounce albedo, BRDF and emission of glTF materials (material_eval.h).
#include "afterglow/scenes/material_eval.h"

#include <algorithm>
#include <cmath>

namespace afterglow::scenes {

namespace {

glm::vec3 textureRgb(const Scene& scene, const TextureRef& ref, glm::vec2 uv0,
                     bool nearest = false) {
  if (!ref.valid() || size_t(ref.texture) >= scene.textures.size()) return glm::vec3(1.0f);
  const Texture& texture = scene.textures[size_t(ref.texture)];
  if (!texture.loaded()) return glm::vec3(1.0f);
  // Texels carry only TEXCOORD_0; a texture asking for another set reads set 0 instead.
  const glm::vec2 uv = ref.transform(uv0);
  return glm::vec3(nearest ? texture.fetch(uv) : texture.sample(uv));
}

float textureAlpha(const Scene& scene, const TextureRef& ref, glm::vec2 uv0,
                   bool nearest = false) {
  if (!ref.valid() || size_t(ref.texture) >= scene.textures.size()) return 1.0f;
  const Texture& texture = scene.textures[size_t(ref.texture)];
  if (!texture.loaded()) return 1.0f;
  const glm::vec2 uv = ref.transform(uv0);
  return (nearest ? texture.fetch(uv) : texture.sample(uv)).a;
}

}  // namespace

glm::vec3 dielectricF0(float ior, float specular, glm::vec3 specularColor) {
  // KHR_materials_ior allows ior >= 1 or exactly 0; the formula gives F0 = 1 at 0 (and in the
  // limit ior -> inf), which is what the extension means by 0. Anything negative or NaN, which
  // the importer never lets through, reads as glTF's default 1.5.
  float f0 = 0.04f;
  if (std::isinf(ior)) {
    f0 = 1.0f;
  } else if (ior >= 0.0f) {
    const float r = (ior - 1.0f) / (ior + 1.0f);
    f0 = r * r;
  }
  const glm::vec3 color = glm::max(specularColor, glm::vec3(0.0f));
  return glm::min(f0 * color, glm::vec3(1.0f)) * glm::clamp(specular, 0.0f, 1.0f);
}

// Unity's meta pass (UnityLightmappingAlbedo in UnityMetaPass.cginc) reflects
//   diffuseColor + specColor × roughness × 0.5,
// diffuseColor = baseColor × oneMinusReflectivity (OneMinusReflectivityFromMetallic: the
// dielectric reflectance, 0.04 there, comes out first), roughness = SmoothnessToRoughness, the
// square of the perceptual roughness glTF stores. glTF's dielectric reflectance comes from
// KHR_materials_ior and KHR_materials_specular, and KHR_materials_specular weights the diffuse
// base by 1 − max_value(dielectric Fresnel); at normal incidence that is 1 − max(dielectricF0).
//
// Never above 1. Per channel, with b = baseColor, m = metallic, r = roughness², d = this
// channel of dielectricF0 and D = max(dielectricF0.rgb), all in [0, 1] for a valid material
// (factors and textures in [0, 1]; F0(ior) × specularColor is clamped to 1 before the
// specular weight in [0, 1] multiplies it), and d <= D:
//   albedo = b(1 − m)(1 − D) + ((1 − m)d + m b) r / 2
//         <= b(1 − m)(1 − D) + (1 − m)D / 2 + m b / 2      (r <= 1, d <= D)
//         <=  (1 − m)(1 − D) + (1 − m)D / 2 + m / 2        (b <= 1)
//          =  (1 − m)(1 − D / 2) + m / 2  <=  1 − m / 2  <=  1,
// with 1 reached only by a white Lambertian surface (b = 1, m = 0, D = 0: specular 0).
glm::vec3 bounceAlbedo(const AlbedoInputs& in) {
  const float metallic = glm::clamp(in.metallic, 0.0f, 1.0f);
  const float perceptual = glm::clamp(in.roughness, 0.0f, 1.0f);
  const float roughness = perceptual * perceptual;
  const glm::vec3 f0 = dielectricF0(in.ior, in.specular, in.specularColor);
  const float reflectivity = std::max(f0.x, std::max(f0.y, f0.z));
  const glm::vec3 diffuse = in.baseColor * (1.0f - metallic) * (1.0f - reflectivity);
  const glm::vec3 specColor = f0 * (1.0f - metallic) + in.baseColor * metallic;
  return diffuse + specColor * roughness * 0.5f;
}

glm::vec3 diffuseAlbedo(const Scene& scene, int material, glm::vec2 uv0, bool nearest) {
  const Material& m = scene.material(material);
  const glm::vec3 mr = textureRgb(scene, m.metallicRoughnessTexture, uv0, nearest);
  AlbedoInputs in;
  in.baseColor = glm::vec3(m.baseColorFactor) * textureRgb(scene, m.baseColorTexture, uv0, nearest);
  in.metallic = m.metallicFactor * mr.b;
  in.roughness = m.roughnessFactor * mr.g;
  in.ior = m.ior;
  in.specular = m.specularFactor * textureAlpha(scene, m.specularTexture, uv0, nearest);
  in.specularColor =
      m.specularColorFactor * textureRgb(scene, m.specularColorTexture, uv0, nearest);
  return bounceAlbedo(in);
}

SurfaceBrdf surfaceBrdf(const Scene& scene, int material, glm::vec2 uv0) {
  const Material& m = scene.material(material);
  const glm::vec3 mr = textureRgb(scene, m.metallicRoughnessTexture, uv0);
  const glm::vec3 base = glm::vec3(m.baseColorFactor) * textureRgb(scene, m.baseColorTexture, uv0);
  const float metallic = glm::clamp(m.metallicFactor * mr.b, 0.0f, 1.0f);
  const glm::vec3 dielectric =
      dielectricF0(m.ior, m.specularFactor * textureAlpha(scene, m.specularTexture, uv0),
                   m.specularColorFactor * textureRgb(scene, m.specularColorTexture, uv0));
  const float reflectivity = std::max(dielectric.x, std::max(dielectric.y, dielectric.z));
  SurfaceBrdf brdf;
  brdf.diffuse = base * (1.0f - metallic) * (1.0f - reflectivity);
  brdf.f0 = glm::mix(dielectric, base, metallic);
  brdf.roughness = glm::clamp(m.roughnessFactor * mr.g, 0.0f, 1.0f);
  return brdf;
}

bool albedoTextured(const Material& m) {
  return m.baseColorTexture.valid() || m.metallicRoughnessTexture.valid() ||
         m.specularTexture.valid() || m.specularColorTexture.valid();
}

glm::vec3 diffuseAlbedoFactor(const Material& m) {
  AlbedoInputs in;
  in.baseColor = glm::vec3(m.baseColorFactor);
  in.metallic = m.metallicFactor;
  in.roughness = m.roughnessFactor;
  in.ior = m.ior;
  in.specular = m.specularFactor;
  in.specularColor = m.specularColorFactor;
  return bounceAlbedo(in);
}

bool baseColorForAlbedoFactor(const Material& material, glm::vec3 albedo,
                              glm::vec3* baseColor) {
  Material m = material;
  auto factorAt = [&](glm::vec3 base) {
    m.baseColorFactor = glm::vec4(base, material.baseColorFactor.a);
    return diffuseAlbedoFactor(m);
  };
  const glm::vec3 a0 = factorAt(glm::vec3(0.0f)), a1 = factorAt(glm::vec3(1.0f));
  glm::vec3 base = glm::vec3(material.baseColorFactor);
  constexpr float kSlack = 1e-6f;  // rounding of an albedo at a0 or a1 itself
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(albedo[c])) return false;
    if (a1[c] == a0[c]) {
      if (albedo[c] != a0[c]) return false;
      continue;  // any base colour gives it: keep the material's
    }
    const float b = (albedo[c] - a0[c]) / (a1[c] - a0[c]);
    if (!(b >= -kSlack && b <= 1.0f + kSlack)) return false;
    base[c] = glm::clamp(b, 0.0f, 1.0f);
  }
  // The channels are independent (max(dielectricF0) does not depend on the base colour): try
  // the neighbouring floats of each for one that gives the albedo bit for bit.
  glm::vec3 got = factorAt(base);
  for (int c = 0; c < 3; ++c) {
    float best = base[c];
    float error = std::abs(got[c] - albedo[c]);
    for (float dir : {-1.0f, 1.0f}) {
      float b = base[c];
      for (int step = 0; step < 4 && error > 0.0f; ++step) {
        b = std::nextafter(b, dir > 0.0f ? 2.0f : -1.0f);
        if (b < 0.0f || b > 1.0f) break;
        glm::vec3 trial = base;
        trial[c] = b;
        const float e = std::abs(factorAt(trial)[c] - albedo[c]);
        if (e < error) best = b, error = e;
      }
    }
    base[c] = best;
  }
  *baseColor = base;
  return true;
}

glm::vec3 emittedRadiance(const Scene& scene, int material, glm::vec2 uv0) {
  const Material& m = scene.material(material);
  if (!m.emissive()) return glm::vec3(0.0f);
  return m.emission() * textureRgb(scene, m.emissiveTexture, uv0);
}

Transmission transmission(const Scene& scene, int material, glm::vec2 uv0, bool blend) {
  const Material& m = scene.material(material);
  Transmission t;
  const float alpha = blend && m.alphaMode == AlphaMode::Blend
                          ? m.baseColorFactor.a * textureAlpha(scene, m.baseColorTexture, uv0)
                          : 1.0f;
  const float passes = m.transmissionFactor > 0.0f
                           ? m.transmissionFactor *
                                 textureRgb(scene, m.transmissionTexture, uv0).r
                           : 0.0f;
  const float covered = glm::clamp(alpha, 0.0f, 1.0f), opaque = 1.0f - glm::clamp(passes, 0.0f, 1.0f);
  t.open = glm::clamp(1.0f - covered * opaque, 0.0f, 1.0f);
  if (t.open > 0.0f)
    t.tint = glm::clamp(glm::vec3(m.baseColorFactor) * textureRgb(scene, m.baseColorTexture, uv0),
                        glm::vec3(0.0f), glm::vec3(1.0f));
  return t;
}

bool transmissive(const Scene& scene, int material, bool blend) {
  const Material& m = scene.material(material);
  if (m.transmissionFactor > 0.0f) return true;
  if (!blend || m.alphaMode != AlphaMode::Blend) return false;
  if (m.baseColorFactor.a < 1.0f) return true;
  const TextureRef& ref = m.baseColorTexture;
  if (!ref.valid() || size_t(ref.texture) >= scene.textures.size()) return false;
  const std::vector<glm::vec4>& texels = scene.textures[size_t(ref.texture)].texels;
  return std::any_of(texels.begin(), texels.end(), [](const glm::vec4& c) { return c.a < 1.0f; });
}

bool triangleTangents(const Scene& scene, uint32_t instance, uint32_t primitive, uint32_t triangle,
                      glm::vec3 n, glm::vec3* t, glm::vec3* b) {
  if (instance >= scene.instances.size()) return false;
  const Instance& inst = scene.instances[instance];
  const Mesh& mesh = scene.meshes[size_t(inst.mesh)];
  if (primitive >= mesh.primitives.size()) return false;
  const Primitive& prim = mesh.primitives[primitive];
  const size_t i = 3 * size_t(triangle);
  if (prim.uv0.size() != prim.positions.size() || i + 2 >= prim.indices.size()) return false;
  const uint32_t k0 = prim.indices[i], k1 = prim.indices[i + 1], k2 = prim.indices[i + 2];
  const glm::vec3 p0 = inst.toWorld(prim.positions[k0]);
  const glm::vec3 e1 = inst.toWorld(prim.positions[k1]) - p0;
  const glm::vec3 e2 = inst.toWorld(prim.positions[k2]) - p0;
  const glm::vec2 d1 = prim.uv0[k1] - prim.uv0[k0], d2 = prim.uv0[k2] - prim.uv0[k0];
  const float det = d1.x * d2.y - d2.x * d1.y;
  if (!(std::abs(det) > 1e-12f)) return false;
  const glm::vec3 dpdu = (e1 * d2.y - e2 * d1.y) / det;
  const glm::vec3 dpdv = (e2 * d1.x - e1 * d2.x) / det;
  glm::vec3 tangent = dpdu - n * glm::dot(n, dpdu);
  const float length = glm::length(tangent);
  if (!(length > 1e-12f)) return false;
  tangent /= length;
  const glm::vec3 up = glm::cross(n, tangent);
  *t = tangent;
  *b = glm::dot(up, -dpdv) >= 0.0f ? up : -up;
  return true;
}

glm::vec3 normalMapped(const Scene& scene, int material, glm::vec2 uv0, glm::vec3 n, glm::vec3 t,
                       glm::vec3 b) {
  const Material& m = scene.material(material);
  const TextureRef& ref = m.normalTexture;
  if (!ref.valid() || size_t(ref.texture) >= scene.textures.size() ||
      !scene.textures[size_t(ref.texture)].loaded())
    return n;
  const glm::vec3 c = 2.0f * textureRgb(scene, ref, uv0) - 1.0f;
  const glm::vec3 mapped = c.x * m.normalScale * t + c.y * m.normalScale * b + c.z * n;
  const float length = glm::length(mapped);
  return length > 1e-6f ? mapped / length : n;
}

}  // namespace afterglow::scenes
