// glTF export. The JSON is written directly with nlohmann::json rather than through a
// tinygltf::Model: tinygltf 2.7's writer decides on its own how buffers and images are stored
// (it embeds or re-encodes them), writes files itself instead of through AtomicOutput, and cannot
// put extras on KHR_lights_punctual lights; writing the few objects we need by hand keeps every
// byte under our control.
//
// Layout: one buffer holding, per primitive, its index view then one view per attribute
// (4-byte aligned). Instances become root nodes with their world matrix (the source hierarchy is
// already flattened in the Scene), followed by one node per light and one per camera.
#include <algorithm>
#include <array>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afterglow/core/atomic_file.h"
#include "afterglow/scenes/gltf.h"

namespace afterglow::scenes {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

constexpr int kFloat = 5126;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

// A float as the shortest decimal that reads back to the same float, so the JSON says 0.725
// rather than 0.7250000238418579 (what the float's exact double value would print as).
double num(float f) {
  if (!std::isfinite(f)) return 0.0;  // JSON has no NaN/Inf; the importer rejects them anyway
  if (f == 0.0f) return 0.0;          // no "-0.0" in the output
  char buf[32];
  auto res = std::to_chars(buf, buf + sizeof(buf), f);
  *res.ptr = '\0';
  return std::strtod(buf, nullptr);
}

json vec(glm::vec2 v) { return json::array({num(v.x), num(v.y)}); }
json vec(glm::vec3 v) { return json::array({num(v.x), num(v.y), num(v.z)}); }
json vec(glm::vec4 v) { return json::array({num(v.x), num(v.y), num(v.z), num(v.w)}); }

json matrix(const glm::mat4& m) {
  json a = json::array();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) a.push_back(num(m[c][r]));  // glTF is column-major too
  return a;
}

std::string base64(const std::string& bytes) {
  static const char* kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = uint32_t(uint8_t(bytes[i])) << 16 | uint32_t(uint8_t(bytes[i + 1])) << 8 |
                       uint32_t(uint8_t(bytes[i + 2]));
    out += kTable[v >> 18 & 63];
    out += kTable[v >> 12 & 63];
    out += kTable[v >> 6 & 63];
    out += kTable[v & 63];
  }
  if (i < bytes.size()) {
    uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    out += kTable[v >> 18 & 63];
    out += kTable[v >> 12 & 63];
    out += i + 1 < bytes.size() ? kTable[v >> 6 & 63] : '=';
    out += '=';
  }
  return out;
}

std::string percentDecode(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(uint8_t(s[i + 1])) &&
        std::isxdigit(uint8_t(s[i + 2]))) {
      out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

// URI-encodes a relative file path: RFC 3986 unreserved characters and '/' stay as they are.
std::string percentEncode(const std::string& s) {
  static const char* kHex = "0123456789ABCDEF";
  std::string out;
  for (char ch : s) {
    const uint8_t c = uint8_t(ch);
    if (std::isalnum(c) || std::strchr("-._~/", ch) != nullptr) {
      out += ch;
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

// Collects the binary buffer with its bufferViews and accessors.
class BufferWriter {
 public:
  int addView(const void* data, size_t size, int target) {
    while (bytes_.size() % 4 != 0) bytes_ += '\0';
    json view = {{"buffer", 0}, {"byteOffset", bytes_.size()}, {"byteLength", size}};
    if (target != 0) view["target"] = target;
    bytes_.append(static_cast<const char*>(data), size);
    views_.push_back(std::move(view));
    return int(views_.size() - 1);
  }

  int addAccessor(int view, int componentType, size_t count, const char* type) {
    accessors_.push_back(
        {{"bufferView", view}, {"componentType", componentType}, {"count", count}, {"type", type}});
    return int(accessors_.size() - 1);
  }

  template <class V>
  int addFloats(const std::vector<V>& values, const char* type) {
    const int view = addView(values.data(), values.size() * sizeof(V), kArrayBuffer);
    return addAccessor(view, kFloat, values.size(), type);
  }

  int addPositions(const std::vector<glm::vec3>& positions) {
    const int acc = addFloats(positions, "VEC3");
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (const glm::vec3& p : positions) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    // min/max must be the exact stored floats (validators compare them bit for bit), so they
    // are written at full double precision of the float, not shortened.
    accessors_[size_t(acc)]["min"] = {double(lo.x), double(lo.y), double(lo.z)};
    accessors_[size_t(acc)]["max"] = {double(hi.x), double(hi.y), double(hi.z)};
    return acc;
  }

  int addIndices(const std::vector<uint32_t>& indices) {
    const uint32_t maxIndex =
        indices.empty() ? 0 : *std::max_element(indices.begin(), indices.end());
    // 65535 is the primitive-restart value in some APIs, so it forces 32-bit indices.
    if (maxIndex < 65535) {
      std::vector<uint16_t> narrow(indices.begin(), indices.end());
      const int view = addView(narrow.data(), narrow.size() * 2, kElementArrayBuffer);
      return addAccessor(view, kUnsignedShort, narrow.size(), "SCALAR");
    }
    const int view = addView(indices.data(), indices.size() * 4, kElementArrayBuffer);
    return addAccessor(view, kUnsignedInt, indices.size(), "SCALAR");
  }

  std::string& bytes() { return bytes_; }
  json& views() { return views_; }
  json& accessors() { return accessors_; }

 private:
  std::string bytes_;
  json views_ = json::array();
  json accessors_ = json::array();
};

struct Exporter {
  Exporter(const Scene& s, const std::string& path) : scene(s), outPath(path) {}

  const Scene& scene;
  std::string outPath;
  json doc = json::object();
  BufferWriter buffer;
  std::set<std::string> extensionsUsed;
  bool transformRequired = false;  // a texture transform that changes the mapping was written
  std::vector<int> textureIndex;  // Scene texture -> glTF texture, -1 when not exported
  std::vector<int> meshIndex;     // Scene mesh -> glTF mesh, -1 when it had nothing to write

  Status writeMeshes() {
    json meshes = json::array();
    meshIndex.assign(scene.meshes.size(), -1);
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
      const Mesh& mesh = scene.meshes[m];
      json prims = json::array();
      for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const Primitive& prim = mesh.primitives[p];
        const size_t n = prim.positions.size();
        auto bad = [&](const char* what, size_t count) {
          return Status::error(format("%s: mesh %zu '%s' primitive %zu: %s has %zu entries for "
                                      "%zu vertices",
                                      outPath.c_str(), m, mesh.name.c_str(), p, what, count, n));
        };
        if (prim.normals.size() != n) return bad("NORMAL", prim.normals.size());
        if (!prim.uv0.empty() && prim.uv0.size() != n) return bad("TEXCOORD_0", prim.uv0.size());
        if (!prim.uv1.empty() && prim.uv1.size() != n) return bad("TEXCOORD_1", prim.uv1.size());
        if (prim.indices.size() % 3 != 0)
          return Status::error(format("%s: mesh %zu '%s' primitive %zu: %zu indices is not a "
                                      "whole number of triangles",
                                      outPath.c_str(), m, mesh.name.c_str(), p,
                                      prim.indices.size()));
        for (uint32_t i : prim.indices)
          if (i >= n)
            return Status::error(format("%s: mesh %zu '%s' primitive %zu: index %u out of range "
                                        "(%zu vertices)",
                                        outPath.c_str(), m, mesh.name.c_str(), p, i, n));
        if (prim.indices.empty()) continue;  // glTF accessors cannot be empty

        json attributes;
        attributes["POSITION"] = buffer.addPositions(prim.positions);
        attributes["NORMAL"] = buffer.addFloats(prim.normals, "VEC3");
        if (!prim.uv0.empty()) attributes["TEXCOORD_0"] = buffer.addFloats(prim.uv0, "VEC2");
        if (!prim.uv1.empty()) attributes["TEXCOORD_1"] = buffer.addFloats(prim.uv1, "VEC2");
        // The indirect grid's UVs (uv/indirect.h), where an engine reads the bounced light's
        // atlas; glTF numbers texture coordinate sets without gaps.
        if (!prim.uv0.empty() && !prim.uv1.empty() && prim.indirectUv.size() == n)
          attributes["TEXCOORD_2"] = buffer.addFloats(prim.indirectUv, "VEC2");
        json jp = {{"attributes", std::move(attributes)},
                   {"indices", buffer.addIndices(prim.indices)},
                   {"mode", 4}};
        if (prim.material >= 0) {
          if (size_t(prim.material) >= scene.materials.size())
            return Status::error(format("%s: mesh %zu '%s' primitive %zu: material %d out of "
                                        "range",
                                        outPath.c_str(), m, mesh.name.c_str(), p,
                                        prim.material));
          jp["material"] = prim.material;
        }
        prims.push_back(std::move(jp));
      }
      // A mesh without triangles has no glTF form; its instances keep their nodes, meshless.
      if (prims.empty()) continue;
      json jm = {{"primitives", std::move(prims)}};
      if (!mesh.name.empty()) jm["name"] = mesh.name;
      meshIndex[m] = int(meshes.size());
      meshes.push_back(std::move(jm));
    }
    if (!meshes.empty()) doc["meshes"] = std::move(meshes);
    return Status::ok();
  }

  // Textures keep pointing at their original image files, re-expressed relative to the output
  // folder. Embedded images (uri "") and data: URIs are not written: the Scene only holds their
  // decoded linear texels, and re-encoding those would be lossy and make the output depend on
  // which image writer is installed; the material keeps its factors and loses that texture.
  void writeTextures() {
    textureIndex.assign(scene.textures.size(), -1);
    const fs::path sourceDir =
        scene.sourcePath.empty() ? fs::path() : fs::absolute(scene.sourcePath).parent_path();
    const fs::path outDir = fs::absolute(outPath).parent_path().lexically_normal();
    json images = json::array(), textures = json::array();
    std::map<std::string, int> imageByUri;
    for (size_t t = 0; t < scene.textures.size(); ++t) {
      const Texture& tex = scene.textures[t];
      if (tex.uri.empty() || tex.uri.rfind("data:", 0) == 0) continue;
      std::string uri = tex.uri;
      // A scene built in code has no folder to resolve against; its URIs are kept as given.
      if (!scene.sourcePath.empty() && uri.find("://") == std::string::npos) {
        const fs::path file = (sourceDir / percentDecode(uri)).lexically_normal();
        uri = percentEncode(file.lexically_relative(outDir).generic_string());
      }
      auto it = imageByUri.find(uri);
      if (it == imageByUri.end()) {
        json image = {{"uri", uri}};
        if (!tex.name.empty()) image["name"] = tex.name;
        it = imageByUri.emplace(uri, int(images.size())).first;
        images.push_back(std::move(image));
      }
      json jt = {{"source", it->second}, {"sampler", 0}};
      if (!tex.name.empty()) jt["name"] = tex.name;
      textureIndex[t] = int(textures.size());
      textures.push_back(std::move(jt));
    }
    if (textures.empty()) return;
    // Texture::sample filters bilinearly with repeat wrapping; say so for other viewers.
    doc["samplers"] = json::array(
        {{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 10497}, {"wrapT", 10497}}});
    doc["images"] = std::move(images);
    doc["textures"] = std::move(textures);
  }

  // Returns a textureInfo, or null when the texture was not exported.
  json textureInfo(const TextureRef& ref) {
    if (!ref.valid() || size_t(ref.texture) >= textureIndex.size() ||
        textureIndex[size_t(ref.texture)] < 0)
      return nullptr;
    json info = {{"index", textureIndex[size_t(ref.texture)]}};
    if (ref.texCoord != 0) info["texCoord"] = ref.texCoord;
    if (ref.hasTransform) {
      json tt;
      if (ref.offset != glm::vec2(0.0f)) tt["offset"] = vec(ref.offset);
      if (ref.rotation != 0.0f) tt["rotation"] = num(ref.rotation);
      if (ref.scale != glm::vec2(1.0f)) tt["scale"] = vec(ref.scale);
      if (tt.is_null())
        tt = json::object();
      else
        transformRequired = true;
      info["extensions"]["KHR_texture_transform"] = std::move(tt);
      extensionsUsed.insert("KHR_texture_transform");
    }
    return info;
  }

  void writeMaterials() {
    json materials = json::array();
    for (const Material& mat : scene.materials) {
      json pbr = {{"baseColorFactor", vec(mat.baseColorFactor)},
                  {"metallicFactor", num(mat.metallicFactor)},
                  {"roughnessFactor", num(mat.roughnessFactor)}};
      if (json t = textureInfo(mat.baseColorTexture); !t.is_null())
        pbr["baseColorTexture"] = std::move(t);
      if (json t = textureInfo(mat.metallicRoughnessTexture); !t.is_null())
        pbr["metallicRoughnessTexture"] = std::move(t);
      json jm = {{"pbrMetallicRoughness", std::move(pbr)}};
      if (!mat.name.empty()) jm["name"] = mat.name;
      if (json t = textureInfo(mat.normalTexture); !t.is_null()) {
        if (mat.normalScale != 1.0f) t["scale"] = num(mat.normalScale);
        jm["normalTexture"] = t;
      }
      if (json t = textureInfo(mat.occlusionTexture); !t.is_null()) jm["occlusionTexture"] = t;
      if (json t = textureInfo(mat.emissiveTexture); !t.is_null()) jm["emissiveTexture"] = t;
      if (mat.emissiveFactor != glm::vec3(0.0f)) jm["emissiveFactor"] = vec(mat.emissiveFactor);
      if (mat.emissiveStrength != 1.0f) {
        jm["extensions"]["KHR_materials_emissive_strength"] = {
            {"emissiveStrength", num(mat.emissiveStrength)}};
        extensionsUsed.insert("KHR_materials_emissive_strength");
      }
      if (mat.ior != 1.5f) {
        jm["extensions"]["KHR_materials_ior"] = {{"ior", num(mat.ior)}};
        extensionsUsed.insert("KHR_materials_ior");
      }
      json specular = json::object();
      if (mat.specularFactor != 1.0f) specular["specularFactor"] = num(mat.specularFactor);
      if (json t = textureInfo(mat.specularTexture); !t.is_null())
        specular["specularTexture"] = std::move(t);
      if (mat.specularColorFactor != glm::vec3(1.0f))
        specular["specularColorFactor"] = vec(mat.specularColorFactor);
      if (json t = textureInfo(mat.specularColorTexture); !t.is_null())
        specular["specularColorTexture"] = std::move(t);
      if (!specular.empty()) {
        jm["extensions"]["KHR_materials_specular"] = std::move(specular);
        extensionsUsed.insert("KHR_materials_specular");
      }
      json transmission = json::object();
      if (mat.transmissionFactor != 0.0f)
        transmission["transmissionFactor"] = num(mat.transmissionFactor);
      if (json t = textureInfo(mat.transmissionTexture); !t.is_null())
        transmission["transmissionTexture"] = std::move(t);
      if (!transmission.empty()) {
        jm["extensions"]["KHR_materials_transmission"] = std::move(transmission);
        extensionsUsed.insert("KHR_materials_transmission");
      }
      if (mat.alphaMode == AlphaMode::Mask) {
        jm["alphaMode"] = "MASK";
        jm["alphaCutoff"] = num(mat.alphaCutoff);
      } else if (mat.alphaMode == AlphaMode::Blend) {
        jm["alphaMode"] = "BLEND";
      }
      if (mat.doubleSided) jm["doubleSided"] = true;
      if (mat.singleSidedEmission) jm["extras"]["afterglow"]["singleSidedEmission"] = true;
      materials.push_back(std::move(jm));
    }
    if (!materials.empty()) doc["materials"] = std::move(materials);
  }

  // Rotation (x, y, z, w) taking the node's -Z, where KHR_lights_punctual lights point, onto d.
  static json lightRotation(glm::vec3 d) {
    const float len = glm::length(d);
    if (!(len > 0.0f)) return nullptr;
    d /= len;
    const glm::vec3 from(0.0f, 0.0f, -1.0f);
    const float c = glm::dot(from, d);
    if (c > 1.0f - 1e-7f) return nullptr;  // already along -Z
    glm::vec4 q;
    if (c < -1.0f + 1e-7f) {
      q = glm::vec4(0.0f, 1.0f, 0.0f, 0.0f);  // half a turn about Y
    } else {
      const glm::vec3 axis = glm::cross(from, d);
      q = glm::normalize(glm::vec4(axis, 1.0f + c));
    }
    return json::array({num(q.x), num(q.y), num(q.z), num(q.w)});
  }

  void writeNodes() {
    json nodes = json::array();
    for (const Instance& inst : scene.instances) {
      json node;
      if (!inst.name.empty()) node["name"] = inst.name;
      if (inst.mesh >= 0 && size_t(inst.mesh) < meshIndex.size() &&
          meshIndex[size_t(inst.mesh)] >= 0)
        node["mesh"] = meshIndex[size_t(inst.mesh)];
      if (inst.transform != glm::mat4(1.0f)) node["matrix"] = matrix(inst.transform);
      json ag = json::object();
      if (!inst.isStatic) ag["static"] = false;
      if (inst.lightmapScale != 1.0f) ag["lightmapScale"] = num(inst.lightmapScale);
      if (!inst.castShadows) ag["castShadows"] = false;
      if (inst.lightmap.atlas >= 0)
        ag["lightmap"] = {{"atlas", inst.lightmap.atlas},
                          {"width", inst.lightmap.width},
                          {"height", inst.lightmap.height}};
      if (inst.indirectLightmap.atlas >= 0)
        ag["indirectLightmap"] = {{"atlas", inst.indirectLightmap.atlas},
                                  {"width", inst.indirectLightmap.width},
                                  {"height", inst.indirectLightmap.height}};
      if (!ag.empty()) node["extras"]["afterglow"] = std::move(ag);
      nodes.push_back(std::move(node));
    }
    // Probe volumes on nodes of their own (a volume that shared a node with a mesh comes back
    // as two nodes of one name; placement reads only the box).
    for (const ProbeVolume& volume : scene.probeVolumes) {
      json node;
      if (!volume.name.empty()) node["name"] = volume.name;
      if (volume.transform != glm::mat4(1.0f)) node["matrix"] = matrix(volume.transform);
      json pv = {{"size", vec(volume.size)}};
      if (volume.spacing > 0.0f) pv["spacing"] = num(volume.spacing);
      node["extras"]["afterglow"]["probeVolume"] = std::move(pv);
      nodes.push_back(std::move(node));
    }
    // Reflection probes likewise, every member written (a reader sees the values in force).
    for (const ReflectionProbe& probe : scene.reflectionProbes) {
      json node;
      if (!probe.name.empty()) node["name"] = probe.name;
      if (probe.transform != glm::mat4(1.0f)) node["matrix"] = matrix(probe.transform);
      json rp = {{"blendDistance", num(probe.blendDistance)},
                 {"importance", probe.importance},
                 {"boxProjection", probe.boxProjection},
                 {"resolution", probe.resolution}};
      if (probe.size != glm::vec3(0.0f)) rp["size"] = vec(probe.size);
      if (probe.projectionSize != glm::vec3(0.0f)) rp["projectionSize"] = vec(probe.projectionSize);
      node["extras"]["afterglow"]["reflectionProbe"] = std::move(rp);
      nodes.push_back(std::move(node));
    }

    json lights = json::array();
    const Light defaults;
    for (const Light& light : scene.lights) {
      json jl = {{"color", vec(light.color)}, {"intensity", num(light.intensity)}};
      if (!light.name.empty()) jl["name"] = light.name;
      switch (light.type) {
        case LightType::Directional: jl["type"] = "directional"; break;
        case LightType::Point: jl["type"] = "point"; break;
        case LightType::Spot:
          jl["type"] = "spot";
          jl["spot"] = {{"innerConeAngle", num(light.innerConeAngle)},
                        {"outerConeAngle", num(light.outerConeAngle)}};
          break;
      }
      if (light.range > 0.0f && light.type != LightType::Directional)
        jl["range"] = num(light.range);
      json ag = json::object();
      if (light.radius != defaults.radius) ag["radius"] = num(light.radius);
      if (light.angularDiameter != defaults.angularDiameter)
        ag["angularDiameter"] = num(light.angularDiameter);
      if (light.bounceIntensity != defaults.bounceIntensity)
        ag["bounceIntensity"] = num(light.bounceIntensity);
      if (!ag.empty()) jl["extras"]["afterglow"] = std::move(ag);

      json node;
      if (!light.name.empty()) node["name"] = light.name;
      if (light.position != glm::vec3(0.0f)) node["translation"] = vec(light.position);
      if (light.type != LightType::Point)
        if (json r = lightRotation(light.direction); !r.is_null()) node["rotation"] = r;
      node["extensions"]["KHR_lights_punctual"] = {{"light", lights.size()}};
      lights.push_back(std::move(jl));
      nodes.push_back(std::move(node));
    }
    if (!lights.empty()) {
      doc["extensions"]["KHR_lights_punctual"] = {{"lights", std::move(lights)}};
      extensionsUsed.insert("KHR_lights_punctual");
    }

    json cameras = json::array();
    for (const Camera& cam : scene.cameras) {
      json jc;
      if (!cam.name.empty()) jc["name"] = cam.name;
      if (cam.perspective) {
        jc["type"] = "perspective";
        json p = {{"yfov", num(cam.yfov)}, {"znear", num(cam.znear)}};
        if (cam.aspectRatio > 0.0f) p["aspectRatio"] = num(cam.aspectRatio);
        if (cam.zfar > 0.0f) p["zfar"] = num(cam.zfar);
        jc["perspective"] = std::move(p);
      } else {
        jc["type"] = "orthographic";
        // glTF requires a finite zfar beyond znear for orthographic cameras.
        const float zfar = cam.zfar > cam.znear ? cam.zfar : cam.znear + 1000.0f;
        jc["orthographic"] = {{"xmag", num(cam.xmag)},
                              {"ymag", num(cam.ymag)},
                              {"znear", num(cam.znear)},
                              {"zfar", num(zfar)}};
      }
      json node = {{"camera", cameras.size()}};
      if (!cam.name.empty()) node["name"] = cam.name;
      if (cam.transform != glm::mat4(1.0f)) node["matrix"] = matrix(cam.transform);
      cameras.push_back(std::move(jc));
      nodes.push_back(std::move(node));
    }
    if (!cameras.empty()) doc["cameras"] = std::move(cameras);

    json roots = json::array();
    for (size_t i = 0; i < nodes.size(); ++i) roots.push_back(i);
    if (!nodes.empty()) doc["nodes"] = std::move(nodes);
    doc["scene"] = 0;
    doc["scenes"] = json::array({{{"nodes", std::move(roots)}}});
  }
};

bool endsWithNoCase(const std::string& s, const std::string& suffix) {
  if (s.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(uint8_t(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
  return true;
}

void appendU32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out += char((v >> (8 * i)) & 0xff);  // GLB is little-endian
}

std::string makeGlb(const std::string& jsonText, const std::string& bin) {
  std::string jsonChunk = jsonText;
  while (jsonChunk.size() % 4 != 0) jsonChunk += ' ';
  std::string binChunk = bin;
  while (binChunk.size() % 4 != 0) binChunk += '\0';
  const size_t total = 12 + 8 + jsonChunk.size() + (binChunk.empty() ? 0 : 8 + binChunk.size());
  std::string out;
  out.reserve(total);
  out += "glTF";
  appendU32(out, 2);
  appendU32(out, uint32_t(total));
  appendU32(out, uint32_t(jsonChunk.size()));
  appendU32(out, 0x4E4F534Au);  // "JSON"
  out += jsonChunk;
  if (!binChunk.empty()) {
    appendU32(out, uint32_t(binChunk.size()));
    appendU32(out, 0x004E4942u);  // "BIN\0"
    out += binChunk;
  }
  return out;
}

}  // namespace

Status saveGltf(const Scene& scene, const std::string& path, const SaveOptions& options) {
  if (path.empty()) return Status::error("saveGltf: empty output path");
  Exporter ex(scene, path);
  ex.doc["asset"] = {{"version", "2.0"}, {"generator", "afterglow"}};
  if (Status s = ex.writeMeshes(); !s) return s;
  ex.writeTextures();
  ex.writeMaterials();
  ex.writeNodes();

  const bool glb = endsWithNoCase(path, ".glb");
  const std::string& bin = ex.buffer.bytes();
  AtomicOutput out;
  if (!bin.empty()) {
    json buf = {{"byteLength", bin.size()}};
    if (glb) {
      // The GLB binary chunk is the buffer; it needs no URI.
    } else if (options.embedBuffers) {
      buf["uri"] = "data:application/octet-stream;base64," + base64(bin);
    } else {
      const fs::path binPath = fs::path(path).replace_extension(".bin");
      buf["uri"] = percentEncode(binPath.filename().string());
      if (Status s = out.write(binPath.string(), bin); !s) return s;
    }
    ex.doc["buffers"] = json::array({std::move(buf)});
    ex.doc["bufferViews"] = std::move(ex.buffer.views());
    ex.doc["accessors"] = std::move(ex.buffer.accessors());
  }
  if (!ex.extensionsUsed.empty())
    ex.doc["extensionsUsed"] = std::vector<std::string>(ex.extensionsUsed.begin(),
                                                        ex.extensionsUsed.end());
  // Lights, emissive strength, ior, specular and transmission degrade gracefully in a viewer
  // that lacks them; a texture transform that is not the identity does not (the textures would
  // land in the wrong place), so only that one is required, as the source files that use it do.
  if (ex.transformRequired) ex.doc["extensionsRequired"] = {"KHR_texture_transform"};

  const std::string text = glb ? ex.doc.dump() : ex.doc.dump(1);
  if (Status s = out.write(path, glb ? makeGlb(text, bin) : text + "\n"); !s) return s;
  return out.commit();
}

}  // namespace afterglow::scenes
