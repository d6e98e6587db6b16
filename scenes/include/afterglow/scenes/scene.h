// The Scene model: what afterglow knows of a level once it is loaded. Every later stage (UVs,
// baking, probes) reads this and nothing else, so it holds world-ready data: triangle lists with
// generated normals, linear colours, decoded linear textures, flattened instances with their
// world transforms. Units follow glTF: metres, lux for directional lights, candela for point and
// spot lights, emissive radiance = emissiveFactor × emissiveTexture × emissiveStrength.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace afterglow::scenes {

// A reference from a material to a texture, with KHR_texture_transform applied on lookup.
struct TextureRef {
  int texture = -1;           // index into Scene::textures; -1 = no texture
  int texCoord = 0;           // UV set (0 = TEXCOORD_0), after KHR_texture_transform's override
  glm::vec2 offset{0.0f};     // KHR_texture_transform offset, in UV units
  glm::vec2 scale{1.0f};      // KHR_texture_transform scale
  float rotation = 0.0f;      // KHR_texture_transform rotation, radians, counter-clockwise
  bool hasTransform = false;  // true when the glTF carried KHR_texture_transform

  bool valid() const { return texture >= 0; }
  // Maps a mesh UV to the texture's UV as KHR_texture_transform defines (T * R * S).
  glm::vec2 transform(glm::vec2 uv) const;
};

// A decoded texture. Colour textures (base colour, emissive, specular colour) are decoded from
// sRGB to linear on load; data textures (metallic-roughness, specular, normal) are kept linear
// as stored.
struct Texture {
  std::string name;
  std::string uri;       // as written in the glTF (file name or "" when embedded)
  int width = 0;         // 0 when the image could not be loaded (the material falls back)
  int height = 0;
  bool srgb = false;     // true when it was decoded from sRGB
  std::vector<glm::vec4> texels;  // linear RGBA, row-major, first row at v = 0

  bool loaded() const { return width > 0 && height > 0; }
  // Bilinear lookup with repeat wrapping; returns (1,1,1,1) when not loaded.
  glm::vec4 sample(glm::vec2 uv) const;
  // The nearest texel, with repeat wrapping: one read where sample makes four, for estimates
  // that average many point samples anyway (the gather's hits).
  glm::vec4 fetch(glm::vec2 uv) const;
  // The texel fetch reads (for prefetching), or null when not loaded.
  const glm::vec4* texelAt(glm::vec2 uv) const;
};

enum class AlphaMode { Opaque, Mask, Blend };

struct Material {
  std::string name;
  glm::vec4 baseColorFactor{1.0f};  // linear RGBA
  TextureRef baseColorTexture;
  float metallicFactor = 1.0f;
  float roughnessFactor = 1.0f;
  TextureRef metallicRoughnessTexture;  // G = roughness, B = metallic
  // KHR_materials_ior: index of refraction, >= 1, or 0 for a dielectric F0 of 1 (the
  // extension's specular-glossiness conversion). Sets F0 = ((ior − 1)/(ior + 1))².
  float ior = 1.5f;
  // KHR_materials_specular: the strength of the dielectric specular reflection (0 = a purely
  // diffuse dielectric), [0, 1], × specularTexture.a (linear); and its F0 colour, >= 0,
  // × specularColorTexture.rgb (decoded from sRGB).
  float specularFactor = 1.0f;
  TextureRef specularTexture;
  glm::vec3 specularColorFactor{1.0f};  // linear RGB
  TextureRef specularColorTexture;
  // KHR_materials_transmission: the fraction of light that passes through the surface, [0, 1],
  // × transmissionTexture.r (linear), tinted by the base colour (material_eval.h, transmission).
  float transmissionFactor = 0.0f;
  TextureRef transmissionTexture;
  TextureRef normalTexture;             // the bake ignores it; `render` tilts the directional
                                        //   lightmaps' normals by it
  float normalScale = 1.0f;             // normalTexture.scale: the map's x and y are scaled by it
  TextureRef occlusionTexture;          // kept for export; not used for lighting
  glm::vec3 emissiveFactor{0.0f};       // linear RGB
  float emissiveStrength = 1.0f;        // KHR_materials_emissive_strength
  TextureRef emissiveTexture;
  bool doubleSided = false;
  // extras.afterglow.singleSidedEmission (or `afterglow bake --single-sided-emission` for every
  // material): a double-sided emissive surface emits from its front only, for engines whose
  // emissive shading ignores back faces. Off by default: glTF shades the back of a doubleSided
  // material with the normal reversed, emission included, so its back glows in every viewer
  // and in Cycles. The back still reflects light either way.
  bool singleSidedEmission = false;
  AlphaMode alphaMode = AlphaMode::Opaque;
  float alphaCutoff = 0.5f;  // used when alphaMode == Mask

  // Emitted radiance of an untextured point (W·sr⁻¹·m⁻² in glTF's photometric sense).
  glm::vec3 emission() const { return emissiveFactor * emissiveStrength; }
  bool emissive() const { return emission() != glm::vec3(0.0f); }
  // Whether the back face emits: the one rule the direct light, the clusters, the reference
  // path tracer and the renderer share.
  bool emitsFromBack() const { return doubleSided && !singleSidedEmission; }
  bool emitsFrom(bool frontFace) const { return frontFace || emitsFromBack(); }
};

// One triangle list with one material. Attribute arrays are per vertex; uv0/uv1 are empty when
// the glTF had none. Normals are always present (flat normals are generated when missing).
struct Primitive {
  int material = -1;  // index into Scene::materials; -1 = glTF's default material
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<glm::vec2> uv0;
  std::vector<glm::vec2> uv1;  // lightmap UVs (authored, or written by afterglow uv)
  // Indirect UVs (Unity's realtime lightmap UVs): uv1's charts repacked at the indirect density
  // into the indirect atlas, where bounced light is solved (uv/indirect.h); empty when the
  // bounced light is solved at the lightmap's own texels.
  std::vector<glm::vec2> indirectUv;
  std::vector<uint32_t> indices;  // 3 per triangle; always filled, also for non-indexed input

  size_t triangleCount() const { return indices.size() / 3; }
};

struct Mesh {
  std::string name;
  std::vector<Primitive> primitives;

  size_t triangleCount() const;
};

// Where an instance's lightmap lives, once UVs are packed.
struct LightmapLocation {
  int atlas = -1;  // index of the atlas; -1 = no lightmap
  int width = 0;   // atlas size in texels
  int height = 0;
};

// The lightmap UV set a stage works on: the lightmap's (uv1) or the indirect grid's (indirectUv).
enum class LightmapUvSet : uint8_t { Lightmap, Indirect };

// A mesh placed in the world by a glTF node. One mesh used by several nodes stays one Mesh with
// several Instances.
struct Instance {
  std::string name;  // the node's name (or "node<i>" when unnamed)
  int node = -1;     // index of the glTF node it came from
  int mesh = -1;     // index into Scene::meshes
  glm::mat4 transform{1.0f};  // object to world
  // extras.afterglow on the node (or inherited from its parent):
  bool isStatic = true;        // "static": gets a lightmap and takes part in bounces
  float lightmapScale = 1.0f;  // "lightmapScale": multiplies texelsPerUnit for this instance
  bool castShadows = true;     // "castShadows"
  LightmapLocation lightmap;
  LightmapLocation indirectLightmap;  // where its indirectUv point (atlas -1: none)

  // A point of its mesh in world space.
  glm::vec3 toWorld(glm::vec3 local) const { return glm::vec3(transform * glm::vec4(local, 1.0f)); }
};

enum class LightType { Directional, Point, Spot };

// How a light's direct light is baked (Unity's light modes, extras.afterglow.mode): into the
// lightmaps and probes (baked); or left to the engine, its bounced light baked (realtime; mixed
// too, whose static shadow is meant for a shadowmask).
enum class LightMode { Baked, Mixed, Realtime };

// KHR_lights_punctual, placed in the world.
struct Light {
  std::string name;
  LightType type = LightType::Point;
  glm::vec3 color{1.0f};   // linear RGB
  float intensity = 1.0f;  // lux (directional) or candela (point, spot)
  float range = 0.0f;      // metres; 0 = infinite
  float innerConeAngle = 0.0f;                     // radians (spot)
  float outerConeAngle = 0.78539816339744830962f;  // radians (spot), π/4 by default
  glm::vec3 position{0.0f};                 // world (point, spot)
  glm::vec3 direction{0.0f, 0.0f, -1.0f};   // world, the way the light travels (directional, spot)
  int node = -1;
  // extras.afterglow on the light:
  float radius = 0.0f;              // "radius", metres: soft shadows for point and spot lights
  float angularDiameter = 0.00925f; // "angularDiameter", radians (the sun's 0.53°): directional
  float bounceIntensity = 1.0f;     // "bounceIntensity": scales this light in bounced light only
  LightMode mode = LightMode::Baked;  // "mode": "baked", "mixed" or "realtime"
};

struct Camera {
  std::string name;
  bool perspective = true;
  float yfov = 0.8f;         // radians
  float aspectRatio = 0.0f;  // 0 = use the image's
  float znear = 0.01f;
  float zfar = 0.0f;         // 0 = infinite
  float xmag = 1.0f, ymag = 1.0f;  // orthographic half extents
  glm::mat4 transform{1.0f};       // camera to world; looks down -Z, +Y up
  int node = -1;
};

// extras.afterglow.probeVolume on a glTF node: a box of light probes, centred on the node and
// turned by its world transform.
struct ProbeVolume {
  std::string name;               // the node's name (or "node<i>")
  int node = -1;
  glm::mat4 transform{1.0f};      // node to world
  glm::vec3 size{0.0f};           // "size": metres along the node's axes (before its scale)
  float spacing = 0.0f;           // "spacing": metres; 0 = the placement's own
};

// extras.afterglow.reflectionProbe on a glTF node: a reflection probe captured at the node's
// origin, lighting an influence box centred on the node and turned by its world transform.
// `{}` takes every default (the box then fitted to the surrounding walls by the bake).
struct ReflectionProbe {
  std::string name;               // the node's name (or "node<i>")
  int node = -1;
  glm::mat4 transform{1.0f};      // node to world
  glm::vec3 size{0.0f};           // "size": metres along the node's axes (before its scale);
                                  //   0 = fitted by the bake
  // "projectionSize": the box that box projection intersects, centred with it (HDRP's proxy
  // volume: the room's walls, where the influence box reaches blendDistance beyond them so that
  // the walls get the probe's full weight); 0 = the influence box itself.
  glm::vec3 projectionSize{0.0f};
  float blendDistance = 1.0f;     // "blendDistance": metres inside the box over which it fades
  int importance = 1;             // "importance": a higher one wins where boxes overlap
  bool boxProjection = true;      // "boxProjection": parallax-corrected lookups
  int resolution = 128;           // "resolution": cubemap face size, texels (a power of two)
};

struct Bounds {
  glm::vec3 min{1e30f};
  glm::vec3 max{-1e30f};
  bool empty() const { return min.x > max.x; }
  void extend(glm::vec3 p) { min = glm::min(min, p); max = glm::max(max, p); }
  glm::vec3 size() const { return empty() ? glm::vec3(0.0f) : max - min; }
};

struct Scene {
  std::string sourcePath;  // file it was loaded from ("" for procedural scenes)
  std::vector<Mesh> meshes;
  std::vector<Material> materials;
  std::vector<Texture> textures;
  std::vector<Instance> instances;
  std::vector<Light> lights;
  std::vector<Camera> cameras;
  std::vector<ProbeVolume> probeVolumes;
  std::vector<ReflectionProbe> reflectionProbes;
  std::vector<std::string> warnings;  // everything the loader skipped or fixed up

  // The material of a primitive, or the glTF default material for -1.
  const Material& material(int index) const;
  // The mesh an instance places, or null when its index is out of range.
  const Mesh* meshOf(const Instance& instance) const {
    return instance.mesh >= 0 && size_t(instance.mesh) < meshes.size()
               ? &meshes[size_t(instance.mesh)] : nullptr;
  }
  // World-space bounds over all instances.
  Bounds bounds() const;
  // World-space bounds over the finite vertices of static instances (dynamic objects move: they
  // shape neither probe grids nor reflection probes).
  Bounds staticBounds() const;
  // Triangles over all instances (instanced meshes counted once per instance).
  size_t instancedTriangleCount() const;
  // Triangles over unique meshes.
  size_t meshTriangleCount() const;
};

// A primitive's UVs and an instance's atlas in one of the two lightmap UV sets.
inline const std::vector<glm::vec2>& lightmapUvs(const Primitive& prim, LightmapUvSet set) {
  return set == LightmapUvSet::Indirect ? prim.indirectUv : prim.uv1;
}
inline const LightmapLocation& lightmapOf(const Instance& instance, LightmapUvSet set) {
  return set == LightmapUvSet::Indirect ? instance.indirectLightmap : instance.lightmap;
}

// Calls fn(triangle, a, b, c) for each triangle of `prim` whose three indices are in range, with
// its corners in world space through `instance` (finite or not: the caller decides).
template <class Fn>
void forEachWorldTriangle(const Instance& instance, const Primitive& prim, Fn&& fn) {
  for (size_t k = 0; k + 2 < prim.indices.size(); k += 3) {
    const uint32_t i0 = prim.indices[k], i1 = prim.indices[k + 1], i2 = prim.indices[k + 2];
    if (i0 >= prim.positions.size() || i1 >= prim.positions.size() ||
        i2 >= prim.positions.size())
      continue;
    fn(k / 3, instance.toWorld(prim.positions[i0]), instance.toWorld(prim.positions[i1]),
       instance.toWorld(prim.positions[i2]));
  }
}
// The same over every primitive of an instance: fn(primitive, triangle, a, b, c).
template <class Fn>
void forEachWorldTriangle(const Scene& scene, const Instance& instance, Fn&& fn) {
  const Mesh* mesh = scene.meshOf(instance);
  if (!mesh) return;
  for (size_t p = 0; p < mesh->primitives.size(); ++p)
    forEachWorldTriangle(instance, mesh->primitives[p],
                         [&](size_t t, glm::vec3 a, glm::vec3 b, glm::vec3 c) { fn(p, t, a, b, c); });
}

}  // namespace afterglow::scenes
