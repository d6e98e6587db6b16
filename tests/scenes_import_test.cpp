// glTF import: small glTFs written by the tests (exact answers) and the shared reference scenes.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <chrono>
#include <ctime>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/material_eval.h"
#include "test_util.h"

namespace afterglow::scenes {
namespace {

using nlohmann::json;

constexpr int kByte = 5120, kUByte = 5121, kShort = 5122, kUShort = 5123, kUInt = 5125,
              kFloat = 5126;

std::string base64(const std::string& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8 | uint8_t(in[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out.push_back(k[(v >> s) & 63]);
  }
  if (i + 1 == in.size()) {
    uint32_t v = uint32_t(uint8_t(in[i])) << 16;
    out += {k[v >> 18 & 63], k[v >> 12 & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8;
    out += {k[v >> 18 & 63], k[v >> 12 & 63], k[v >> 6 & 63], '='};
  }
  return out;
}

// Builds a glTF with one buffer, embedded as a data: URI (gltf()) or as a GLB BIN chunk (glb()).
struct Builder {
  json j = {{"asset", {{"version", "2.0"}}}};
  std::string bin;

  template <class T>
  int data(const std::vector<T>& values, int componentType, const char* type,
           bool normalized = false) {
    while (bin.size() % 4) bin.push_back('\0');
    const size_t offset = bin.size();
    bin.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
    j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset},
                                {"byteLength", values.size() * sizeof(T)}});
    const int components = std::string(type) == "SCALAR" ? 1 : type[3] - '0';
    json acc = {{"bufferView", j["bufferViews"].size() - 1}, {"componentType", componentType},
                {"count", values.size() / size_t(components)}, {"type", type}};
    if (normalized) acc["normalized"] = true;
    j["accessors"].push_back(acc);
    return int(j["accessors"].size() - 1);
  }
  int positions(const std::vector<float>& xyz) { return data(xyz, kFloat, "VEC3"); }
  int mesh(json primitives, const std::string& name = "") {
    json m = {{"primitives", primitives}};
    if (!name.empty()) m["name"] = name;
    j["meshes"].push_back(m);
    return int(j["meshes"].size() - 1);
  }
  int node(json n) {
    j["nodes"].push_back(n);
    return int(j["nodes"].size() - 1);
  }
  void scene(std::vector<int> roots) { j["scenes"] = json::array({{{"nodes", roots}}}); j["scene"] = 0; }

  json withBuffer() const {
    json out = j;
    if (!bin.empty())
      out["buffers"] = json::array({{{"byteLength", bin.size()},
                                     {"uri", "data:application/octet-stream;base64," + base64(bin)}}});
    return out;
  }
  std::string gltf() const { return withBuffer().dump(); }
  std::string glb() const {
    json out = j;
    std::string b = bin;
    while (b.size() % 4) b.push_back('\0');
    if (!b.empty()) out["buffers"] = json::array({{{"byteLength", bin.size()}}});
    std::string text = out.dump();
    while (text.size() % 4) text.push_back(' ');
    std::string glbBytes = "glTF";
    auto u32 = [&](uint32_t v) { glbBytes.append(reinterpret_cast<const char*>(&v), 4); };
    u32(2);
    u32(uint32_t(12 + 8 + text.size() + (b.empty() ? 0 : 8 + b.size())));
    u32(uint32_t(text.size()));
    u32(0x4E4F534A);
    glbBytes += text;
    if (!b.empty()) {
      u32(uint32_t(b.size()));
      u32(0x004E4942);
      glbBytes += b;
    }
    return glbBytes;
  }
};

Result<Scene> load(const std::string& bytes, const LoadOptions& options = {}) {
  return loadGltfFromMemory(bytes, "test.gltf", "/nonexistent-dir", options);
}

void expectVec(glm::vec3 a, glm::vec3 b, float eps = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, eps);
  EXPECT_NEAR(a.y, b.y, eps);
  EXPECT_NEAR(a.z, b.z, eps);
}

glm::vec3 worldPosition(const Scene& s, size_t instance, size_t vertex) {
  const Instance& inst = s.instances[instance];
  return glm::vec3(inst.transform *
                   glm::vec4(s.meshes[size_t(inst.mesh)].primitives[0].positions[vertex], 1.0f));
}

bool hasWarning(const Scene& s, const std::string& a, const std::string& b = "") {
  for (const std::string& w : s.warnings)
    if (w.find(a) != std::string::npos && w.find(b) != std::string::npos) return true;
  return false;
}

const std::vector<float> kTriangle = {0, 0, 0, 1, 0, 0, 0, 1, 0};

TEST(GltfImport, TrsAndMatrixHierarchyGiveExactWorldPositions) {
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}}}));
  // child: matrix translating +1 in x; parent: T(1,2,3) R(90° about Z) S(2).
  b.node({{"name", "child"}, {"mesh", 0},
          {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1}}});
  const double h = std::sqrt(0.5);
  b.node({{"name", "parent"}, {"children", {0}}, {"translation", {1, 2, 3}},
          {"rotation", {0, 0, h, h}}, {"scale", {2, 2, 2}}});
  b.scene({1});
  auto r = load(b.gltf());
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->instances.size(), 1u);
  EXPECT_EQ(r->instances[0].name, "child");
  EXPECT_EQ(r->instances[0].node, 0);
  // (1,0,0) → child (2,0,0) → scale (4,0,0) → rotate (0,4,0) → translate (1,6,3).
  expectVec(worldPosition(*r, 0, 1), {1, 6, 3});
  // (0,1,0) → (1,1,0) → (2,2,0) → (-2,2,0) → (-1,4,3).
  expectVec(worldPosition(*r, 0, 2), {-1, 4, 3});
  Bounds bounds = r->bounds();
  expectVec(bounds.min, {-1, 4, 3});
  expectVec(bounds.max, {1, 6, 3});
}

TEST(GltfImport, TwoNodesOnOneMeshGiveOneMeshTwoInstances) {
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}}}), "Tri");
  b.node({{"mesh", 0}, {"translation", {5, 0, 0}}});
  b.node({{"mesh", 0}, {"translation", {-5, 0, 0}}, {"name", "second"}});
  b.scene({0, 1});
  auto r = load(b.gltf());
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->meshes.size(), 1u);
  EXPECT_EQ(r->meshes[0].name, "Tri");
  ASSERT_EQ(r->instances.size(), 2u);
  EXPECT_EQ(r->instances[0].mesh, 0);
  EXPECT_EQ(r->instances[1].mesh, 0);
  EXPECT_EQ(r->instances[0].name, "node0");
  EXPECT_EQ(r->instancedTriangleCount(), 2u);
  EXPECT_EQ(r->meshTriangleCount(), 1u);
  expectVec(worldPosition(*r, 1, 1), {-4, 0, 0});
}

TEST(GltfImport, EveryIndexComponentTypeAndNonIndexed) {
  const std::vector<float> quad = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::vector<uint32_t> expected = {0, 1, 2, 0, 2, 3};
  for (int type : {kUByte, kUShort, kUInt, 0}) {
    Builder b;
    int pos = b.positions(quad);
    json prim = {{"attributes", {{"POSITION", pos}}}};
    if (type == kUByte) prim["indices"] = b.data(std::vector<uint8_t>{0, 1, 2, 0, 2, 3}, type, "SCALAR");
    if (type == kUShort) prim["indices"] = b.data(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}, type, "SCALAR");
    if (type == kUInt) prim["indices"] = b.data(std::vector<uint32_t>{0, 1, 2, 0, 2, 3}, type, "SCALAR");
    if (type == 0) {
      b.j["accessors"][0]["count"] = 3;  // non-indexed: the first three vertices
    }
    b.mesh(json::array({prim}));
    b.node({{"mesh", 0}});
    b.scene({0});
    auto r = load(b.gltf());
    ASSERT_TRUE(r) << r.message();
    const Primitive& p = r->meshes[0].primitives[0];
    if (type == 0) {
      // Flat normals unweld the vertices but keep the order.
      EXPECT_EQ(p.indices, (std::vector<uint32_t>{0, 1, 2}));
      EXPECT_EQ(p.positions.size(), 3u);
    } else {
      ASSERT_EQ(p.triangleCount(), 2u) << type;
      expectVec(p.positions[p.indices[4]], {1, 1, 0});
      expectVec(p.positions[p.indices[5]], {0, 1, 0});
    }
  }
}

TEST(GltfImport, SparseAccessorOverridesBaseValues) {
  Builder b;
  int pos = b.positions(kTriangle);
  b.data(std::vector<uint16_t>{2, 0}, kUShort, "SCALAR");          // accessor 1 (its view: 1)
  b.data(std::vector<float>{0, 5, 0, 7, 7, 7}, kFloat, "VEC3");    // accessor 2 (its view: 2)
  b.j["accessors"][pos]["sparse"] = {
      {"count", 2},
      {"indices", {{"bufferView", 1}, {"componentType", kUShort}}},
      {"values", {{"bufferView", 2}}}};
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  auto r = load(b.gltf());
  ASSERT_TRUE(r) << r.message();
  const Primitive& p = r->meshes[0].primitives[0];
  expectVec(p.positions[0], {7, 7, 7});
  expectVec(p.positions[1], {1, 0, 0});
  expectVec(p.positions[2], {0, 5, 0});
}

TEST(GltfImport, NormalizedAndQuantizedTexCoords) {
  Builder b;
  int pos = b.positions(kTriangle);
  int n = b.data(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}, kFloat, "VEC3");
  int uv0 = b.data(std::vector<uint8_t>{0, 255, 128, 0, 255, 255}, kUByte, "VEC2", true);
  int uv1 = b.data(std::vector<uint16_t>{65535, 0, 0, 32768, 1, 2}, kUShort, "VEC2", true);
  int uv2 = b.data(std::vector<int16_t>{-32767, 32767, 0, 0, 3, -4}, kShort, "VEC2", false);
  (void)uv2;
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}, {"NORMAL", n}, {"TEXCOORD_0", uv0},
                                       {"TEXCOORD_1", uv1}}}}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  auto r = load(b.gltf());
  ASSERT_TRUE(r) << r.message();
  const Primitive& p = r->meshes[0].primitives[0];
  ASSERT_EQ(p.uv0.size(), 3u);
  EXPECT_FLOAT_EQ(p.uv0[0].y, 1.0f);
  EXPECT_NEAR(p.uv0[1].x, 128.0f / 255.0f, 1e-6f);
  EXPECT_FLOAT_EQ(p.uv1[0].x, 1.0f);
  EXPECT_NEAR(p.uv1[1].y, 32768.0f / 65535.0f, 1e-6f);
  EXPECT_TRUE(r->warnings.empty());

  // Signed, non-normalised components (KHR_mesh_quantization) are read as plain integers, and
  // signed normalised ones clamp at -1.
  Builder q;
  int qpos = q.data(std::vector<int16_t>{-3, 0, 0, 0, 0, 4, 0, 0, 0, 0, 0, 0}, kShort, "VEC3");
  // Vec3 of 2-byte components needs a stride of 8 to stay 4-byte aligned.
  q.j["bufferViews"][0]["byteStride"] = 8;
  q.j["accessors"][qpos]["count"] = 3;
  q.j["bufferViews"][0]["byteLength"] = 24;
  int qn = q.data(std::vector<int8_t>{0, 0, -128, 0, 0, 127, 0, 0, 127, 0, 0, 0}, kByte, "VEC3", true);
  q.j["bufferViews"][1]["byteStride"] = 4;
  q.j["accessors"][qn]["count"] = 3;
  q.mesh(json::array({{{"attributes", {{"POSITION", qpos}, {"NORMAL", qn}}}}}));
  q.node({{"mesh", 0}});
  q.scene({0});
  auto rq = load(q.gltf());
  ASSERT_TRUE(rq) << rq.message();
  const Primitive& qp = rq->meshes[0].primitives[0];
  expectVec(qp.positions[0], {-3, 0, 0});
  expectVec(qp.positions[1], {0, 4, 0});
  expectVec(qp.normals[0], {0, 0, -1});
  expectVec(qp.normals[1], {0, 1, 0});
}

TEST(GltfImport, MissingNormalsBecomeFlatNormalsWithAWarning) {
  Builder b;
  int pos = b.positions({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 1, 0, 0});
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}}}), "Bent");
  b.node({{"mesh", 0}});
  b.scene({0});
  auto r = load(b.gltf());
  ASSERT_TRUE(r) << r.message();
  const Primitive& p = r->meshes[0].primitives[0];
  ASSERT_EQ(p.normals.size(), 6u);
  expectVec(p.normals[0], {0, 0, 1});
  expectVec(p.normals[2], {0, 0, 1});
  // (0,0,0), (0,0,1), (1,0,0): (0,0,1)×(1,0,0) = (0,1,0).
  expectVec(p.normals[3], {0, 1, 0});
  EXPECT_TRUE(hasWarning(*r, "mesh 'Bent' primitive 0", "flat normals"));
}

TEST(GltfImport, StripsAndFansBecomeTriangleLists) {
  for (int mode : {5, 6}) {
    Builder b;
    int pos = b.positions({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 2, 0});
    int n = b.data(std::vector<float>(15, 0.0f), kFloat, "VEC3");
    b.mesh(json::array({{{"attributes", {{"POSITION", pos}, {"NORMAL", n}}}, {"mode", mode}}}));
    b.node({{"mesh", 0}});
    b.scene({0});
    auto r = load(b.gltf());
    ASSERT_TRUE(r) << r.message();
    const Primitive& p = r->meshes[0].primitives[0];
    if (mode == 5)
      EXPECT_EQ(p.indices, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2, 2, 3, 4}));
    else
      EXPECT_EQ(p.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4}));
    EXPECT_TRUE(hasWarning(*r, "zero-length normals"));
  }
  // Lines are skipped with a warning; the mesh stays.
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}, {"mode", 1}}}), "Wire");
  b.node({{"mesh", 0}});
  b.scene({0});
  auto r = load(b.gltf());
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(r->meshes[0].primitives.size(), 0u);
  EXPECT_TRUE(hasWarning(*r, "mesh 'Wire' primitive 0", "lines"));
}

TEST(GltfImport, TextureTransformMath) {
  TextureRef ref;
  EXPECT_EQ(ref.transform({0.3f, 0.7f}), glm::vec2(0.3f, 0.7f));
  ref.hasTransform = true;
  ref.offset = {0.5f, -1.0f};
  ref.scale = {2.0f, 3.0f};
  ref.rotation = 1.5707963267948966f;
  // S: (1,1) → (2,3); R(90°): (c·x + s·y, −s·x + c·y) = (3, −2); T: (3.5, −3).
  glm::vec2 uv = ref.transform({1.0f, 1.0f});
  EXPECT_NEAR(uv.x, 3.5f, 1e-5f);
  EXPECT_NEAR(uv.y, -3.0f, 1e-5f);
}

// Writes a 2×1 RGBA 16-bit PNG: sRGB-encoded 0.5 grey and an alpha of 0.5.
void writeGreyPng(const std::string& path) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(2, 1, 4, OIIO::TypeDesc::UINT16);
  ASSERT_TRUE(out->open(path, spec));
  const uint16_t half = 32768;
  std::vector<uint16_t> px = {half, half, half, half, 65535, 0, 0, 65535};
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT16, px.data()));
  out->close();
}

TEST(GltfImport, TexturesDecodeSrgbPerUseAndHonourTransforms) {
  const std::string dir = test::tempDir("gltf_import_textures");
  writeGreyPng(dir + "/grey tex.png");
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}, {"material", 0}}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  b.j["images"] = json::array({{{"uri", "grey%20tex.png"}}, {{"uri", "missing.png"}, {"name", "Gone"}}});
  b.j["textures"] = json::array({{{"source", 0}}, {{"source", 1}}});
  b.j["materials"] = json::array(
      {{{"name", "Grey"},
        {"pbrMetallicRoughness",
         {{"baseColorTexture",
           {{"index", 0},
            {"extensions",
             {{"KHR_texture_transform", {{"offset", {0.25, 0.5}}, {"scale", {2, 2}}, {"texCoord", 1}}}}}}},
          {"metallicRoughnessTexture", {{"index", 0}}}}},
        {"emissiveTexture", {{"index", 1}}},
        {"emissiveFactor", {1, 0.5, 0}},
        {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4}}}}},
        {"doubleSided", true},
        {"alphaMode", "MASK"},
        {"alphaCutoff", 0.25}}});
  const std::string text = b.gltf();
  auto r = loadGltfFromMemory(text, "tex.gltf", dir);
  ASSERT_TRUE(r) << r.message();
  const Material& m = r->materials[0];
  EXPECT_EQ(r->material(0).name, "Grey");
  EXPECT_EQ(r->material(-1).baseColorFactor, glm::vec4(1.0f));
  EXPECT_TRUE(m.doubleSided);
  EXPECT_EQ(m.alphaMode, AlphaMode::Mask);
  EXPECT_FLOAT_EQ(m.alphaCutoff, 0.25f);
  EXPECT_EQ(m.emission(), glm::vec3(4.0f, 2.0f, 0.0f));
  EXPECT_TRUE(m.emissive());
  // Transform with a texCoord override.
  ASSERT_TRUE(m.baseColorTexture.valid());
  EXPECT_TRUE(m.baseColorTexture.hasTransform);
  EXPECT_EQ(m.baseColorTexture.texCoord, 1);
  glm::vec2 uv = m.baseColorTexture.transform({0.5f, 0.5f});
  EXPECT_NEAR(uv.x, 1.25f, 1e-6f);
  EXPECT_NEAR(uv.y, 1.5f, 1e-6f);
  // The same image decoded as sRGB for base colour and as linear for metallic-roughness.
  ASSERT_NE(m.baseColorTexture.texture, m.metallicRoughnessTexture.texture);
  const Texture& colour = r->textures[size_t(m.baseColorTexture.texture)];
  const Texture& data = r->textures[size_t(m.metallicRoughnessTexture.texture)];
  ASSERT_TRUE(colour.loaded());
  ASSERT_TRUE(data.loaded());
  EXPECT_EQ(colour.width, 2);
  EXPECT_EQ(colour.uri, "grey%20tex.png");
  EXPECT_TRUE(colour.srgb);
  EXPECT_FALSE(data.srgb);
  EXPECT_NEAR(colour.texels[0].r, 0.2140f, 1e-4f);
  EXPECT_NEAR(colour.texels[0].a, 0.5f, 1e-4f);  // alpha is never sRGB-decoded
  EXPECT_NEAR(data.texels[0].g, 0.5f, 1e-4f);
  EXPECT_NEAR(colour.texels[1].r, 1.0f, 1e-6f);
  // Bilinear with repeat: texel centres at u = 0.25 and 0.75; u = 0 mixes both halves.
  EXPECT_NEAR(colour.sample({0.25f, 0.5f}).r, 0.2140f, 1e-4f);
  EXPECT_NEAR(colour.sample({0.0f, 0.5f}).r, (0.2140f + 1.0f) / 2, 1e-4f);
  EXPECT_NEAR(colour.sample({-3.0f, 0.5f}).r, (0.2140f + 1.0f) / 2, 1e-4f);
  // The missing image: a warning naming file, material and image; the texture stays unloaded.
  const Texture& gone = r->textures[size_t(m.emissiveTexture.texture)];
  EXPECT_FALSE(gone.loaded());
  EXPECT_EQ(gone.sample({0.5f, 0.5f}), glm::vec4(1.0f));
  EXPECT_TRUE(hasWarning(*r, "tex.gltf: material 'Grey' emissiveTexture", "image 'Gone' ('missing.png')"))
      << (r->warnings.empty() ? "" : r->warnings[0]);

  // loadTextures = false keeps the references but decodes nothing and warns about nothing.
  LoadOptions skip;
  skip.loadTextures = false;
  auto r2 = loadGltfFromMemory(text, "tex.gltf", dir, skip);
  ASSERT_TRUE(r2) << r2.message();
  EXPECT_EQ(r2->textures.size(), r->textures.size());
  for (const Texture& t : r2->textures) EXPECT_FALSE(t.loaded());
  EXPECT_FALSE(hasWarning(*r2, "decoded"));
}

// KHR_materials_specular and KHR_materials_ior: factors, textures (specular strength from the
// alpha channel of a linear texture, specular colour from an sRGB one), no "used but ignored".
TEST(GltfImport, SpecularAndIorFactorsAndTextures) {
  const std::string dir = test::tempDir("gltf_import_specular");
  writeGreyPng(dir + "/spec.png");
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}, {"material", 0}}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  b.j["extensionsUsed"] = {"KHR_materials_specular", "KHR_materials_ior", "KHR_texture_transform"};
  b.j["images"] = json::array({{{"uri", "spec.png"}}});
  b.j["textures"] = json::array({{{"source", 0}}});
  b.j["materials"] = json::array(
      {{{"name", "Glossy"},
        {"extensions",
         {{"KHR_materials_ior", {{"ior", 1.33}}},
          {"KHR_materials_specular",
           {{"specularFactor", 0.75},
            {"specularTexture", {{"index", 0}, {"texCoord", 1}}},
            {"specularColorFactor", {2.0, 1.0, 0.5}},
            {"specularColorTexture",
             {{"index", 0},
              {"extensions", {{"KHR_texture_transform", {{"offset", {0.5, 0}}}}}}}}}}}}},
       {{"name", "Plain"}},
       {{"name", "SpecGloss"}, {"extensions", {{"KHR_materials_ior", {{"ior", 0}}}}}}});
  auto r = loadGltfFromMemory(b.gltf(), "spec.gltf", dir);
  ASSERT_TRUE(r) << r.message();
  // The triangle's missing normals are the only thing to warn about.
  for (const std::string& w : r->warnings)
    if (w.find("no NORMAL attribute") == std::string::npos) ADD_FAILURE() << w;
  ASSERT_EQ(r->materials.size(), 3u);
  const Material& m = r->materials[0];
  EXPECT_FLOAT_EQ(m.ior, 1.33f);
  EXPECT_FLOAT_EQ(m.specularFactor, 0.75f);
  EXPECT_EQ(m.specularColorFactor, glm::vec3(2.0f, 1.0f, 0.5f));
  ASSERT_TRUE(m.specularTexture.valid());
  ASSERT_TRUE(m.specularColorTexture.valid());
  EXPECT_EQ(m.specularTexture.texCoord, 1);
  EXPECT_FALSE(m.specularTexture.hasTransform);
  EXPECT_TRUE(m.specularColorTexture.hasTransform);
  EXPECT_EQ(m.specularColorTexture.offset, glm::vec2(0.5f, 0.0f));
  // One image, decoded linear for the strength and sRGB for the colour.
  ASSERT_NE(m.specularTexture.texture, m.specularColorTexture.texture);
  const Texture& strength = r->textures[size_t(m.specularTexture.texture)];
  const Texture& colour = r->textures[size_t(m.specularColorTexture.texture)];
  ASSERT_TRUE(strength.loaded());
  ASSERT_TRUE(colour.loaded());
  EXPECT_FALSE(strength.srgb);
  EXPECT_TRUE(colour.srgb);
  EXPECT_NEAR(strength.texels[0].r, 0.5f, 1e-4f);
  EXPECT_NEAR(strength.texels[0].a, 0.5f, 1e-4f);
  EXPECT_NEAR(colour.texels[0].r, 0.2140f, 1e-4f);
  // Without the extensions: glTF's defaults.
  const Material& plain = r->materials[1];
  EXPECT_EQ(plain.ior, 1.5f);
  EXPECT_EQ(plain.specularFactor, 1.0f);
  EXPECT_EQ(plain.specularColorFactor, glm::vec3(1.0f));
  EXPECT_FALSE(plain.specularTexture.valid());
  EXPECT_FALSE(plain.specularColorTexture.valid());
  // ior 0 is valid (the specular-glossiness conversion: F0 = 1).
  EXPECT_EQ(r->materials[2].ior, 0.0f);
}

// Out-of-range values are clamped into range, each with a warning naming the file and material.
TEST(GltfImport, SpecularAndIorOutOfRangeWarn) {
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}, {"material", 0}}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  b.j["extensionsUsed"] = {"KHR_materials_specular", "KHR_materials_ior"};
  b.j["materials"] = json::array(
      {{{"name", "TooMuch"},
        {"extensions",
         {{"KHR_materials_ior", {{"ior", 0.5}}},
          {"KHR_materials_specular",
           {{"specularFactor", 1.5}, {"specularColorFactor", {-1.0, 0.5, 3.0}}}}}}},
       {{"name", "Negative"},
        {"extensions",
         {{"KHR_materials_ior", {{"ior", -2}}},
          {"KHR_materials_specular", {{"specularFactor", -0.5}, {"specularColorFactor", "red"}}}}}},
       {{"name", "BadTexture"},
        {"extensions", {{"KHR_materials_specular", {{"specularTexture", {{"texCoord", 0}}}}}}}}});
  auto r = load(b.gltf());
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->materials.size(), 3u);
  const Material& a = r->materials[0];
  EXPECT_EQ(a.ior, 1.0f);
  EXPECT_EQ(a.specularFactor, 1.0f);
  EXPECT_EQ(a.specularColorFactor, glm::vec3(0.0f, 0.5f, 3.0f));  // above 1 is valid
  EXPECT_TRUE(hasWarning(*r, "test.gltf: material 'TooMuch'", "ior 0.5 is below 1"));
  EXPECT_TRUE(hasWarning(*r, "test.gltf: material 'TooMuch'", "specularFactor 1.5 is outside [0, 1]"));
  EXPECT_TRUE(hasWarning(*r, "test.gltf: material 'TooMuch'", "specularColorFactor has negative"));
  const Material& n = r->materials[1];
  EXPECT_EQ(n.ior, 1.5f);
  EXPECT_EQ(n.specularFactor, 0.0f);
  EXPECT_EQ(n.specularColorFactor, glm::vec3(1.0f));
  EXPECT_TRUE(hasWarning(*r, "test.gltf: material 'Negative'", "ior is not a number >= 1 or 0"));
  EXPECT_TRUE(hasWarning(*r, "test.gltf: material 'Negative'", "specularFactor -0.5 is outside"));
  EXPECT_TRUE(hasWarning(*r, "test.gltf: material 'Negative'", "specularColorFactor is not 3"));
  EXPECT_FALSE(r->materials[2].specularTexture.valid());
  EXPECT_TRUE(hasWarning(*r, "test.gltf: material 'BadTexture'", "specularTexture has no valid index"));
  EXPECT_FALSE(hasWarning(*r, "used but ignored"));
  size_t materialWarnings = 0;
  for (const std::string& w : r->warnings) materialWarnings += w.find("material '") != std::string::npos;
  EXPECT_EQ(materialWarnings, 7u);
}

// KHR_materials_transmission: its factor and texture (the transmission in the red channel of a
// linear texture), clamped with a warning out of range; and what material_eval makes of it and
// of alphaMode BLEND: the light that passes, tinted by the base colour.
TEST(GltfImport, TransmissionFactorTextureAndWhatPasses) {
  const std::string dir = test::tempDir("gltf_import_transmission");
  writeGreyPng(dir + "/t.png");
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}, {"material", 0}}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  b.j["extensionsUsed"] = {"KHR_materials_transmission"};
  b.j["images"] = json::array({{{"uri", "t.png"}}});
  b.j["textures"] = json::array({{{"source", 0}}});
  const json tinted = {{"baseColorFactor", {0.5, 1.0, 0.25, 0.4}}};
  b.j["materials"] = json::array(
      {{{"name", "Textured"},
        {"pbrMetallicRoughness", tinted},
        {"extensions",
         {{"KHR_materials_transmission",
           {{"transmissionFactor", 0.8}, {"transmissionTexture", {{"index", 0}}}}}}}},
       {{"name", "TooMuch"},
        {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 1.5}}}}}},
       {{"name", "Blend"}, {"alphaMode", "BLEND"}, {"pbrMetallicRoughness", tinted}},
       {{"name", "BlendAndTransmission"},
        {"alphaMode", "BLEND"},
        {"pbrMetallicRoughness", tinted},
        {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 0.5}}}}}},
       {{"name", "Mask"}, {"alphaMode", "MASK"}, {"pbrMetallicRoughness", tinted}},
       {{"name", "OpaqueBlend"}, {"alphaMode", "BLEND"}}});
  auto r = loadGltfFromMemory(b.gltf(), "t.gltf", dir);
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->materials.size(), 6u);
  const Material& m = r->materials[0];
  EXPECT_FLOAT_EQ(m.transmissionFactor, 0.8f);
  ASSERT_TRUE(m.transmissionTexture.valid());
  EXPECT_FALSE(r->textures[size_t(m.transmissionTexture.texture)].srgb);
  EXPECT_EQ(r->materials[1].transmissionFactor, 1.0f);
  EXPECT_TRUE(hasWarning(*r, "t.gltf: material 'TooMuch'", "transmissionFactor 1.5 is outside"));
  EXPECT_FALSE(hasWarning(*r, "used but ignored"));
  // The texture's first texel is a linear 0.5: 0.8 × 0.5 passes, tinted by the base colour
  // (OPAQUE: its alpha does not count).
  const Transmission textured = transmission(*r, 0, glm::vec2(0.25f, 0.5f));
  EXPECT_NEAR(textured.open, 0.4f, 1e-3f);
  expectVec(textured.tint, glm::vec3(0.5f, 1.0f, 0.25f));
  EXPECT_NEAR(textured.grey(), 0.4f * 1.75f / 3.0f, 1e-3f);
  // BLEND lets 1 − alpha through; with transmission 1 − alpha × (1 − transmission).
  EXPECT_NEAR(transmission(*r, 2, {}).open, 0.6f, 1e-6f);
  expectVec(transmission(*r, 2, {}).rgb(), 0.6f * glm::vec3(0.5f, 1.0f, 0.25f));
  EXPECT_NEAR(transmission(*r, 3, {}).open, 0.8f, 1e-6f);
  EXPECT_EQ(transmission(*r, 2, {}, false).open, 0.0f);  // BLEND cut out as MASK instead
  // MASK and OPAQUE alphas, and a BLEND of alpha 1, let nothing through.
  EXPECT_EQ(transmission(*r, 4, {}).open, 0.0f);
  EXPECT_FALSE(transmissive(*r, 4));
  EXPECT_FALSE(transmissive(*r, 5));
  EXPECT_FALSE(transmissive(*r, -1));
  for (int k : {0, 1, 2, 3}) EXPECT_TRUE(transmissive(*r, k)) << k;
  EXPECT_FALSE(transmissive(*r, 2, false));
}

TEST(GltfImport, EmbeddedEightBitImagesUseTheExactSrgbCurve) {
  // A 1×1 8-bit grey PNG of code value 128, embedded once through a bufferView and once as a
  // data: URI. sRGB 128/255 = 0.50196 decodes to 0.21586 linear.
  const std::string dir = test::tempDir("gltf_import_embedded");
  {
    auto out = OIIO::ImageOutput::create(dir + "/g.png");
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(dir + "/g.png", OIIO::ImageSpec(1, 1, 3, OIIO::TypeDesc::UINT8)));
    const uint8_t px[3] = {128, 128, 128};
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px));
    out->close();
  }
  std::ifstream in(dir + "/g.png", std::ios::binary);
  const std::string png((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(png.size(), 8u);
  Builder b;
  int pos = b.positions(kTriangle);
  b.data(std::vector<char>(png.begin(), png.end()), kUByte, "SCALAR");
  b.j["accessors"].erase(1);  // only its bufferView (1) is wanted
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}, {"material", 0}}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  b.j["images"] = json::array({{{"bufferView", 1}, {"mimeType", "image/png"}},
                               {{"uri", "data:image/png;base64," + base64(png)}}});
  b.j["textures"] = json::array({{{"source", 0}}, {{"source", 1}}});
  b.j["materials"] = json::array({{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}},
                                   {"emissiveTexture", {{"index", 1}}}}});
  for (const std::string& bytes : {b.gltf(), b.glb()}) {
    auto r = load(bytes);
    ASSERT_TRUE(r) << r.message();
    ASSERT_EQ(r->textures.size(), 2u);
    for (const Texture& t : r->textures) {
      ASSERT_TRUE(t.loaded()) << t.name;
      EXPECT_EQ(t.uri, "");
      EXPECT_NEAR(t.texels[0].r, 0.21586f, 2e-5f);
      EXPECT_FLOAT_EQ(t.texels[0].a, 1.0f);
    }
  }
}

TEST(GltfImport, LightsAndCamerasArePlacedInWorldSpace) {
  Builder b;
  const double h = std::sqrt(0.5);
  b.j["extensionsUsed"] = {"KHR_lights_punctual"};
  b.j["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
      {{{"name", "Sun"}, {"type", "directional"}, {"color", {1, 0.9, 0.8}}, {"intensity", 5},
        {"extras", {{"afterglow", {{"angularDiameter", 0.02}, {"bounceIntensity", 2},
                                   {"mode", "mixed"}}}}}},
       {{"type", "point"}, {"intensity", 100}, {"range", 7},
        {"extras", {{"afterglow", {{"radius", 0.1}, {"mode", "realtime"}}}}}},
       {{"type", "spot"}, {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.5}}},
        {"extras", {{"afterglow", {{"mode", "dynamic"}}}}}}});
  // Rotating -90° about X turns -Z into -Y: the sun shines straight down.
  b.node({{"name", "sunNode"}, {"rotation", {-h, 0, 0, h}},
          {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  b.node({{"translation", {1, 2, 3}}, {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
  b.node({{"translation", {0, 4, 0}}, {"rotation", {0, h, 0, h}}, {"children", {3}}});
  b.node({{"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}, {"camera", 0}});
  b.j["cameras"] = json::array({{{"type", "perspective"},
                                 {"perspective", {{"yfov", 0.5}, {"znear", 0.1}, {"aspectRatio", 1.5}}}}});
  b.scene({0, 1, 2});
  auto r = load(b.gltf());
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->lights.size(), 3u);
  const Light& sun = r->lights[0];
  EXPECT_EQ(sun.name, "Sun");
  EXPECT_EQ(sun.type, LightType::Directional);
  expectVec(sun.direction, {0, -1, 0});
  expectVec(sun.color, {1, 0.9f, 0.8f});
  EXPECT_FLOAT_EQ(sun.intensity, 5.0f);
  EXPECT_FLOAT_EQ(sun.angularDiameter, 0.02f);
  EXPECT_FLOAT_EQ(sun.bounceIntensity, 2.0f);
  EXPECT_EQ(sun.mode, LightMode::Mixed);
  EXPECT_EQ(sun.node, 0);
  const Light& point = r->lights[1];
  EXPECT_EQ(point.type, LightType::Point);
  expectVec(point.position, {1, 2, 3});
  EXPECT_FLOAT_EQ(point.range, 7.0f);
  EXPECT_FLOAT_EQ(point.radius, 0.1f);
  EXPECT_FLOAT_EQ(point.angularDiameter, 0.00925f);
  EXPECT_EQ(point.mode, LightMode::Realtime);
  // The spot hangs under a parent rotated 90° about Y: -Z turns into -X.
  const Light& spot = r->lights[2];
  EXPECT_EQ(spot.type, LightType::Spot);
  expectVec(spot.position, {0, 4, 0});
  expectVec(spot.direction, {-1, 0, 0});
  EXPECT_FLOAT_EQ(spot.innerConeAngle, 0.2f);
  EXPECT_FLOAT_EQ(spot.outerConeAngle, 0.5f);
  // An unknown mode is baked, with a warning naming the light.
  EXPECT_EQ(spot.mode, LightMode::Baked);
  EXPECT_TRUE(std::any_of(r->warnings.begin(), r->warnings.end(), [](const std::string& w) {
    return w.find("extras.afterglow.mode") != std::string::npos;
  }));
  ASSERT_EQ(r->cameras.size(), 1u);
  EXPECT_TRUE(r->cameras[0].perspective);
  EXPECT_FLOAT_EQ(r->cameras[0].yfov, 0.5f);
  EXPECT_FLOAT_EQ(r->cameras[0].aspectRatio, 1.5f);
  expectVec(glm::vec3(r->cameras[0].transform[3]), {0, 4, 0});
  expectVec(glm::vec3(r->cameras[0].transform * glm::vec4(0, 0, -1, 0)), {-1, 0, 0});
}

TEST(GltfImport, ExtrasAfterglowDefaultsAndInheritance) {
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}}}));
  b.node({{"name", "root"}, {"mesh", 0}, {"children", {1}},
          {"extras", {{"afterglow", {{"static", false}, {"lightmapScale", 2.5}}}}}});
  b.node({{"name", "child"}, {"mesh", 0}, {"children", {2}},
          {"extras", {{"afterglow", {{"castShadows", false}}}}}});
  b.node({{"name", "grandchild"}, {"mesh", 0},
          {"extras", {{"afterglow", {{"static", true}, {"lightmapScale", "big"}}}}}});
  b.node({{"name", "plain"}, {"mesh", 0},
          {"extras", {{"afterglow", {{"lightmap", {{"atlas", 2}, {"width", 512}, {"height", 256}}}}}}}});
  b.scene({0, 3});
  auto r = load(b.gltf());
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->instances.size(), 4u);
  const auto& root = r->instances[0];
  const auto& child = r->instances[1];
  const auto& grandchild = r->instances[2];
  const auto& plain = r->instances[3];
  EXPECT_EQ(plain.name, "plain");
  EXPECT_TRUE(plain.isStatic);
  EXPECT_FLOAT_EQ(plain.lightmapScale, 1.0f);
  EXPECT_TRUE(plain.castShadows);
  EXPECT_EQ(plain.lightmap.atlas, 2);
  EXPECT_EQ(plain.lightmap.width, 512);
  EXPECT_EQ(plain.lightmap.height, 256);
  EXPECT_EQ(root.lightmap.atlas, -1);  // not inherited, and absent by default
  EXPECT_FALSE(root.isStatic);
  EXPECT_FLOAT_EQ(root.lightmapScale, 2.5f);
  EXPECT_TRUE(root.castShadows);
  EXPECT_FALSE(child.isStatic);
  EXPECT_FLOAT_EQ(child.lightmapScale, 2.5f);
  EXPECT_FALSE(child.castShadows);
  EXPECT_TRUE(grandchild.isStatic);
  EXPECT_FLOAT_EQ(grandchild.lightmapScale, 2.5f);  // the wrong type keeps the inherited value
  EXPECT_FALSE(grandchild.castShadows);
  EXPECT_TRUE(hasWarning(*r, "node 'grandchild'", "lightmapScale"));
}

TEST(GltfImport, SceneSelectionAndGlb) {
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}}}));
  b.node({{"name", "a"}, {"mesh", 0}});
  b.node({{"name", "b"}, {"mesh", 0}});
  b.node({{"name", "c"}, {"mesh", 0}, {"children", {1}}});
  // No scenes: every root node (a and c, with c's child b).
  auto none = load(b.gltf());
  ASSERT_TRUE(none) << none.message();
  EXPECT_EQ(none->instances.size(), 3u);
  b.j["scenes"] = json::array({{{"nodes", {0}}}, {{"nodes", {2}}}});
  auto first = load(b.gltf());  // no default scene: scene 0
  ASSERT_TRUE(first) << first.message();
  ASSERT_EQ(first->instances.size(), 1u);
  EXPECT_EQ(first->instances[0].name, "a");
  b.j["scene"] = 1;
  auto second = load(b.glb());  // the default scene, from a GLB this time
  ASSERT_TRUE(second) << second.message();
  ASSERT_EQ(second->instances.size(), 2u);
  EXPECT_EQ(second->instances[0].name, "c");
  EXPECT_EQ(second->instances[1].name, "b");
}

TEST(GltfImport, FileOnDiskWithExternalBufferAndGlbByMagic) {
  const std::string dir = test::tempDir("gltf_import_files");
  Builder b;
  int pos = b.positions(kTriangle);
  b.mesh(json::array({{{"attributes", {{"POSITION", pos}}}}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  json j = b.j;
  j["buffers"] = json::array({{{"byteLength", b.bin.size()}, {"uri", "my%20data.bin"}}});
  std::ofstream(dir + "/my data.bin", std::ios::binary) << b.bin;
  std::ofstream(dir + "/level.gltf") << j.dump();
  auto r = loadGltf(dir + "/level.gltf");
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(r->sourcePath, dir + "/level.gltf");
  EXPECT_EQ(r->meshTriangleCount(), 1u);
  // A GLB with a misleading extension is still recognised by its magic.
  std::ofstream(dir + "/actually_binary.gltf", std::ios::binary) << b.glb();
  auto g = loadGltf(dir + "/actually_binary.gltf");
  ASSERT_TRUE(g) << g.message();
  EXPECT_EQ(g->meshTriangleCount(), 1u);
}

// ---- shared reference scenes --------------------------------------------------------------

TEST(GltfImportShared, CornellBox) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  auto r = loadGltf(path);
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(r->meshTriangleCount(), 32u);
  EXPECT_EQ(r->instancedTriangleCount(), 32u);
  int emissive = 0;
  for (const Material& m : r->materials) emissive += m.emissive();
  EXPECT_EQ(emissive, 1);
  EXPECT_FALSE(r->bounds().empty());
}

TEST(GltfImportShared, SponzaGeometry) {
  AG_REQUIRE_SHARED_SCENE(path, "sponza/Sponza.gltf");
  LoadOptions options;
  options.loadTextures = false;
  auto r = loadGltf(path, options);
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(r->meshes.size(), 44u);
  EXPECT_EQ(r->instances.size(), 170u);
  EXPECT_EQ(r->instancedTriangleCount(), 262087u);
  EXPECT_GT(r->meshTriangleCount(), 100000u);
  EXPECT_LT(r->meshTriangleCount(), 130000u);
  for (const Mesh& m : r->meshes)
    for (const Primitive& p : m.primitives) {
      EXPECT_EQ(p.normals.size(), p.positions.size());
      EXPECT_EQ(p.uv0.size(), p.positions.size());
    }
}

TEST(GltfImportShared, SponzaTexturesDecode) {
  AG_REQUIRE_SHARED_SCENE(path, "sponza/Sponza.gltf");
  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpuStart = std::clock();
  auto r = loadGltf(path);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // The process's processor time (all threads): unlike wall time, it does not grow when other
  // tests share the machine's cores.
  const double cpuSeconds = double(std::clock() - cpuStart) / CLOCKS_PER_SEC;
  ASSERT_TRUE(r) << r.message();
  size_t loaded = 0, colour = 0;
  for (const Texture& t : r->textures) {
    loaded += t.loaded();
    colour += t.loaded() && t.srgb;
  }
  EXPECT_GT(colour, 20u);
  for (const Material& m : r->materials)
    if (m.baseColorTexture.valid()) {
      EXPECT_TRUE(r->textures[size_t(m.baseColorTexture.texture)].loaded()) << m.name;
    }
  EXPECT_TRUE(r->warnings.empty()) << r->warnings.front();
  EXPECT_LT(cpuSeconds, 60.0) << seconds << " s wall";
  RecordProperty("load_seconds", std::to_string(seconds));
  RecordProperty("load_cpu_seconds", std::to_string(cpuSeconds));
}

TEST(GltfImportShared, SponzaSunHasOneDirectionalLight) {
  AG_REQUIRE_SHARED_SCENE(path, "sponza/Sponza-sun.gltf");
  LoadOptions options;
  options.loadTextures = false;
  auto r = loadGltf(path, options);
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->lights.size(), 1u);
  EXPECT_EQ(r->lights[0].type, LightType::Directional);
  EXPECT_NEAR(glm::length(r->lights[0].direction), 1.0f, 1e-5f);
  EXPECT_LT(r->lights[0].direction.y, 0.0f);  // the sun shines downwards
  EXPECT_EQ(r->instances.size(), 170u);
}

TEST(GltfImportShared, MixedLightingHasLightmapUvsAndTextureTransform) {
  AG_REQUIRE_SHARED_SCENE(path, "mixed_lighting_bevy/MixedLightingExample.gltf");
  auto r = loadGltf(path);
  ASSERT_TRUE(r) << r.message();
  size_t primitives = 0;
  for (const Mesh& m : r->meshes)
    for (const Primitive& p : m.primitives) {
      ++primitives;
      EXPECT_EQ(p.uv1.size(), p.positions.size()) << m.name;
    }
  EXPECT_GT(primitives, 0u);
  bool transform = false;
  for (const Material& m : r->materials) transform = transform || m.baseColorTexture.hasTransform;
  EXPECT_TRUE(transform);
  EXPECT_FALSE(r->lights.empty());
  EXPECT_TRUE(hasWarning(*r, "KHR_materials_sheen"));
  for (const Material& m : r->materials)
    if (m.baseColorTexture.valid()) {
      EXPECT_TRUE(r->textures[size_t(m.baseColorTexture.texture)].loaded()) << m.name;
    }
}

}  // namespace
}  // namespace afterglow::scenes
