// glTF 2.0 import (.gltf and .glb) into the Scene model.
//
// tinygltf parses the JSON and loads buffers; everything it leaves unchecked (accessor ranges,
// indices, node references, cycles) is validated here before a byte is read, so a malformed file
// gives one error line naming the file and the object at fault, never a crash. Recoverable
// problems become Scene::warnings.
//
// Choices worth knowing:
// - Scene::textures holds one entry per (glTF image, colour space) pair that materials use: an
//   image used as base colour (sRGB) and as metallic-roughness (linear) is decoded twice.
// - Normal and occlusion textures are kept as references (name, URI) for the exporter but are not
//   decoded: the bake samples neither, and decoding them would double load time. `render`
//   decodes the normal textures (LoadOptions::loadNormalTextures) for directional lightmaps.
// - Only the meshes that the selected scene instantiates are imported.
// - Instances with a negative-determinant transform keep their data as stored; their world-space
//   winding is flipped, which later stages detect from the determinant.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "afterglow/core/parallel.h"
#include "afterglow/scenes/gltf.h"
#include "texture_io.h"
#include "tinygltf_config.h"

namespace afterglow::scenes {

namespace {

namespace fs = std::filesystem;

// Limits that keep hostile files from exhausting memory or the stack.
constexpr size_t kMaxInputBytes = size_t(1) << 31;        // tinygltf takes 32-bit sizes
constexpr size_t kMaxAccessorElements = size_t(1) << 28;  // elements in one accessor
// An accessor without a bufferView is zeros (plus sparse values): its count is not bounded by
// any buffer, so it gets a tighter cap.
constexpr size_t kMaxElementsWithoutBufferView = size_t(1) << 20;
constexpr int kMaxJsonDepth = 200;   // tinygltf converts extras recursively
constexpr size_t kMaxWarnings = 500;  // a broken file must not produce millions of lines

const std::set<std::string>& supportedExtensions() {
  static const std::set<std::string> kSupported = {
      "KHR_lights_punctual", "KHR_texture_transform", "KHR_materials_emissive_strength",
      "KHR_materials_ior", "KHR_materials_specular", "KHR_materials_transmission",
      "KHR_mesh_quantization"};
  return kSupported;
}

// Numbers from the file become floats; converting a finite double beyond float's range is
// undefined behaviour, so such values saturate (and NaN becomes 0).
float narrow(double v) {
  if (std::isnan(v)) return 0.0f;
  const double limit = double(std::numeric_limits<float>::max());
  return float(std::clamp(v, -limit, limit));
}
glm::vec3 narrow3(const glm::dvec3& v) { return glm::vec3(narrow(v.x), narrow(v.y), narrow(v.z)); }
glm::vec3 narrow3(const glm::dvec4& v) { return narrow3(glm::dvec3(v)); }
glm::mat4 narrowMat(const glm::dmat4& m) {
  glm::mat4 out;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) out[c][r] = narrow(m[c][r]);
  return out;
}

std::string label(const char* kind, size_t index, const std::string& name) {
  if (name.empty()) return format("%s %zu", kind, index);
  return format("%s '%s'", kind, name.c_str());
}

std::string firstLine(const std::string& text) {
  size_t begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return "unknown error";
  size_t end = text.find_first_of("\r\n", begin);
  std::string line = text.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
  while (!line.empty() && (line.back() == ' ' || line.back() == '.')) line.pop_back();
  // tinygltf quotes whole data: URIs in some messages.
  if (line.size() > 200) line = line.substr(0, 200) + "...";
  return line;
}

std::string percentDecode(const std::string& uri) {
  auto hex = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  std::string out;
  out.reserve(uri.size());
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && hex(uri[i + 1]) >= 0 && hex(uri[i + 2]) >= 0) {
      out.push_back(char(hex(uri[i + 1]) * 16 + hex(uri[i + 2])));
      i += 2;
    } else {
      out.push_back(uri[i]);
    }
  }
  return out;
}

// Deeply nested JSON would overflow the stack in tinygltf's recursive conversion of extras.
bool jsonTooDeep(const char* s, size_t n) {
  int depth = 0;
  bool inString = false;
  for (size_t i = 0; i < n; ++i) {
    char c = s[i];
    if (inString) {
      if (c == '\\') ++i;
      else if (c == '"') inString = false;
    } else if (c == '"') {
      inString = true;
    } else if (c == '{' || c == '[') {
      if (++depth > kMaxJsonDepth) return true;
    } else if (c == '}' || c == ']') {
      --depth;
    }
  }
  return false;
}

uint32_t readU32(const unsigned char* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// tinygltf 2.7 checks the BIN chunk's length without its 8-byte header and would read past
// the end of the data; validate the container here so it only sees consistent GLBs.
Status checkGlbContainer(const std::string& bytes, const std::string& file, size_t& jsonOffset,
                         size_t& jsonLength) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  const uint64_t size = bytes.size();
  if (size < 20) return Status::error(file + ": truncated GLB header");
  const uint32_t version = readU32(p + 4), length = readU32(p + 8);
  if (version != 2) return Status::error(format("%s: GLB version %u is not 2", file.c_str(), version));
  if (length > size)
    return Status::error(format("%s: GLB header says %u bytes but the file has %llu", file.c_str(),
                                length, (unsigned long long)size));
  const uint64_t chunk0Length = readU32(p + 12), chunk0Type = readU32(p + 16);
  if (chunk0Type != 0x4E4F534Au) return Status::error(file + ": GLB's first chunk is not JSON");
  if (chunk0Length == 0 || 20 + chunk0Length > length)
    return Status::error(format("%s: GLB JSON chunk (%llu bytes) runs past the end of the file",
                                file.c_str(), (unsigned long long)chunk0Length));
  const uint64_t binStart = 20 + chunk0Length;
  if (binStart < length) {
    if (binStart + 8 > length)
      return Status::error(file + ": GLB has a truncated chunk header after the JSON chunk");
    const uint64_t chunk1Length = readU32(p + binStart);
    const uint32_t chunk1Type = readU32(p + binStart + 4);
    if (chunk1Type != 0x004E4942u)
      return Status::error(file + ": GLB's second chunk is not BIN");
    if (binStart + 8 + chunk1Length > length)
      return Status::error(format("%s: GLB BIN chunk (%llu bytes) runs past the end of the file",
                                  file.c_str(), (unsigned long long)chunk1Length));
    if (chunk1Length < 4 || chunk1Length % 4 != 0)
      return Status::error(format("%s: GLB BIN chunk length %llu is not a positive multiple of 4",
                                  file.c_str(), (unsigned long long)chunk1Length));
  }
  jsonOffset = 20;
  jsonLength = size_t(chunk0Length);
  return Status::ok();
}

// tinygltf 2.7 takes the address of an image's bufferView bytes before anyone checks that the
// bufferView lies inside its buffer (pointer overflow for absurd offsets). Buffers always end up
// exactly as long as their declared byteLength, so the declared numbers are checked up front.
Status checkImageBufferViews(const nlohmann::json& root, const std::string& file) {
  if (root.is_discarded() || !root.is_object()) return Status::ok();  // tinygltf reports it
  auto array = [&](const char* key) -> const nlohmann::json* {
    auto it = root.find(key);
    return it != root.end() && it->is_array() ? &*it : nullptr;
  };
  auto unsignedMember = [](const nlohmann::json& o, const char* key, uint64_t fallback) {
    auto it = o.find(key);
    return it != o.end() && it->is_number_unsigned() ? it->get<uint64_t>() : fallback;
  };
  const nlohmann::json* images = array("images");
  const nlohmann::json* views = array("bufferViews");
  const nlohmann::json* buffers = array("buffers");
  if (!images) return Status::ok();
  for (size_t i = 0; i < images->size(); ++i) {
    const nlohmann::json& image = (*images)[i];
    if (!image.is_object()) continue;
    auto bv = image.find("bufferView");
    if (bv == image.end() || !bv->is_number_integer()) continue;
    const int64_t viewIndex = bv->get<int64_t>();
    if (!views || viewIndex < 0 || uint64_t(viewIndex) >= views->size()) continue;  // tinygltf checks
    const nlohmann::json& view = (*views)[size_t(viewIndex)];
    if (!view.is_object()) continue;
    auto b = view.find("buffer");
    if (b == view.end() || !b->is_number_integer()) continue;
    const int64_t bufferIndex = b->get<int64_t>();
    if (!buffers || bufferIndex < 0 || uint64_t(bufferIndex) >= buffers->size()) continue;
    const nlohmann::json& buffer = (*buffers)[size_t(bufferIndex)];
    if (!buffer.is_object()) continue;
    const uint64_t bufferLength = unsignedMember(buffer, "byteLength", 0);
    const uint64_t offset = unsignedMember(view, "byteOffset", 0);
    const uint64_t viewLength = unsignedMember(view, "byteLength", 0);
    if (offset > bufferLength || viewLength > bufferLength - offset)
      return Status::error(format("%s: image %zu: bufferView %lld lies outside buffer %lld (needs "
                                  "%llu bytes, has %llu)",
                                  file.c_str(), i, (long long)viewIndex, (long long)bufferIndex,
                                  (unsigned long long)(offset + viewLength),
                                  (unsigned long long)bufferLength));
  }
  return Status::ok();
}

// An object of the file that carries an extension in its `extensions` object.
struct ExtensionCarrier {
  std::string where;  // "textures[2]", "meshes[0].primitives[1]", "the document"
  int texture = -1;   // the index when the carrier is an entry of the top-level textures
};
using ExtensionCarriers = std::map<std::string, std::vector<ExtensionCarrier>>;

// Every object that carries one of `wanted` in its `extensions` object, searched in the raw JSON
// so that no object kind is missed (tinygltf keeps `extensions` on some objects only). Values
// under `extras` are application data, not extensions, and are not searched. The depth is
// bounded by jsonTooDeep() before this runs.
void findExtensionCarriers(const nlohmann::json& value, const std::string& where, int texture,
                           const std::set<std::string>& wanted, ExtensionCarriers& out) {
  if (value.is_array()) {
    for (size_t i = 0; i < value.size(); ++i)
      findExtensionCarriers(value[i], where + "[" + std::to_string(i) + "]",
                            where == "textures" ? int(i) : -1, wanted, out);
    return;
  }
  if (!value.is_object()) return;
  for (auto it = value.begin(); it != value.end(); ++it) {
    if (it.key() == "extras") continue;
    if (it.key() == "extensions" && it->is_object())
      for (auto ext = it->begin(); ext != it->end(); ++ext)
        if (wanted.count(ext.key()))
          out[ext.key()].push_back({where.empty() ? "the document" : where, texture});
    findExtensionCarriers(*it, where.empty() ? it.key() : where + "." + it.key(), -1, wanted,
                          out);
  }
}

// Per node, the members of its extras.afterglow that are empty objects: tinygltf drops empty
// objects from extras, but `"reflectionProbe": {}` asks for every default and `"probeVolume":
// {}` must be refused for its missing size, so they are found in the raw JSON.
using EmptyExtras = std::map<size_t, std::set<std::string>>;
EmptyExtras emptyAfterglowMembers(const nlohmann::json& root) {
  EmptyExtras out;
  if (!root.is_object()) return out;
  auto nodes = root.find("nodes");
  if (nodes == root.end() || !nodes->is_array()) return out;
  for (size_t i = 0; i < nodes->size(); ++i) {
    const nlohmann::json& node = (*nodes)[i];
    if (!node.is_object()) continue;
    auto extras = node.find("extras");
    if (extras == node.end() || !extras->is_object()) continue;
    auto ag = extras->find("afterglow");
    if (ag == extras->end() || !ag->is_object()) continue;
    for (auto it = ag->begin(); it != ag->end(); ++it)
      if (it->is_object() && it->empty()) out[i].insert(it.key());
  }
  return out;
}

// The carriers of every extension the file requires that afterglow does not support.
ExtensionCarriers unsupportedRequiredExtensions(const nlohmann::json& root) {
  ExtensionCarriers carriers;
  if (!root.is_object()) return carriers;
  auto required = root.find("extensionsRequired");
  if (required == root.end() || !required->is_array()) return carriers;
  std::set<std::string> wanted;
  for (const nlohmann::json& ext : *required)
    if (ext.is_string() && !supportedExtensions().count(ext.get<std::string>()))
      wanted.insert(ext.get<std::string>());
  if (!wanted.empty()) findExtensionCarriers(root, "", -1, wanted, carriers);
  return carriers;
}

// tinygltf hands us image bytes it decoded from data: URIs; we keep them and decode later with
// OpenImageIO. For bufferView images tinygltf passes a pointer it never bounds-checked, so we
// ignore it and read the bufferView ourselves.
bool keepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                    const unsigned char* bytes, int size, void*) {
  if (image->bufferView >= 0) return true;
  if (bytes != nullptr && size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

// Reads external buffers only from regular files (never devices or pipes) of sane size.
bool readRegularFile(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                     void*) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    if (err) *err += "not a regular file";
    return false;
  }
  const uintmax_t size = fs::file_size(path, ec);
  if (ec || size > kMaxInputBytes) {
    if (err) *err += "unreadable or too large";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  out->resize(size_t(size));
  if (size > 0 && !in.read(reinterpret_cast<char*>(out->data()), std::streamsize(size))) {
    if (err) *err += "read failed";
    return false;
  }
  return true;
}

// Extras values, with the type checks tinygltf::Value leaves to us.
const tinygltf::Value* member(const tinygltf::Value& v, const char* key) {
  if (!v.IsObject() || !v.Has(key)) return nullptr;
  return &v.Get(key);
}

struct NodeSettings {
  bool isStatic = true;
  float lightmapScale = 1.0f;
  bool castShadows = true;
};

struct TextureKey {
  int image;
  bool srgb;
  bool operator<(const TextureKey& o) const {
    return image != o.image ? image < o.image : srgb < o.srgb;
  }
};

struct PendingTexture {
  int image = -1;
  bool srgb = false;
  bool decode = false;
  std::string user;  // "material 'X' baseColorTexture", for warnings
};

class Importer {
 public:
  Importer(const tinygltf::Model& model, const std::string& file, const std::string& baseDir,
           const LoadOptions& options, const ExtensionCarriers& carriers,
           const EmptyExtras& emptyExtras, Scene& scene)
      : model_(model),
        file_(file),
        baseDir_(baseDir),
        options_(options),
        carriers_(carriers),
        emptyExtras_(emptyExtras),
        scene_(scene) {}

  Status run() {
    Status s = checkExtensions();
    if (!s) return s;
    s = importMaterials();
    if (!s) return s;
    s = importNodes();
    if (!s) return s;
    s = importMeshes();
    if (!s) return s;
    decodeTextures();
    return Status::ok();
  }

 private:
  Status fail(const std::string& what) const { return Status::error(file_ + ": " + what); }

  void warn(const std::string& what) {
    if (scene_.warnings.size() < kMaxWarnings) {
      scene_.warnings.push_back(file_ + ": " + what);
    } else if (scene_.warnings.size() == kMaxWarnings) {
      scene_.warnings.push_back(file_ + ": further warnings suppressed");
    }
  }

  // ---- extensions ---------------------------------------------------------------------------

  // A required extension afterglow does not support refuses the file only when something in it
  // really uses it. Whether it is used is judged by the objects that carry it in their
  // `extensions` (the extensionsUsed list is not trusted either way):
  //  - carried by nothing: a stale entry in extensionsRequired; warn and load.
  //  - carried only by textures that also have a plain `source` (an alternative image, e.g. a DDS
  //    beside a PNG): warn and load the plain source, the fallback the extension stands beside.
  //  - carried by anything else, or by a texture whose only image is in the extension: refuse,
  //    naming the texture or the object.
  Status checkExtensions() {
    std::set<std::string> reported;
    for (const std::string& ext : model_.extensionsRequired) {
      if (supportedExtensions().count(ext) || !reported.insert(ext).second) continue;
      auto found = carriers_.find(ext);
      if (found == carriers_.end() || found->second.empty()) {
        warn("requires extension " + ext + ", which afterglow does not support, but nothing in "
             "the file uses it; loaded without it");
        continue;
      }
      std::vector<int> fallbacks;
      for (const ExtensionCarrier& c : found->second) {
        const bool texture = c.texture >= 0 && size_t(c.texture) < model_.textures.size();
        if (texture && model_.textures[size_t(c.texture)].source >= 0) {
          fallbacks.push_back(c.texture);
          continue;
        }
        if (texture) {
          const std::string& name = model_.textures[size_t(c.texture)].name;
          return fail(format("texture %d%s has its only image in extension %s, which afterglow "
                             "does not support (the file requires it)",
                             c.texture, name.empty() ? "" : (" '" + name + "'").c_str(),
                             ext.c_str()));
        }
        return fail("requires extension " + ext + ", which afterglow does not support (used by " +
                    c.where + ")");
      }
      std::string list;
      for (size_t i = 0; i < fallbacks.size() && i < 8; ++i)
        list += (i ? ", " : "") + std::to_string(fallbacks[i]);
      if (fallbacks.size() > 8) list += ", ...";
      warn(format("requires extension %s, which afterglow does not support; it only gives "
                  "alternative images, so texture%s %s use%s %s plain source",
                  ext.c_str(), fallbacks.size() > 1 ? "s" : "", list.c_str(),
                  fallbacks.size() > 1 ? "" : "s", fallbacks.size() > 1 ? "their" : "its"));
    }
    for (const std::string& ext : model_.extensionsUsed)
      if (!supportedExtensions().count(ext) && !reported.count(ext))
        warn("extension " + ext + " is used but ignored");
    return Status::ok();
  }

  // ---- accessors ----------------------------------------------------------------------------

  static int componentCount(int type) {
    switch (type) {
      case TINYGLTF_TYPE_SCALAR: return 1;
      case TINYGLTF_TYPE_VEC2: return 2;
      case TINYGLTF_TYPE_VEC3: return 3;
      case TINYGLTF_TYPE_VEC4: return 4;
      default: return 0;  // matrices are never read by the importer
    }
  }

  static int componentSize(int componentType) {
    switch (componentType) {
      case TINYGLTF_COMPONENT_TYPE_BYTE:
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
      case TINYGLTF_COMPONENT_TYPE_SHORT:
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
      default: return 0;
    }
  }

  static double readComponent(const unsigned char* p, int componentType, bool normalized) {
    switch (componentType) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t v;
        std::memcpy(&v, p, 1);
        return normalized ? std::max(double(v) / 127.0, -1.0) : double(v);
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? double(*p) / 255.0 : double(*p);
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? std::max(double(v) / 32767.0, -1.0) : double(v);
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? double(v) / 65535.0 : double(v);
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        std::memcpy(&v, p, 4);
        return normalized ? double(v) / 4294967295.0 : double(v);
      }
      default: {
        float v;
        std::memcpy(&v, p, 4);
        return double(v);
      }
    }
  }

  // The bytes of a bufferView, after checking that it lies inside its buffer.
  Status bufferViewBytes(int index, const std::string& what, const unsigned char*& data,
                         size_t& length) const {
    if (index < 0 || size_t(index) >= model_.bufferViews.size())
      return fail(format("%s: bufferView %d does not exist (%zu bufferViews)", what.c_str(), index,
                         model_.bufferViews.size()));
    const tinygltf::BufferView& view = model_.bufferViews[size_t(index)];
    if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size())
      return fail(format("%s: bufferView %d refers to buffer %d, which does not exist (%zu buffers)",
                         what.c_str(), index, view.buffer, model_.buffers.size()));
    const std::vector<unsigned char>& buffer = model_.buffers[size_t(view.buffer)].data;
    if (view.byteOffset > buffer.size() || view.byteLength > buffer.size() - view.byteOffset)
      return fail(format("%s: bufferView %d reads past the end of buffer %d (needs %llu bytes, has "
                         "%zu)",
                         what.c_str(), index, view.buffer,
                         (unsigned long long)view.byteOffset + (unsigned long long)view.byteLength,
                         buffer.size()));
    data = buffer.data() + view.byteOffset;
    length = view.byteLength;
    return Status::ok();
  }

  // Checks that `count` elements of elementSize bytes, `stride` apart, from byteOffset fit in a
  // bufferView of `length` bytes.
  Status checkRange(const std::string& what, int viewIndex, size_t byteOffset, size_t count,
                    size_t stride, size_t elementSize, size_t length) const {
    if (count == 0) return Status::ok();
    // count ≤ 2^28 and stride ≤ 252 keep this product far from overflowing.
    const unsigned long long needed =
        (unsigned long long)byteOffset + (unsigned long long)stride * (count - 1) + elementSize;
    if (byteOffset > length || needed > length) {
      const tinygltf::BufferView& view = model_.bufferViews[size_t(viewIndex)];
      return fail(format("%s reads past the end of bufferView %d of buffer %d (needs %llu bytes, "
                         "has %zu)",
                         what.c_str(), viewIndex, view.buffer,
                         byteOffset > length ? (unsigned long long)byteOffset : needed, length));
    }
    return Status::ok();
  }

  // Reads an accessor as count × components doubles, applying normalisation and sparse values.
  // `what` names the use, e.g. "mesh 'Floor' primitive 0: POSITION accessor 3".
  Status readAccessor(int index, const std::string& what, std::vector<double>& out,
                      int& components, size_t& count) const {
    if (index < 0 || size_t(index) >= model_.accessors.size())
      return fail(format("%s does not exist (%zu accessors)", what.c_str(), model_.accessors.size()));
    const tinygltf::Accessor& acc = model_.accessors[size_t(index)];
    components = componentCount(acc.type);
    const int compSize = componentSize(acc.componentType);
    if (components == 0) return fail(what + " has an unsupported type (expected SCALAR or VECn)");
    if (compSize == 0)
      return fail(format("%s has an unsupported componentType %d", what.c_str(), acc.componentType));
    count = acc.count;
    if (count > kMaxAccessorElements)
      return fail(format("%s has an absurd count %zu", what.c_str(), count));
    const size_t elementSize = size_t(components) * size_t(compSize);

    if (acc.bufferView >= 0) {
      const unsigned char* data = nullptr;
      size_t length = 0;
      Status s = bufferViewBytes(acc.bufferView, what, data, length);
      if (!s) return s;
      const size_t viewStride = model_.bufferViews[size_t(acc.bufferView)].byteStride;
      const size_t stride = viewStride ? viewStride : elementSize;
      if (stride < elementSize)
        return fail(format("%s: byteStride %zu of bufferView %d is smaller than an element (%zu "
                           "bytes)",
                           what.c_str(), stride, acc.bufferView, elementSize));
      s = checkRange(what, acc.bufferView, acc.byteOffset, count, stride, elementSize, length);
      if (!s) return s;
      out.resize(count * size_t(components));
      for (size_t i = 0; i < count; ++i) {
        const unsigned char* element = data + acc.byteOffset + i * stride;
        for (int c = 0; c < components; ++c)
          out[i * size_t(components) + size_t(c)] =
              readComponent(element + size_t(c) * size_t(compSize), acc.componentType, acc.normalized);
      }
    } else {
      if (count > kMaxElementsWithoutBufferView)
        return fail(format("%s has no bufferView and an absurd count %zu", what.c_str(), count));
      out.assign(count * size_t(components), 0.0);
    }

    if (acc.sparse.isSparse) {
      const size_t sparseCount = acc.sparse.count < 0 ? size_t(-1) : size_t(acc.sparse.count);
      if (sparseCount == 0 || sparseCount > count)
        return fail(format("%s: sparse count %d is outside [1, %zu]", what.c_str(), acc.sparse.count,
                           count));
      const int indexType = acc.sparse.indices.componentType;
      const int indexSize = componentSize(indexType);
      if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
          indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        return fail(format("%s: sparse indices have componentType %d (expected an unsigned integer)",
                           what.c_str(), indexType));
      if (acc.sparse.indices.byteOffset < 0 || acc.sparse.values.byteOffset < 0)
        return fail(what + ": sparse byteOffset is negative");
      const unsigned char* indexData = nullptr;
      size_t indexLength = 0;
      const std::string indicesWhat = what + " sparse indices";
      Status s = bufferViewBytes(acc.sparse.indices.bufferView, indicesWhat, indexData, indexLength);
      if (!s) return s;
      s = checkRange(indicesWhat, acc.sparse.indices.bufferView,
                     size_t(acc.sparse.indices.byteOffset), sparseCount, size_t(indexSize),
                     size_t(indexSize), indexLength);
      if (!s) return s;
      const unsigned char* valueData = nullptr;
      size_t valueLength = 0;
      const std::string valuesWhat = what + " sparse values";
      s = bufferViewBytes(acc.sparse.values.bufferView, valuesWhat, valueData, valueLength);
      if (!s) return s;
      s = checkRange(valuesWhat, acc.sparse.values.bufferView, size_t(acc.sparse.values.byteOffset),
                     sparseCount, elementSize, elementSize, valueLength);
      if (!s) return s;
      for (size_t k = 0; k < sparseCount; ++k) {
        const double target = readComponent(
            indexData + size_t(acc.sparse.indices.byteOffset) + k * size_t(indexSize), indexType, false);
        if (target >= double(count))
          return fail(format("%s: sparse index %.0f is out of range (count %zu)", what.c_str(),
                             target, count));
        const unsigned char* element =
            valueData + size_t(acc.sparse.values.byteOffset) + k * elementSize;
        for (int c = 0; c < components; ++c)
          out[size_t(target) * size_t(components) + size_t(c)] =
              readComponent(element + size_t(c) * size_t(compSize), acc.componentType, acc.normalized);
      }
    }
    return Status::ok();
  }

  Status readVectors(int index, const std::string& what, int wanted, std::vector<double>& out,
                     size_t& count) const {
    int components = 0;
    Status s = readAccessor(index, what, out, components, count);
    if (!s) return s;
    if (components != wanted)
      return fail(format("%s has %d components per element (expected %d)", what.c_str(), components,
                         wanted));
    return Status::ok();
  }

  // ---- meshes -------------------------------------------------------------------------------

  Status importPrimitive(size_t meshIndex, size_t primIndex, Primitive& out, bool& keep) {
    const tinygltf::Mesh& mesh = model_.meshes[meshIndex];
    const tinygltf::Primitive& prim = mesh.primitives[primIndex];
    const std::string where =
        label("mesh", meshIndex, mesh.name) + format(" primitive %zu", primIndex);
    keep = false;

    const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
    if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        mode != TINYGLTF_MODE_TRIANGLE_FAN) {
      const bool known = mode >= TINYGLTF_MODE_POINTS && mode <= TINYGLTF_MODE_LINE_STRIP;
      warn(where + (known ? ": points and lines are skipped" : format(": unknown mode %d skipped", mode)));
      return Status::ok();
    }
    if (prim.material >= 0 && size_t(prim.material) >= model_.materials.size())
      return fail(format("%s: material %d does not exist (%zu materials)", where.c_str(),
                         prim.material, model_.materials.size()));
    if (prim.material < -1)
      return fail(format("%s: material %d does not exist", where.c_str(), prim.material));
    out.material = prim.material;
    if (!prim.targets.empty()) warn(where + ": morph targets are ignored (base shape used)");

    auto attribute = [&](const char* name) -> int {
      auto it = prim.attributes.find(name);
      return it == prim.attributes.end() ? -2 : it->second;
    };
    const int positionAccessor = attribute("POSITION");
    if (positionAccessor == -2) {
      warn(where + ": no POSITION attribute, skipped");
      return Status::ok();
    }

    std::vector<double> values;
    size_t vertexCount = 0;
    std::string what = where + format(": POSITION accessor %d", positionAccessor);
    Status s = readVectors(positionAccessor, what, 3, values, vertexCount);
    if (!s) return s;
    out.positions.resize(vertexCount);
    for (size_t i = 0; i < vertexCount; ++i) {
      for (int c = 0; c < 3; ++c) {
        const double v = values[i * 3 + size_t(c)];
        if (!std::isfinite(v) || std::abs(v) > double(std::numeric_limits<float>::max()))
          return fail(format("%s holds a NaN or infinite value at vertex %zu", what.c_str(), i));
        out.positions[i][c] = float(v);
      }
    }

    auto readAttribute = [&](const char* name, int components, auto& dest) -> Status {
      const int accessor = attribute(name);
      if (accessor == -2) return Status::ok();
      const std::string attrWhat = where + format(": %s accessor %d", name, accessor);
      size_t count = 0;
      Status st = readVectors(accessor, attrWhat, components, values, count);
      if (!st) return st;
      if (count != vertexCount)
        return fail(format("%s has %zu elements but POSITION has %zu", attrWhat.c_str(), count,
                           vertexCount));
      dest.resize(count);
      size_t fixedUp = 0;
      for (size_t i = 0; i < count; ++i)
        for (int c = 0; c < components; ++c) {
          double v = values[i * size_t(components) + size_t(c)];
          if (!std::isfinite(v) || std::abs(v) > 1e30) {
            v = 0.0;
            ++fixedUp;
          }
          dest[i][c] = float(v);
        }
      if (fixedUp) warn(format("%s: %zu NaN or infinite values replaced by 0", attrWhat.c_str(), fixedUp));
      return Status::ok();
    };
    s = readAttribute("NORMAL", 3, out.normals);
    if (!s) return s;
    s = readAttribute("TEXCOORD_0", 2, out.uv0);
    if (!s) return s;
    s = readAttribute("TEXCOORD_1", 2, out.uv1);
    if (!s) return s;
    if (options_.loadIndirectUvs) {
      s = readAttribute("TEXCOORD_2", 2, out.indirectUv);
      if (!s) return s;
    }

    // Indices (or the implicit 0..n-1), then strips and fans become lists.
    std::vector<uint32_t> order;
    if (prim.indices >= 0) {
      what = where + format(": indices accessor %d", prim.indices);
      if (size_t(prim.indices) >= model_.accessors.size())
        return fail(format("%s does not exist (%zu accessors)", what.c_str(), model_.accessors.size()));
      const int type = model_.accessors[size_t(prim.indices)].componentType;
      if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
          type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        return fail(format("%s has componentType %d (expected an unsigned integer)", what.c_str(), type));
      size_t count = 0;
      s = readVectors(prim.indices, what, 1, values, count);
      if (!s) return s;
      order.resize(count);
      for (size_t i = 0; i < count; ++i) {
        const double v = values[i];
        if (v >= double(vertexCount))
          return fail(format("%s: index %.0f at position %zu is >= the vertex count %zu",
                             what.c_str(), v, i, vertexCount));
        order[i] = uint32_t(v);
      }
    } else {
      if (vertexCount > std::numeric_limits<uint32_t>::max())
        return fail(where + ": too many vertices");
      order.resize(vertexCount);
      for (size_t i = 0; i < vertexCount; ++i) order[i] = uint32_t(i);
    }

    std::vector<uint32_t>& tri = out.indices;
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      if (order.size() % 3 != 0)
        warn(format("%s: %zu indices is not a multiple of 3; the last %zu are ignored", where.c_str(),
                    order.size(), order.size() % 3));
      tri.assign(order.begin(), order.begin() + std::ptrdiff_t(order.size() / 3 * 3));
    } else if (order.size() >= 3) {
      tri.reserve((order.size() - 2) * 3);
      for (size_t i = 0; i + 2 < order.size(); ++i) {
        if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
          // Every other strip triangle swaps two vertices to keep a consistent winding.
          const bool odd = i % 2 == 1;
          tri.insert(tri.end(), {order[i], order[odd ? i + 2 : i + 1], order[odd ? i + 1 : i + 2]});
        } else {
          tri.insert(tri.end(), {order[0], order[i + 1], order[i + 2]});
        }
      }
    }

    if (out.normals.empty()) {
      generateFlatNormals(out);
      warn(where + ": no NORMAL attribute, flat normals generated");
    } else {
      size_t fixedUp = 0;
      for (glm::vec3& n : out.normals) {
        const float len = glm::length(n);
        if (len > 1e-20f && std::isfinite(len)) {
          n /= len;
        } else {
          n = glm::vec3(0.0f, 0.0f, 1.0f);
          ++fixedUp;
        }
      }
      if (fixedUp) warn(format("%s: %zu zero-length normals replaced by +Z", where.c_str(), fixedUp));
    }
    keep = true;
    return Status::ok();
  }

  // Flat normals need one vertex per triangle corner, so the primitive is unwelded.
  static void generateFlatNormals(Primitive& p) {
    Primitive flat;
    flat.material = p.material;
    const size_t corners = p.indices.size();
    flat.positions.resize(corners);
    flat.normals.resize(corners);
    if (!p.uv0.empty()) flat.uv0.resize(corners);
    if (!p.uv1.empty()) flat.uv1.resize(corners);
    flat.indices.resize(corners);
    for (size_t t = 0; t + 2 < corners; t += 3) {
      const glm::vec3 a = p.positions[p.indices[t]], b = p.positions[p.indices[t + 1]],
                      c = p.positions[p.indices[t + 2]];
      glm::vec3 n = glm::cross(b - a, c - a);
      const float len = glm::length(n);
      n = (len > 0.0f && std::isfinite(len)) ? n / len : glm::vec3(0.0f, 0.0f, 1.0f);
      for (size_t k = 0; k < 3; ++k) {
        const uint32_t src = p.indices[t + k];
        flat.positions[t + k] = p.positions[src];
        flat.normals[t + k] = n;
        if (!p.uv0.empty()) flat.uv0[t + k] = p.uv0[src];
        if (!p.uv1.empty()) flat.uv1[t + k] = p.uv1[src];
        flat.indices[t + k] = uint32_t(t + k);
      }
    }
    p = std::move(flat);
  }

  Status importMeshes() {
    // Meshes are imported in glTF order; instances were recorded with glTF mesh indices.
    std::map<int, int> remap;
    for (const auto& entry : usedMeshes_) {
      const size_t meshIndex = size_t(entry);
      const tinygltf::Mesh& src = model_.meshes[meshIndex];
      Mesh mesh;
      mesh.name = src.name.empty() ? format("mesh%zu", meshIndex) : src.name;
      for (size_t p = 0; p < src.primitives.size(); ++p) {
        Primitive prim;
        bool keep = false;
        Status s = importPrimitive(meshIndex, p, prim, keep);
        if (!s) return s;
        if (keep) mesh.primitives.push_back(std::move(prim));
      }
      remap[entry] = int(scene_.meshes.size());
      scene_.meshes.push_back(std::move(mesh));
    }
    for (Instance& inst : scene_.instances) inst.mesh = remap.at(inst.mesh);
    return Status::ok();
  }

  // ---- materials and textures ---------------------------------------------------------------

  static bool finiteAll(const std::vector<double>& v) {
    for (double x : v)
      if (!std::isfinite(x)) return false;
    return true;
  }

  Status textureRef(int textureIndex, double texCoord, const tinygltf::ExtensionMap& extensions,
                        const std::string& where, bool srgb, bool decode, TextureRef& ref) {
    if (textureIndex < 0) return Status::ok();
    if (size_t(textureIndex) >= model_.textures.size())
      return fail(format("%s: texture %d does not exist (%zu textures)", where.c_str(), textureIndex,
                         model_.textures.size()));
    const tinygltf::Texture& tex = model_.textures[size_t(textureIndex)];
    int image = tex.source;
    if (image < 0) {
      // Textures whose only source is in an extension (EXT_texture_webp, KHR_texture_basisu...).
      for (const auto& ext : tex.extensions) {
        const tinygltf::Value* source = member(ext.second, "source");
        if (source && source->IsInt()) image = source->GetNumberAsInt();
      }
    }
    if (image >= 0 && size_t(image) >= model_.images.size())
      return fail(format("%s: texture %d uses image %d, which does not exist (%zu images)",
                         where.c_str(), textureIndex, image, model_.images.size()));

    ref.texCoord = texCoord >= 0 && texCoord < 1e6 ? int(texCoord) : 0;
    auto ext = extensions.find("KHR_texture_transform");
    if (ext != extensions.end() && ext->second.IsObject()) {
      const tinygltf::Value& t = ext->second;
      ref.hasTransform = true;
      auto vec2 = [&](const char* key, glm::vec2& dest) {
        const tinygltf::Value* v = member(t, key);
        if (!v) return;
        if (v->ArrayLen() == 2 && v->Get(0).IsNumber() && v->Get(1).IsNumber() &&
            std::isfinite(v->Get(0).GetNumberAsDouble()) && std::isfinite(v->Get(1).GetNumberAsDouble())) {
          dest = glm::vec2(narrow(v->Get(0).GetNumberAsDouble()), narrow(v->Get(1).GetNumberAsDouble()));
        } else {
          warn(where + ": KHR_texture_transform " + key + " is not two numbers, ignored");
        }
      };
      vec2("offset", ref.offset);
      vec2("scale", ref.scale);
      if (const tinygltf::Value* r = member(t, "rotation")) {
        if (r->IsNumber() && std::isfinite(r->GetNumberAsDouble()))
          ref.rotation = narrow(r->GetNumberAsDouble());
        else
          warn(where + ": KHR_texture_transform rotation is not a number, ignored");
      }
      if (const tinygltf::Value* tc = member(t, "texCoord")) {
        if (tc->IsInt() && tc->GetNumberAsInt() >= 0)
          ref.texCoord = tc->GetNumberAsInt();
        else
          warn(where + ": KHR_texture_transform texCoord is not a non-negative integer, ignored");
      }
    }
    if (ref.texCoord > 1)
      warn(format("%s: uses TEXCOORD_%d, which afterglow does not import", where.c_str(), ref.texCoord));

    if (image < 0) {
      warn(format("%s: texture %d has no image afterglow can read; the factor is used", where.c_str(),
                  textureIndex));
    }
    const TextureKey key{image, srgb};
    auto found = textureSlots_.find(key);
    if (found == textureSlots_.end()) {
      Texture t;
      if (image >= 0) {
        const tinygltf::Image& img = model_.images[size_t(image)];
        t.uri = img.uri;
        t.name = !img.name.empty() ? img.name : !tex.name.empty() ? tex.name : img.uri;
      } else {
        t.name = tex.name;
      }
      if (t.name.empty()) t.name = format("image%d", image);
      found = textureSlots_.emplace(key, int(scene_.textures.size())).first;
      scene_.textures.push_back(std::move(t));
      pending_.push_back(PendingTexture{image, srgb, false, where});
    }
    PendingTexture& pending = pending_[size_t(found->second)];
    if (decode && !pending.decode) {
      pending.decode = true;
      pending.user = where;
    }
    ref.texture = found->second;
    return Status::ok();
  }

  Status importMaterials() {
    for (size_t i = 0; i < model_.materials.size(); ++i) {
      const tinygltf::Material& src = model_.materials[i];
      const std::string where = label("material", i, src.name);
      Material m;
      m.name = src.name.empty() ? format("material%zu", i) : src.name;
      const tinygltf::PbrMetallicRoughness& pbr = src.pbrMetallicRoughness;
      if (pbr.baseColorFactor.size() == 4 && finiteAll(pbr.baseColorFactor))
        m.baseColorFactor = glm::vec4(narrow(pbr.baseColorFactor[0]), narrow(pbr.baseColorFactor[1]),
                                      narrow(pbr.baseColorFactor[2]), narrow(pbr.baseColorFactor[3]));
      else if (!pbr.baseColorFactor.empty())
        warn(where + ": baseColorFactor is not 4 finite numbers, white used");
      auto factor = [&](double v, float& dest, const char* name) {
        if (std::isfinite(v)) dest = narrow(v);
        else warn(where + ": " + name + " is not finite, default used");
      };
      factor(pbr.metallicFactor, m.metallicFactor, "metallicFactor");
      factor(pbr.roughnessFactor, m.roughnessFactor, "roughnessFactor");
      if (src.emissiveFactor.size() == 3 && finiteAll(src.emissiveFactor))
        m.emissiveFactor = glm::vec3(narrow(src.emissiveFactor[0]), narrow(src.emissiveFactor[1]),
                                     narrow(src.emissiveFactor[2]));
      else if (!src.emissiveFactor.empty())
        warn(where + ": emissiveFactor is not 3 finite numbers, black used");
      auto strength = src.extensions.find("KHR_materials_emissive_strength");
      if (strength != src.extensions.end()) {
        const tinygltf::Value* v = member(strength->second, "emissiveStrength");
        if (v && v->IsNumber() && std::isfinite(v->GetNumberAsDouble()) && v->GetNumberAsDouble() >= 0)
          m.emissiveStrength = narrow(v->GetNumberAsDouble());
        else if (v)
          warn(where + ": emissiveStrength is not a non-negative number, 1 used");
      }
      m.doubleSided = src.doubleSided;
      if (const tinygltf::Value* ag = member(src.extras, "afterglow")) {
        if (!ag->IsObject()) {
          warn(where + ": extras.afterglow is not an object, ignored");
        } else {
          if (const tinygltf::Value* v = member(*ag, "singleSidedEmission")) {
            if (v->IsBool()) m.singleSidedEmission = v->Get<bool>();
            else warn(where + ": extras.afterglow.singleSidedEmission is not a boolean, ignored");
          }
          // Earlier versions emitted from the front only unless this was set; both sides are
          // now the default, as glTF says.
          if (member(*ag, "doubleSidedEmission"))
            warn(where + ": extras.afterglow.doubleSidedEmission is obsolete and ignored: a "
                         "doubleSided material emits from both sides unless "
                         "extras.afterglow.singleSidedEmission is true");
        }
      }
      if (src.alphaMode == "MASK") m.alphaMode = AlphaMode::Mask;
      else if (src.alphaMode == "BLEND") m.alphaMode = AlphaMode::Blend;
      else if (src.alphaMode != "OPAQUE" && !src.alphaMode.empty())
        warn(where + ": unknown alphaMode '" + src.alphaMode + "', OPAQUE used");
      factor(src.alphaCutoff, m.alphaCutoff, "alphaCutoff");

      Status s = textureRef(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord,
                            pbr.baseColorTexture.extensions, where + " baseColorTexture", true, true,
                            m.baseColorTexture);
      if (!s) return s;
      s = textureRef(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                     pbr.metallicRoughnessTexture.extensions, where + " metallicRoughnessTexture",
                     false, true, m.metallicRoughnessTexture);
      if (!s) return s;
      s = textureRef(src.emissiveTexture.index, src.emissiveTexture.texCoord, src.emissiveTexture.extensions,
                     where + " emissiveTexture", true, true, m.emissiveTexture);
      if (!s) return s;
      s = textureRef(src.normalTexture.index, src.normalTexture.texCoord,
                         src.normalTexture.extensions, where + " normalTexture", false,
                         options_.loadNormalTextures, m.normalTexture);
      if (!s) return s;
      if (m.normalTexture.valid()) m.normalScale = float(src.normalTexture.scale);
      s = textureRef(src.occlusionTexture.index, src.occlusionTexture.texCoord,
                         src.occlusionTexture.extensions, where + " occlusionTexture", false, false,
                         m.occlusionTexture);
      if (!s) return s;
      s = importSpecular(src, where, m);
      if (!s) return s;
      s = importTransmission(src, where, m);
      if (!s) return s;
      scene_.materials.push_back(std::move(m));
    }
    return Status::ok();
  }

  // A textureInfo inside an extension (a JSON object rather than tinygltf's TextureInfo).
  Status extensionTexture(const tinygltf::Value& ext, const char* key, const std::string& where,
                          bool srgb, TextureRef& ref) {
    const tinygltf::Value* info = member(ext, key);
    if (!info) return Status::ok();
    const tinygltf::Value* index = member(*info, "index");
    if (!index || !index->IsInt() || index->GetNumberAsInt() < 0) {
      warn(where + " " + key + " has no valid index, ignored");
      return Status::ok();
    }
    double texCoord = 0.0;
    if (const tinygltf::Value* tc = member(*info, "texCoord")) {
      if (tc->IsInt() && tc->GetNumberAsInt() >= 0) texCoord = tc->GetNumberAsInt();
      else warn(where + " " + key + ": texCoord is not a non-negative integer, 0 used");
    }
    tinygltf::ExtensionMap extensions;
    if (const tinygltf::Value* e = member(*info, "extensions"))
      for (const std::string& name : e->Keys()) extensions[name] = e->Get(name);
    return textureRef(index->GetNumberAsInt(), texCoord, extensions, where + " " + key, srgb, true,
                      ref);
  }

  // KHR_materials_ior and KHR_materials_specular: the dielectric reflectance the bounce albedo
  // takes out of the diffuse part. Out-of-range values are clamped into range with a warning.
  Status importSpecular(const tinygltf::Material& src, const std::string& where, Material& m) {
    auto ior = src.extensions.find("KHR_materials_ior");
    if (ior != src.extensions.end()) {
      if (const tinygltf::Value* v = member(ior->second, "ior")) {
        const double x = v->IsNumber() ? v->GetNumberAsDouble() : std::nan("");
        if (std::isfinite(x) && (x >= 1.0 || x == 0.0)) {
          m.ior = narrow(x);
        } else if (std::isfinite(x) && x > 0.0) {
          m.ior = 1.0f;
          warn(format("%s: KHR_materials_ior ior %g is below 1 (and not 0), 1 used", where.c_str(), x));
        } else {
          warn(where + ": KHR_materials_ior ior is not a number >= 1 or 0, 1.5 used");
        }
      }
    }
    const tinygltf::Value* found = extensionObject(src, "KHR_materials_specular", where);
    if (!found) return Status::ok();
    const tinygltf::Value& ext = *found;
    unitFactor(ext, "KHR_materials_specular", "specularFactor", where, "1", m.specularFactor);
    if (const tinygltf::Value* v = member(ext, "specularColorFactor")) {
      bool numbers = v->IsArray() && v->ArrayLen() == 3;
      for (int k = 0; numbers && k < 3; ++k)
        numbers = v->Get(k).IsNumber() && std::isfinite(v->Get(k).GetNumberAsDouble());
      if (!numbers) {
        warn(where + ": KHR_materials_specular specularColorFactor is not 3 finite numbers, "
                     "white used");
      } else {
        bool negative = false;
        for (int k = 0; k < 3; ++k) {
          const double x = v->Get(k).GetNumberAsDouble();
          negative = negative || x < 0.0;
          m.specularColorFactor[k] = narrow(std::max(x, 0.0));
        }
        if (negative)
          warn(where + ": KHR_materials_specular specularColorFactor has negative components, "
                       "0 used for them");
      }
    }
    Status s = extensionTexture(ext, "specularTexture", where + " KHR_materials_specular", false,
                                m.specularTexture);
    if (!s) return s;
    return extensionTexture(ext, "specularColorTexture", where + " KHR_materials_specular", true,
                            m.specularColorTexture);
  }

  // KHR_materials_transmission: the light that passes through the surface (material_eval.h,
  // transmission). A factor outside [0, 1] is clamped into it with a warning.
  Status importTransmission(const tinygltf::Material& src, const std::string& where,
                            Material& m) {
    const tinygltf::Value* ext = extensionObject(src, "KHR_materials_transmission", where);
    if (!ext) return Status::ok();
    unitFactor(*ext, "KHR_materials_transmission", "transmissionFactor", where, "0",
               m.transmissionFactor);
    return extensionTexture(*ext, "transmissionTexture", where + " KHR_materials_transmission",
                            false, m.transmissionTexture);
  }

  // The material's extension `name` when it is an object; null (with a warning when present but
  // not an object) otherwise.
  const tinygltf::Value* extensionObject(const tinygltf::Material& src, const char* name,
                                         const std::string& where) {
    auto found = src.extensions.find(name);
    if (found == src.extensions.end()) return nullptr;
    if (!found->second.IsObject()) {
      warn(where + ": " + name + " is not an object, ignored");
      return nullptr;
    }
    return &found->second;
  }

  // A factor in [0, 1] of extension `name`: kept as it was (`fallback` names that value) when
  // not a number, clamped into [0, 1] with a warning when outside.
  void unitFactor(const tinygltf::Value& ext, const char* name, const char* key,
                  const std::string& where, const char* fallback, float& out) {
    const tinygltf::Value* v = member(ext, key);
    if (!v) return;
    const double x = v->IsNumber() ? v->GetNumberAsDouble() : std::nan("");
    if (!std::isfinite(x)) {
      warn(where + ": " + name + " " + key + " is not a number, " + fallback + " used");
      return;
    }
    out = narrow(std::clamp(x, 0.0, 1.0));
    if (x < 0.0 || x > 1.0)
      warn(format("%s: %s %s %g is outside [0, 1], %g used", where.c_str(), name, key, x,
                  double(out)));
  }

  void decodeTextures() {
    if (!options_.loadTextures) return;
    std::vector<Status> results(pending_.size());
    parallelFor(pending_.size(), [&](size_t i) {
      const PendingTexture& p = pending_[i];
      if (!p.decode || p.image < 0) return;
      Texture& tex = scene_.textures[i];
      const bool srgb = p.srgb;
      const tinygltf::Image& img = model_.images[size_t(p.image)];
      if (img.bufferView >= 0) {
        const unsigned char* data = nullptr;
        size_t length = 0;
        Status s = bufferViewBytes(img.bufferView, format("image %d", p.image), data, length);
        results[i] = s ? detail::decodeImageMemory(data, length, img.mimeType, srgb, tex) : s;
      } else if (!img.image.empty()) {
        results[i] = detail::decodeImageMemory(img.image.data(), img.image.size(), img.mimeType, srgb, tex);
      } else if (!img.uri.empty()) {
        const fs::path path = fs::path(baseDir_) / percentDecode(img.uri);
        results[i] = detail::decodeImageFile(path.string(), srgb, tex);
      } else {
        results[i] = Status::error("the image has no data");
      }
    });
    for (size_t i = 0; i < pending_.size(); ++i) {
      if (results[i]) continue;
      const PendingTexture& p = pending_[i];
      const tinygltf::Image& img = model_.images[size_t(p.image)];
      const std::string source = img.uri.empty() ? std::string("embedded") : "'" + img.uri + "'";
      warn(format("%s: %s (%s) could not be decoded (%s); the factor is used", p.user.c_str(),
                  label("image", size_t(p.image), img.name).c_str(), source.c_str(),
                  firstLine(results[i].message()).c_str()));
    }
  }

  // ---- nodes --------------------------------------------------------------------------------

  glm::dmat4 localTransform(const tinygltf::Node& node, const std::string& where) {
    if (!node.matrix.empty()) {
      if (node.matrix.size() == 16 && finiteAll(node.matrix)) {
        glm::dmat4 m;
        for (int c = 0; c < 4; ++c)
          for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[size_t(c * 4 + r)];
        return m;
      }
      warn(where + ": matrix is not 16 finite numbers, identity used");
      return glm::dmat4(1.0);
    }
    glm::dmat4 m(1.0);
    if (!node.translation.empty()) {
      if (node.translation.size() == 3 && finiteAll(node.translation))
        m = glm::translate(m, glm::dvec3(node.translation[0], node.translation[1], node.translation[2]));
      else
        warn(where + ": translation is not 3 finite numbers, ignored");
    }
    if (!node.rotation.empty()) {
      const auto& r = node.rotation;
      const bool ok = r.size() == 4 && finiteAll(r);
      const glm::dquat q = ok ? glm::dquat(r[3], r[0], r[1], r[2]) : glm::dquat(1, 0, 0, 0);
      const double len = glm::length(q);
      if (ok && len > 1e-12)
        m = m * glm::mat4_cast(q / len);
      else
        warn(where + ": rotation is not a non-zero quaternion, ignored");
    }
    if (!node.scale.empty()) {
      if (node.scale.size() == 3 && finiteAll(node.scale))
        m = glm::scale(m, glm::dvec3(node.scale[0], node.scale[1], node.scale[2]));
      else
        warn(where + ": scale is not 3 finite numbers, ignored");
    }
    return m;
  }

  NodeSettings readNodeSettings(const tinygltf::Node& node, const std::string& where,
                                NodeSettings settings) {
    const tinygltf::Value* ag = member(node.extras, "afterglow");
    if (!ag) return settings;
    if (!ag->IsObject()) {
      warn(where + ": extras.afterglow is not an object, ignored");
      return settings;
    }
    if (const tinygltf::Value* v = member(*ag, "static")) {
      if (v->IsBool()) settings.isStatic = v->Get<bool>();
      else warn(where + ": extras.afterglow.static is not a boolean, ignored");
    }
    if (const tinygltf::Value* v = member(*ag, "castShadows")) {
      if (v->IsBool()) settings.castShadows = v->Get<bool>();
      else warn(where + ": extras.afterglow.castShadows is not a boolean, ignored");
    }
    if (const tinygltf::Value* v = member(*ag, "lightmapScale")) {
      const double s = v->IsNumber() ? v->GetNumberAsDouble() : -1.0;
      if (s > 0.0 && s < 1e6) settings.lightmapScale = float(s);
      else warn(where + ": extras.afterglow.lightmapScale is not a positive number, ignored");
    }
    return settings;
  }

  // Node `index`'s extras.afterglow.<key>, or an empty object where the file had `{}` (which
  // tinygltf dropped), or null.
  const tinygltf::Value* afterglowMember(const tinygltf::Node& node, size_t index,
                                         const char* key) const {
    const tinygltf::Value* ag = member(node.extras, "afterglow");
    if (const tinygltf::Value* v = ag ? member(*ag, key) : nullptr) return v;
    static const tinygltf::Value kEmpty{tinygltf::Value::Object()};
    auto found = emptyExtras_.find(index);
    return found != emptyExtras_.end() && found->second.count(key) ? &kEmpty : nullptr;
  }

  // extras.afterglow.probeVolume = {"size": [x, y, z], "spacing": s}: a box of light probes
  // centred on the node (not inherited). A box of no volume or a malformed one is an error: a
  // probe placement that silently ignored it would fill the whole level instead.
  Status readProbeVolume(const tinygltf::Node& node, size_t index, const std::string& where,
                         const glm::dmat4& world) {
    const tinygltf::Value* pv = afterglowMember(node, index, "probeVolume");
    if (!pv) return Status::ok();
    if (!pv->IsObject()) return fail(where + ": extras.afterglow.probeVolume is not an object");
    ProbeVolume volume;
    volume.name = node.name.empty() ? format("node%zu", index) : node.name;
    volume.node = int(index);
    volume.transform = narrowMat(world);
    const tinygltf::Value* size = member(*pv, "size");
    bool sizeOk = size && size->IsArray() && size->ArrayLen() == 3;
    for (int i = 0; sizeOk && i < 3; ++i) {
      const tinygltf::Value& c = size->Get(i);
      const double v = c.IsNumber() ? c.GetNumberAsDouble() : -1.0;
      sizeOk = std::isfinite(v) && v > 0.0 && v < 1e9;
      if (sizeOk) volume.size[i] = float(v);
    }
    if (!sizeOk)
      return fail(where + ": extras.afterglow.probeVolume.size must be 3 positive finite numbers");
    if (const tinygltf::Value* sp = member(*pv, "spacing")) {
      const double v = sp->IsNumber() ? sp->GetNumberAsDouble() : -1.0;
      if (!(std::isfinite(v) && v > 0.0 && v < 1e9))
        return fail(where + ": extras.afterglow.probeVolume.spacing must be a positive number");
      volume.spacing = float(v);
    }
    if (!std::isfinite(glm::determinant(world)) || std::abs(glm::determinant(world)) < 1e-30)
      return fail(where + ": extras.afterglow.probeVolume is on a node whose transform has no "
                          "volume");
    scene_.probeVolumes.push_back(std::move(volume));
    return Status::ok();
  }

  // extras.afterglow.reflectionProbe = {"size": [x, y, z], "projectionSize": [x, y, z],
  // "blendDistance": d, "importance": i, "boxProjection": b, "resolution": n}, every member
  // optional (not inherited). A malformed
  // member is an error naming it: a probe that silently took a default would light the wrong
  // region or blur the wrong way, and the level designer would not know why.
  Status readReflectionProbe(const tinygltf::Node& node, size_t index, const std::string& where,
                             const glm::dmat4& world) {
    const tinygltf::Value* rp = afterglowMember(node, index, "reflectionProbe");
    if (!rp) return Status::ok();
    const std::string key = where + ": extras.afterglow.reflectionProbe";
    if (!rp->IsObject()) return fail(key + " is not an object");
    ReflectionProbe probe;
    probe.name = node.name.empty() ? format("node%zu", index) : node.name;
    probe.node = int(index);
    probe.transform = narrowMat(world);
    for (const auto& [name, out] : {std::pair<const char*, glm::vec3*>{"size", &probe.size},
                                    {"projectionSize", &probe.projectionSize}}) {
      const tinygltf::Value* size = member(*rp, name);
      if (!size) continue;
      bool ok = size->IsArray() && size->ArrayLen() == 3;
      for (int i = 0; ok && i < 3; ++i) {
        const tinygltf::Value& c = size->Get(i);
        const double v = c.IsNumber() ? c.GetNumberAsDouble() : -1.0;
        ok = std::isfinite(v) && v > 0.0 && v < 1e9;
        if (ok) (*out)[i] = float(v);
      }
      if (!ok) return fail(key + "." + name + " must be 3 positive finite numbers");
    }
    if (const tinygltf::Value* v = member(*rp, "blendDistance")) {
      const double d = v->IsNumber() ? v->GetNumberAsDouble() : -1.0;
      if (!(std::isfinite(d) && d >= 0.0 && d < 1e9))
        return fail(key + ".blendDistance must be a number of metres >= 0");
      probe.blendDistance = float(d);
    }
    if (const tinygltf::Value* v = member(*rp, "importance")) {
      const double i = v->IsNumber() ? v->GetNumberAsDouble() : 0.5;
      if (!(std::isfinite(i) && i == std::floor(i) && std::abs(i) <= 1e6))
        return fail(key + ".importance must be a whole number");
      probe.importance = int(i);
    }
    if (const tinygltf::Value* v = member(*rp, "boxProjection")) {
      if (!v->IsBool()) return fail(key + ".boxProjection must be true or false");
      probe.boxProjection = v->Get<bool>();
    }
    if (const tinygltf::Value* v = member(*rp, "resolution")) {
      const double n = v->IsNumber() ? v->GetNumberAsDouble() : 0.0;
      const bool powerOfTwo = n >= 8.0 && n <= 2048.0 && n == std::floor(n) &&
                              (int(n) & (int(n) - 1)) == 0;
      if (!powerOfTwo) return fail(key + ".resolution must be a power of two from 8 to 2048");
      probe.resolution = int(n);
    }
    if (!std::isfinite(glm::determinant(world)) || std::abs(glm::determinant(world)) < 1e-30)
      return fail(key + " is on a node whose transform has no volume");
    scene_.reflectionProbes.push_back(std::move(probe));
    return Status::ok();
  }

  // extras.afterglow.lightmap: where `afterglow uv` put this node's lightmap (not inherited).
  LightmapLocation readLightmap(const tinygltf::Node& node, const std::string& where,
                                const char* key = "lightmap") {
    LightmapLocation location;
    const tinygltf::Value* ag = member(node.extras, "afterglow");
    const tinygltf::Value* lm = ag ? member(*ag, key) : nullptr;
    if (!lm) return location;
    const tinygltf::Value* atlas = member(*lm, "atlas");
    const tinygltf::Value* width = member(*lm, "width");
    const tinygltf::Value* height = member(*lm, "height");
    if (atlas && width && height && atlas->IsInt() && width->IsInt() && height->IsInt() &&
        atlas->GetNumberAsInt() >= 0 && width->GetNumberAsInt() > 0 && height->GetNumberAsInt() > 0) {
      location.atlas = atlas->GetNumberAsInt();
      location.width = width->GetNumberAsInt();
      location.height = height->GetNumberAsInt();
    } else {
      warn(where + ": extras.afterglow." + key + " needs integers atlas >= 0, width > 0, "
                   "height > 0; ignored");
    }
    return location;
  }

  void placeLight(int lightIndex, const glm::dmat4& world, size_t nodeIndex,
                  const std::string& where) {
    if (lightIndex < 0 || size_t(lightIndex) >= model_.lights.size()) {
      warn(format("%s: light %d does not exist, ignored", where.c_str(), lightIndex));
      return;
    }
    const tinygltf::Light& src = model_.lights[size_t(lightIndex)];
    const std::string lightWhere = label("light", size_t(lightIndex), src.name);
    Light light;
    light.name = src.name.empty() ? format("light%d", lightIndex) : src.name;
    if (src.type == "directional") light.type = LightType::Directional;
    else if (src.type == "point") light.type = LightType::Point;
    else if (src.type == "spot") light.type = LightType::Spot;
    else {
      warn(lightWhere + ": unknown type '" + src.type + "', skipped");
      return;
    }
    if (src.color.size() == 3 && finiteAll(src.color))
      light.color = glm::max(glm::vec3(narrow(src.color[0]), narrow(src.color[1]), narrow(src.color[2])),
                             glm::vec3(0.0f));
    else if (!src.color.empty())
      warn(lightWhere + ": color is not 3 finite numbers, white used");
    if (std::isfinite(src.intensity) && src.intensity >= 0) light.intensity = narrow(src.intensity);
    else warn(lightWhere + ": intensity is not a non-negative number, 1 used");
    if (std::isfinite(src.range) && src.range >= 0) light.range = narrow(src.range);
    else warn(lightWhere + ": range is not a non-negative number, infinite used");
    if (light.type == LightType::Spot) {
      const double halfPi = 1.5707963267948966;
      double outer = src.spot.outerConeAngle, inner = src.spot.innerConeAngle;
      if (!(outer > 0.0 && outer <= halfPi)) {
        warn(lightWhere + ": outerConeAngle is outside (0, pi/2], pi/4 used");
        outer = halfPi / 2;
      }
      if (!(inner >= 0.0 && inner < outer)) {
        warn(lightWhere + ": innerConeAngle is outside [0, outerConeAngle), 0 used");
        inner = 0.0;
      }
      light.outerConeAngle = float(outer);
      light.innerConeAngle = float(inner);
    }
    light.position = narrow3(world * glm::dvec4(0, 0, 0, 1));
    const glm::dvec3 dir = glm::dvec3(world * glm::dvec4(0, 0, -1, 0));
    const double len = glm::length(dir);
    if (len > 1e-12 && std::isfinite(len)) light.direction = narrow3(dir / len);
    else warn(where + ": degenerate transform, the light points down -Z");
    light.node = int(nodeIndex);

    if (const tinygltf::Value* ag = member(src.extras, "afterglow")) {
      auto number = [&](const char* key, float& dest) {
        const tinygltf::Value* v = member(*ag, key);
        if (!v) return;
        if (v->IsNumber() && std::isfinite(v->GetNumberAsDouble()) && v->GetNumberAsDouble() >= 0)
          dest = narrow(v->GetNumberAsDouble());
        else
          warn(lightWhere + ": extras.afterglow." + key + " is not a non-negative number, ignored");
      };
      if (!ag->IsObject()) warn(lightWhere + ": extras.afterglow is not an object, ignored");
      number("radius", light.radius);
      number("angularDiameter", light.angularDiameter);
      number("bounceIntensity", light.bounceIntensity);
      if (const tinygltf::Value* mode = member(*ag, "mode")) {
        const std::string m = mode->IsString() ? mode->Get<std::string>() : std::string();
        if (m == "baked") light.mode = LightMode::Baked;
        else if (m == "mixed") light.mode = LightMode::Mixed;
        else if (m == "realtime") light.mode = LightMode::Realtime;
        else warn(lightWhere + ": extras.afterglow.mode is not \"baked\", \"mixed\" or "
                  "\"realtime\", baked used");
      }
    }
    scene_.lights.push_back(std::move(light));
  }

  void placeCamera(int cameraIndex, const glm::dmat4& world, size_t nodeIndex,
                   const std::string& where) {
    if (cameraIndex < 0 || size_t(cameraIndex) >= model_.cameras.size()) {
      warn(format("%s: camera %d does not exist, ignored", where.c_str(), cameraIndex));
      return;
    }
    const tinygltf::Camera& src = model_.cameras[size_t(cameraIndex)];
    Camera cam;
    cam.name = src.name.empty() ? format("camera%d", cameraIndex) : src.name;
    auto positive = [](double v, float fallback) {
      return std::isfinite(v) && v > 0 ? narrow(v) : fallback;
    };
    if (src.type == "orthographic") {
      cam.perspective = false;
      cam.xmag = positive(src.orthographic.xmag, cam.xmag);
      cam.ymag = positive(src.orthographic.ymag, cam.ymag);
      cam.znear = std::isfinite(src.orthographic.znear) && src.orthographic.znear >= 0
                      ? narrow(src.orthographic.znear) : cam.znear;
      cam.zfar = positive(src.orthographic.zfar, cam.zfar);
    } else {
      cam.yfov = positive(src.perspective.yfov, cam.yfov);
      cam.aspectRatio = positive(src.perspective.aspectRatio, 0.0f);
      cam.znear = positive(src.perspective.znear, cam.znear);
      cam.zfar = positive(src.perspective.zfar, 0.0f);
    }
    cam.transform = narrowMat(world);
    cam.node = int(nodeIndex);
    scene_.cameras.push_back(std::move(cam));
  }

  Status importNodes() {
    const size_t nodeCount = model_.nodes.size();
    std::vector<int> roots;
    if (model_.defaultScene >= 0 && size_t(model_.defaultScene) < model_.scenes.size()) {
      roots = model_.scenes[size_t(model_.defaultScene)].nodes;
    } else {
      if (model_.defaultScene >= 0)
        warn(format("default scene %d does not exist, scene 0 used", model_.defaultScene));
      if (!model_.scenes.empty()) {
        roots = model_.scenes[0].nodes;
      } else {
        std::vector<bool> isChild(nodeCount, false);
        for (const tinygltf::Node& n : model_.nodes)
          for (int c : n.children)
            if (c >= 0 && size_t(c) < nodeCount) isChild[size_t(c)] = true;
        for (size_t i = 0; i < nodeCount; ++i)
          if (!isChild[i]) roots.push_back(int(i));
      }
    }

    struct Item {
      int node;
      glm::dmat4 parent;
      NodeSettings settings;
    };
    std::vector<Item> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it)
      stack.push_back(Item{*it, glm::dmat4(1.0), NodeSettings{}});
    std::vector<bool> visited(nodeCount, false);
    std::set<int> meshes;
    size_t mirrored = 0;
    while (!stack.empty()) {
      Item item = std::move(stack.back());
      stack.pop_back();
      if (item.node < 0 || size_t(item.node) >= nodeCount) {
        warn(format("node %d does not exist (%zu nodes), ignored", item.node, nodeCount));
        continue;
      }
      const size_t index = size_t(item.node);
      const tinygltf::Node& node = model_.nodes[index];
      const std::string where = label("node", index, node.name);
      // A node belongs to one parent; a second visit means a cycle or a shared child.
      if (visited[index]) {
        warn(where + " is reached twice (a cycle or two parents); visited once");
        continue;
      }
      visited[index] = true;
      const glm::dmat4 world = item.parent * localTransform(node, where);
      const NodeSettings settings = readNodeSettings(node, where, item.settings);

      if (node.mesh >= 0 || node.mesh < -1) {
        if (size_t(node.mesh) >= model_.meshes.size())
          return fail(format("%s: mesh %d does not exist (%zu meshes)", where.c_str(), node.mesh,
                             model_.meshes.size()));
        if (node.skin >= 0) warn(where + ": skinning is ignored (bind pose used)");
        Instance inst;
        inst.name = node.name.empty() ? format("node%zu", index) : node.name;
        inst.node = int(index);
        inst.mesh = node.mesh;  // glTF index until importMeshes remaps it
        inst.transform = narrowMat(world);
        inst.isStatic = settings.isStatic;
        inst.lightmapScale = settings.lightmapScale;
        inst.castShadows = settings.castShadows;
        inst.lightmap = readLightmap(node, where);
        if (options_.loadIndirectUvs)
          inst.indirectLightmap = readLightmap(node, where, "indirectLightmap");
        if (glm::determinant(world) < 0.0) ++mirrored;
        scene_.instances.push_back(std::move(inst));
        meshes.insert(node.mesh);
      }
      if (Status pv = readProbeVolume(node, index, where, world); !pv) return pv;
      if (Status rp = readReflectionProbe(node, index, where, world); !rp) return rp;
      if (node.camera >= 0) placeCamera(node.camera, world, index, where);
      auto lights = node.extensions.find("KHR_lights_punctual");
      if (lights != node.extensions.end()) {
        const tinygltf::Value* light = member(lights->second, "light");
        if (light && light->IsInt())
          placeLight(light->GetNumberAsInt(), world, index, where);
        else
          warn(where + ": KHR_lights_punctual has no integer 'light', ignored");
      }
      for (auto c = node.children.rbegin(); c != node.children.rend(); ++c)
        stack.push_back(Item{*c, world, settings});
    }
    if (mirrored)
      warn(format("%zu instances have a mirroring transform (negative determinant); their winding "
                  "is flipped in world space",
                  mirrored));
    usedMeshes_.assign(meshes.begin(), meshes.end());
    return Status::ok();
  }

  const tinygltf::Model& model_;
  std::string file_;
  std::string baseDir_;
  LoadOptions options_;
  const ExtensionCarriers& carriers_;  // unsupported required extensions' carriers
  const EmptyExtras& emptyExtras_;  // per node, its extras.afterglow members that are {}
  Scene& scene_;
  std::vector<int> usedMeshes_;
  std::map<TextureKey, int> textureSlots_;
  std::vector<PendingTexture> pending_;  // parallel to scene_.textures
};

}  // namespace

Result<Scene> loadGltfFromMemory(const std::string& bytes, const std::string& nameForMessages,
                                 const std::string& baseDir, const LoadOptions& options) {
  const std::string& file = nameForMessages;
  if (bytes.size() > kMaxInputBytes) return Result<Scene>::error(file + ": file is too large");
  const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
  size_t jsonOffset = 0, jsonLength = bytes.size();
  if (binary) {
    Status s = checkGlbContainer(bytes, file, jsonOffset, jsonLength);
    if (!s) return s;
  }
  if (jsonTooDeep(bytes.data() + jsonOffset, jsonLength))
    return Result<Scene>::error(format("%s: malformed JSON: nested deeper than %d levels",
                                       file.c_str(), kMaxJsonDepth));

  ExtensionCarriers carriers;
  EmptyExtras emptyExtras;
  {
    // Parsed here for the checks tinygltf does not make, and freed before tinygltf parses it.
    const nlohmann::json root = nlohmann::json::parse(
        bytes.data() + jsonOffset, bytes.data() + jsonOffset + jsonLength, nullptr, false);
    Status images = checkImageBufferViews(root, file);
    if (!images) return images;
    carriers = unsupportedRequiredExtensions(root);
    emptyExtras = emptyAfterglowMembers(root);
  }

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keepImageBytes, nullptr);
  tinygltf::FsCallbacks callbacks{&tinygltf::FileExists, &tinygltf::ExpandFilePath,
                                  &readRegularFile, &tinygltf::WriteWholeFile, nullptr};
  loader.SetFsCallbacks(callbacks);
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  try {
    if (binary)
      ok = loader.LoadBinaryFromMemory(&model, &err, &warn,
                                       reinterpret_cast<const unsigned char*>(bytes.data()),
                                       unsigned(bytes.size()), baseDir);
    else
      ok = loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), unsigned(bytes.size()),
                                      baseDir);
  } catch (const std::exception& e) {
    err = e.what();
    ok = false;
  }
  if (!ok) {
    const std::string line = firstLine(err);
    const bool json = line.find("json.exception") != std::string::npos ||
                      line.find("JSON") != std::string::npos;
    return Result<Scene>::error(file + (json ? ": malformed JSON: " : ": invalid glTF: ") + line);
  }

  Scene scene;
  scene.sourcePath = nameForMessages;
  Importer importer(model, file, baseDir, options, carriers, emptyExtras, scene);
  Status s;
  try {
    s = importer.run();
  } catch (const std::bad_alloc&) {
    s = Status::error(file + ": out of memory");
  }
  if (!s) return s;
  return scene;
}

Result<Scene> loadGltf(const std::string& path, const LoadOptions& options) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return Result<Scene>::error(path + ": no such file");
  const uintmax_t size = fs::file_size(path, ec);
  if (ec || size > kMaxInputBytes) return Result<Scene>::error(path + ": unreadable or too large");
  std::string bytes(size_t(size), '\0');
  std::ifstream in(path, std::ios::binary);
  if (size > 0 && !in.read(bytes.data(), std::streamsize(size)))
    return Result<Scene>::error(path + ": read failed");
  const std::string baseDir = fs::path(path).parent_path().string();
  Result<Scene> result = loadGltfFromMemory(bytes, path, baseDir.empty() ? "." : baseDir, options);
  if (result) result->sourcePath = path;
  return result;
}

}  // namespace afterglow::scenes
