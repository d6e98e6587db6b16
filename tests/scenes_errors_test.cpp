// glTF import errors: every malformed input fails with one line that names the file and the
// object at fault; recoverable problems load with a warning instead.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "afterglow/scenes/gltf.h"
#include "test_util.h"

namespace afterglow::scenes {
namespace {

using nlohmann::json;

std::string base64(const std::string& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  uint32_t acc = 0;
  int bits = 0;
  for (unsigned char c : in) {
    acc = acc << 8 | c;
    bits += 8;
    while (bits >= 6) out.push_back(k[(acc >> (bits -= 6)) & 63]);
  }
  if (bits > 0) out.push_back(k[(acc << (6 - bits)) & 63]);
  while (out.size() % 4) out.push_back('=');
  return out;
}

std::string floats(std::initializer_list<float> v) {
  return std::string(reinterpret_cast<const char*>(v.begin()), v.size() * sizeof(float));
}

// A valid one-triangle level: mesh 'Floor' (POSITION = accessor 0, indices = accessor 1),
// material 'Stone', all in one data: URI buffer. Tests break one thing at a time.
struct Level {
  std::string bin = floats({0, 0, 0, 1, 0, 0, 0, 1, 0}) + std::string("\0\0\1\0\2\0\0\0", 8);
  json j = json::parse(R"({
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [{"name": "FloorNode", "mesh": 0}],
    "meshes": [{"name": "Floor", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
                                                  "material": 0}]}],
    "materials": [{"name": "Stone"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                  {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
  })");

  std::string text() const {
    json out = j;
    if (!out.contains("buffers"))
      out["buffers"] = json::array({{{"byteLength", bin.size()},
                                     {"uri", "data:application/octet-stream;base64," + base64(bin)}}});
    return out.dump();
  }
};

Result<Scene> load(const std::string& bytes) {
  return loadGltfFromMemory(bytes, "level.gltf", "/nonexistent-dir");
}

// The load fails and the message is one line naming the file and every given fragment.
void expectError(const Result<Scene>& r, std::initializer_list<const char*> fragments) {
  ASSERT_FALSE(r) << "loaded although it should fail";
  const std::string& m = r.message();
  EXPECT_EQ(m.rfind("level.gltf: ", 0), 0u) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  for (const char* f : fragments) EXPECT_NE(m.find(f), std::string::npos) << "'" << f << "' not in: " << m;
}

TEST(GltfErrors, TheBaseLevelLoads) {
  auto r = load(Level().text());
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(r->instancedTriangleCount(), 1u);
}

TEST(GltfErrors, MalformedJson) {
  expectError(load("{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [}"), {"malformed JSON"});
  expectError(load("not json at all"), {"malformed JSON"});
  expectError(load(std::string(100000, '[')), {"malformed JSON"});
  expectError(load(""), {});
}

TEST(GltfErrors, MissingAndShortBuffers) {
  Level missing;
  missing.j["buffers"] = json::array({{{"byteLength", 44}, {"uri", "gone.bin"}}});
  expectError(load(missing.text()), {"gone.bin"});

  Level shortUri;  // the data: URI holds fewer bytes than byteLength
  shortUri.j["buffers"] = json::array(
      {{{"byteLength", 4400}, {"uri", "data:application/octet-stream;base64," + base64(shortUri.bin)}}});
  expectError(load(shortUri.text()), {"invalid glTF"});

  Level shortView;  // bufferView 0 runs past the buffer
  shortView.j["bufferViews"][0]["byteLength"] = 4800;
  expectError(load(shortView.text()), {"mesh 'Floor' primitive 0", "POSITION accessor 0",
                                       "bufferView 0", "buffer 0", "needs 4800 bytes, has 44"});

  Level noView;
  noView.j["accessors"][0]["bufferView"] = 7;
  expectError(load(noView.text()), {"mesh 'Floor' primitive 0", "bufferView 7 does not exist"});

  Level noBuffer;
  noBuffer.j["bufferViews"][0]["buffer"] = 3;
  expectError(load(noBuffer.text()), {"mesh 'Floor' primitive 0", "buffer 3"});
}

TEST(GltfErrors, AccessorReadsPastItsBufferView) {
  Level level;
  level.j["accessors"][0]["count"] = 400;
  expectError(load(level.text()), {"mesh 'Floor' primitive 0: POSITION accessor 0 reads past the end "
                                   "of bufferView 0 of buffer 0 (needs 4800 bytes, has 36)"});
  Level offset;
  offset.j["accessors"][1]["byteOffset"] = 2;
  expectError(load(offset.text()), {"mesh 'Floor' primitive 0: indices accessor 1", "needs 8 bytes, has 6"});
  Level stride;
  stride.j["bufferViews"][0]["byteStride"] = 8;
  expectError(load(stride.text()), {"POSITION accessor 0", "byteStride 8"});
}

TEST(GltfErrors, AccessorsAndIndicesOutOfRange) {
  Level badAccessor;
  badAccessor.j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 9;
  expectError(load(badAccessor.text()), {"mesh 'Floor' primitive 0: POSITION accessor 9 does not exist"});

  Level badIndex;
  badIndex.bin[36 + 2] = 7;  // second index = 7, only 3 vertices
  expectError(load(badIndex.text()), {"mesh 'Floor' primitive 0: indices accessor 1",
                                      "index 7 at position 1 is >= the vertex count 3"});

  Level floatIndices;
  floatIndices.j["accessors"][1]["componentType"] = 5126;
  expectError(load(floatIndices.text()), {"indices accessor 1", "componentType 5126"});

  Level wrongType;
  wrongType.j["accessors"][0]["type"] = "VEC2";
  expectError(load(wrongType.text()), {"POSITION accessor 0 has 2 components"});

  Level hugeCount;  // count × stride overflows 32 bits; must not wrap around
  hugeCount.j["accessors"][0]["count"] = 4294967296ull * 4 + 3;
  expectError(load(hugeCount.text()), {"POSITION accessor 0"});

  Level noViewHuge;  // zeros without a bufferView are capped, not allocated
  noViewHuge.j["accessors"][0].erase("bufferView");
  noViewHuge.j["accessors"][0]["count"] = 1000000000;
  expectError(load(noViewHuge.text()), {"POSITION accessor 0", "absurd count"});

  Level badSparse;
  badSparse.j["accessors"][0]["sparse"] = {
      {"count", 1},
      {"indices", {{"bufferView", 1}, {"componentType", 5123}, {"byteOffset", 2}}},
      {"values", {{"bufferView", 0}}}};
  badSparse.bin[36 + 2] = 9;  // sparse index 9 of 3
  expectError(load(badSparse.text()), {"POSITION accessor 0", "sparse index 9"});

  Level badMaterial;
  badMaterial.j["meshes"][0]["primitives"][0]["material"] = 4;
  expectError(load(badMaterial.text()), {"mesh 'Floor' primitive 0: material 4 does not exist"});

  Level badMesh;
  badMesh.j["nodes"][0]["mesh"] = 2;
  expectError(load(badMesh.text()), {"node 'FloorNode': mesh 2 does not exist"});

  Level badTexture;
  badTexture.j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] = 3;
  expectError(load(badTexture.text()), {"material 'Stone' baseColorTexture: texture 3 does not exist"});

  Level badImage;
  badImage.j["textures"] = json::array({{{"source", 5}}});
  badImage.j["materials"][0]["emissiveTexture"]["index"] = 0;
  expectError(load(badImage.text()), {"material 'Stone' emissiveTexture", "image 5"});
}

TEST(GltfErrors, ImageBufferViewOutsideItsBuffer) {
  Level level;
  level.j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 18446744073709551000ull}, {"byteLength", 4}});
  level.j["images"] = json::array({{{"bufferView", 2}, {"mimeType", "image/png"}}});
  expectError(load(level.text()), {"image 0: bufferView 2 lies outside buffer 0"});
  Level tooLong;
  tooLong.j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 40}, {"byteLength", 8}});
  tooLong.j["images"] = json::array({{{"bufferView", 2}, {"mimeType", "image/png"}}});
  expectError(load(tooLong.text()), {"image 0: bufferView 2", "needs 48 bytes, has 44"});
}

TEST(GltfErrors, NonFinitePositions) {
  Level level;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&level.bin[4 * 4], &nan, 4);  // vertex 1, y
  expectError(load(level.text()), {"mesh 'Floor' primitive 0: POSITION accessor 0", "NaN or infinite",
                                   "vertex 1"});
  Level inf;
  const float infinity = std::numeric_limits<float>::infinity();
  std::memcpy(&inf.bin[8 * 4], &infinity, 4);
  expectError(load(inf.text()), {"vertex 2"});
}

TEST(GltfErrors, Extensions) {
  Level required;
  required.j["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  required.j["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  required.j["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"] = {
      {"bufferView", 0}, {"attributes", {{"POSITION", 0}}}};
  expectError(load(required.text()), {"requires extension KHR_draco_mesh_compression",
                                      "meshes[0].primitives[0]"});

  Level supported;
  supported.j["extensionsUsed"] = {"KHR_texture_transform", "KHR_materials_clearcoat"};
  supported.j["extensionsRequired"] = {"KHR_texture_transform", "KHR_mesh_quantization"};
  auto r = load(supported.text());
  ASSERT_TRUE(r) << r.message();
  int extensionWarnings = 0;
  for (const std::string& w : r->warnings) {
    extensionWarnings += w.find("extension") != std::string::npos;
    EXPECT_EQ(w.find("KHR_texture_transform"), std::string::npos) << w;
  }
  EXPECT_EQ(extensionWarnings, 1);
  EXPECT_NE(r->warnings[0].find("level.gltf: extension KHR_materials_clearcoat"), std::string::npos);
}

// The number of warnings that mention every given fragment.
int warningsWith(const Scene& scene, std::initializer_list<const char*> fragments) {
  int n = 0;
  for (const std::string& w : scene.warnings) {
    bool all = true;
    for (const char* f : fragments) all = all && w.find(f) != std::string::npos;
    n += all;
  }
  return n;
}

// A required extension that nothing in the file uses (a real asset lists MSFT_texture_dds in
// extensionsRequired only, and has no texture) loads with a warning naming file and extension;
// so does one listed in extensionsUsed too but carried by no object, and one that appears only
// inside extras (application data, not an extension).
TEST(GltfErrors, UnusedRequiredExtensionsLoadWithAWarning) {
  Level stale;
  stale.j["extensionsRequired"] = {"MSFT_texture_dds"};
  auto r = load(stale.text());
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(warningsWith(*r, {"level.gltf: ", "MSFT_texture_dds", "nothing in the file uses it"}),
            1);
  EXPECT_EQ(r->instancedTriangleCount(), 1u);

  Level listed;
  listed.j["extensionsUsed"] = {"KHR_draco_mesh_compression", "MSFT_texture_dds"};
  listed.j["extensionsRequired"] = {"KHR_draco_mesh_compression", "MSFT_texture_dds"};
  listed.j["materials"][0]["extras"]["extensions"]["MSFT_texture_dds"] = {{"source", 0}};
  r = load(listed.text());
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(warningsWith(*r, {"level.gltf: ", "KHR_draco_mesh_compression", "nothing"}), 1);
  EXPECT_EQ(warningsWith(*r, {"level.gltf: ", "MSFT_texture_dds", "nothing"}), 1);
  // One warning per extension, not a second "used but ignored".
  EXPECT_EQ(warningsWith(*r, {"extension"}), 2) << ::testing::PrintToString(r->warnings);
}

// A texture whose only image is given through an unsupported required extension cannot load:
// refused, naming the file, the texture and the extension. With a plain `source` beside the
// extension's alternative, the plain image is the fallback: loaded with a warning.
TEST(GltfErrors, RequiredTextureExtensionsWithoutAFallbackAreRefused) {
  Level onlyDds;
  onlyDds.j["extensionsUsed"] = {"MSFT_texture_dds"};
  onlyDds.j["extensionsRequired"] = {"MSFT_texture_dds"};
  onlyDds.j["images"] = json::array({{{"uri", "stone.dds"}}});
  onlyDds.j["textures"] = json::array(
      {{{"name", "StoneDds"}, {"extensions", {{"MSFT_texture_dds", {{"source", 0}}}}}}});
  onlyDds.j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  expectError(load(onlyDds.text()), {"texture 0 'StoneDds'", "MSFT_texture_dds"});
  // Not trusting extensionsUsed: the texture needs it even when the list leaves it out.
  onlyDds.j.erase("extensionsUsed");
  expectError(load(onlyDds.text()), {"texture 0 'StoneDds'", "MSFT_texture_dds"});

  Level withPng;
  withPng.j["extensionsUsed"] = {"MSFT_texture_dds"};
  withPng.j["extensionsRequired"] = {"MSFT_texture_dds"};
  withPng.j["images"] = json::array({{{"uri", "stone.png"}}, {{"uri", "stone.dds"}}});
  withPng.j["textures"] = json::array(
      {{{"source", 0}, {"extensions", {{"MSFT_texture_dds", {{"source", 1}}}}}}});
  withPng.j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  scenes::LoadOptions noTextures;
  noTextures.loadTextures = false;
  auto r = loadGltfFromMemory(withPng.text(), "level.gltf", "/nonexistent-dir", noTextures);
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(warningsWith(*r, {"level.gltf: ", "MSFT_texture_dds", "texture 0 uses its plain source"}),
            1);
  ASSERT_EQ(r->textures.size(), 1u);
  EXPECT_EQ(r->textures[0].uri, "stone.png");
}

TEST(GltfErrors, MismatchedAttributeCounts) {
  Level level;
  level.bin += floats({0, 0, 1, 0, 0, 1});
  level.j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 44}, {"byteLength", 24}});
  level.j["accessors"].push_back({{"bufferView", 2}, {"componentType", 5126}, {"count", 2}, {"type", "VEC3"}});
  level.j["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = 2;
  expectError(load(level.text()), {"mesh 'Floor' primitive 0: NORMAL accessor 2 has 2 elements but "
                                   "POSITION has 3"});
}

TEST(GltfErrors, RecoverableProblemsBecomeWarnings) {
  Level empty;  // zero primitives is fine
  empty.j["meshes"][0]["primitives"] = json::array();
  auto r = load(empty.text());
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(r->instances.size(), 1u);
  EXPECT_EQ(r->instancedTriangleCount(), 0u);

  Level cycle;  // node 0 → 1 → 0: visited once, with a warning, no hang
  cycle.j["nodes"][0]["children"] = {1};
  cycle.j["nodes"].push_back({{"name", "Loop"}, {"children", {0}}});
  auto rc = load(cycle.text());
  ASSERT_TRUE(rc) << rc.message();
  EXPECT_EQ(rc->instances.size(), 1u);
  bool warned = false;
  for (const std::string& w : rc->warnings) warned |= w.find("node 'FloorNode' is reached twice") != std::string::npos;
  EXPECT_TRUE(warned);

  Level badExtras;
  badExtras.j["nodes"][0]["extras"] = {{"afterglow", {{"static", "yes"}, {"castShadows", 0}}}};
  auto re = load(badExtras.text());
  ASSERT_TRUE(re) << re.message();
  EXPECT_TRUE(re->instances[0].isStatic);
  EXPECT_TRUE(re->instances[0].castShadows);
  int extrasWarnings = 0;
  for (const std::string& w : re->warnings)
    extrasWarnings += w.find("node 'FloorNode': extras.afterglow.") != std::string::npos;
  EXPECT_EQ(extrasWarnings, 2);
}

TEST(GltfErrors, BrokenGlbContainers) {
  const std::string text = Level().text();
  std::string json = text;
  while (json.size() % 4) json.push_back(' ');
  auto glb = [&](uint32_t declaredLength, uint32_t jsonLength, const std::string& tail) {
    std::string out = "glTF";
    auto u32 = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    u32(2);
    u32(declaredLength);
    u32(jsonLength);
    u32(0x4E4F534A);
    out += json + tail;
    return out;
  };
  const uint32_t total = uint32_t(20 + json.size());
  auto ok = load(glb(total, uint32_t(json.size()), ""));
  ASSERT_TRUE(ok) << ok.message();
  expectError(load(glb(total + 100, uint32_t(json.size()), "")), {"GLB header says"});
  expectError(load(glb(total, uint32_t(json.size()) + 8, "")), {"JSON chunk"});
  // A BIN chunk whose length claims the 8 bytes of its own header (tinygltf misses this).
  std::string bin = std::string("\x10\0\0\0BIN\0", 8) + std::string(8, '\0');
  expectError(load(glb(total + 16, uint32_t(json.size()), bin)), {"BIN chunk"});
  expectError(load(std::string("glTF\2\0\0\0", 8)), {"truncated GLB"});
}

TEST(GltfErrors, MissingFile) {
  auto r = loadGltf(test::tempDir("gltf_errors_missing") + "/nope.gltf");
  ASSERT_FALSE(r);
  EXPECT_NE(r.message().find("nope.gltf"), std::string::npos) << r.message();
}

}  // namespace
}  // namespace afterglow::scenes
