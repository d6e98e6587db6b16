// glTF export: round trips through saveGltf -> loadGltf, the JSON it writes, and atomicity.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "afterglow/core/atomic_file.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"
#include "test_util.h"

namespace afterglow::scenes {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::vector<std::string> filesIn(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

json readJson(const std::string& path) {
  Result<std::string> text = readFile(path);
  EXPECT_TRUE(text.isOk()) << text.message();
  return json::parse(text.isOk() ? text.value() : std::string("{}"));
}

void expectVecNear(glm::vec3 a, glm::vec3 b, float tol, const std::string& what) {
  EXPECT_NEAR(a.x, b.x, tol) << what;
  EXPECT_NEAR(a.y, b.y, tol) << what;
  EXPECT_NEAR(a.z, b.z, tol) << what;
}

void expectMatNear(const glm::mat4& a, const glm::mat4& b, float tol, const std::string& what) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(a[c][r], b[c][r], tol) << what << " [" << c << r << "]";
}

// The Cornell box plus everything the exporter must carry that the procedural scene lacks.
// A node's world transform turned 36.87 degrees about +Y and moved: what a round trip of a
// node-placed box must keep.
const glm::mat4 kTurnedNode(0.8f, 0.0f, -0.6f, 0.0f,
                            0.0f, 1.0f, 0.0f, 0.0f,
                            0.6f, 0.0f, 0.8f, 0.0f,
                            1.5f, 2.0f, -3.0f, 1.0f);

void expectSameTransform(const glm::mat4& a, const glm::mat4& b, const std::string& name) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(a[c][r], b[c][r], 1e-6f) << name;
}

// A glTF of one node named `node` at (1, 2, 3) with extras.afterglow.<key> = `value` (JSON
// text), written to DIR/NAME.gltf; returns its path.
std::string writeNodeExtras(const std::string& dir, const std::string& name,
                            const std::string& node, const std::string& key,
                            const std::string& value) {
  const std::string path = dir + "/" + name + ".gltf";
  std::ofstream(path) << R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"name": ")" << node << R"(", "translation": [1, 2, 3],
               "extras": {"afterglow": {")" << key << R"(": )" << value << "}}}]}";
  return path;
}

Scene decoratedCornellBox() {
  Scene scene = makeCornellBox();
  Light point;
  point.name = "bulb";
  point.type = LightType::Point;
  point.color = {1.0f, 0.9f, 0.8f};
  point.intensity = 12.5f;
  point.range = 4.0f;
  point.position = {0.2f, 0.4f, 0.3f};
  point.radius = 0.05f;
  scene.lights.push_back(point);
  Light spot;
  spot.name = "spot";
  spot.type = LightType::Spot;
  spot.intensity = 300.0f;
  spot.position = {0.278f, 0.5f, 0.1f};
  spot.direction = glm::normalize(glm::vec3(0.1f, -1.0f, 0.4f));
  spot.innerConeAngle = 0.2f;
  spot.outerConeAngle = 0.6f;
  spot.bounceIntensity = 2.0f;
  scene.lights.push_back(spot);
  Light sun;
  sun.name = "sun";
  sun.type = LightType::Directional;
  sun.intensity = 100000.0f;
  sun.direction = glm::normalize(glm::vec3(-0.3f, -0.8f, 0.5f));
  sun.angularDiameter = 0.02f;
  scene.lights.push_back(sun);
  Light down;  // straight along +Z: the antiparallel case of the -Z -> direction rotation
  down.name = "backwards";
  down.type = LightType::Directional;
  down.direction = {0.0f, 0.0f, 1.0f};
  scene.lights.push_back(down);

  scene.instances[1].isStatic = false;
  scene.instances[2].lightmapScale = 2.5f;
  scene.instances[3].castShadows = false;
  scene.instances[0].lightmap = {3, 512, 256};
  scene.instances[4].lightmap = {0, 1024, 1024};
  // Move one block to check that instance transforms survive.
  glm::mat4 t(1.0f);
  t[0] = glm::vec4(0.0f, 0.0f, -1.0f, 0.0f);
  t[2] = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
  t[3] = glm::vec4(0.01f, 0.0f, -0.02f, 1.0f);
  scene.instances[5].transform = t;

  Primitive& floor = scene.meshes[0].primitives[0];
  for (const glm::vec3& p : floor.positions) {
    floor.uv0.push_back({p.x * 2.0f, p.z * 2.0f});
    floor.uv1.push_back({p.x / 0.556f * 0.5f + 0.25f, p.z / 0.5592f * 0.5f});
  }
  scene.materials[1].doubleSided = true;
  scene.materials[2].alphaMode = AlphaMode::Mask;
  scene.materials[2].alphaCutoff = 0.3f;
  scene.materials[0].metallicFactor = 0.25f;
  scene.materials[0].roughnessFactor = 0.75f;
  return scene;
}

void expectSameGeometry(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (size_t m = 0; m < a.meshes.size(); ++m) {
    const Mesh& ma = a.meshes[m];
    const Mesh& mb = b.meshes[m];
    EXPECT_EQ(ma.name, mb.name);
    ASSERT_EQ(ma.primitives.size(), mb.primitives.size()) << ma.name;
    EXPECT_EQ(ma.triangleCount(), mb.triangleCount()) << ma.name;
    for (size_t p = 0; p < ma.primitives.size(); ++p) {
      const Primitive& pa = ma.primitives[p];
      const Primitive& pb = mb.primitives[p];
      EXPECT_EQ(pa.material, pb.material);
      ASSERT_EQ(pa.indices.size(), pb.indices.size());
      EXPECT_EQ(pa.uv0.size(), pb.uv0.size());
      EXPECT_EQ(pa.uv1.size(), pb.uv1.size());
      // Compare per corner so the test does not depend on vertex order.
      for (size_t i = 0; i < pa.indices.size(); ++i) {
        const uint32_t ia = pa.indices[i], ib = pb.indices[i];
        expectVecNear(pa.positions[ia], pb.positions[ib], 1e-6f, ma.name + " position");
        expectVecNear(pa.normals[ia], pb.normals[ib], 1e-6f, ma.name + " normal");
        if (!pa.uv1.empty() && pa.uv1.size() == pb.uv1.size()) {
          EXPECT_NEAR(pa.uv1[ia].x, pb.uv1[ib].x, 1e-6f);
          EXPECT_NEAR(pa.uv1[ia].y, pb.uv1[ib].y, 1e-6f);
        }
        if (!pa.uv0.empty() && pa.uv0.size() == pb.uv0.size()) {
          EXPECT_NEAR(pa.uv0[ia].x, pb.uv0[ib].x, 1e-6f);
          EXPECT_NEAR(pa.uv0[ia].y, pb.uv0[ib].y, 1e-6f);
        }
      }
    }
  }
}

void expectSameMaterials(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (size_t i = 0; i < a.materials.size(); ++i) {
    const Material& x = a.materials[i];
    const Material& y = b.materials[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.baseColorFactor, y.baseColorFactor) << x.name;
    EXPECT_EQ(x.metallicFactor, y.metallicFactor) << x.name;
    EXPECT_EQ(x.roughnessFactor, y.roughnessFactor) << x.name;
    EXPECT_EQ(x.emissiveFactor, y.emissiveFactor) << x.name;
    EXPECT_EQ(x.emissiveStrength, y.emissiveStrength) << x.name;
    EXPECT_EQ(x.ior, y.ior) << x.name;
    EXPECT_EQ(x.specularFactor, y.specularFactor) << x.name;
    EXPECT_EQ(x.specularColorFactor, y.specularColorFactor) << x.name;
    EXPECT_EQ(x.specularTexture.valid(), y.specularTexture.valid()) << x.name;
    EXPECT_EQ(x.specularColorTexture.valid(), y.specularColorTexture.valid()) << x.name;
    EXPECT_EQ(x.doubleSided, y.doubleSided) << x.name;
    EXPECT_EQ(x.alphaMode, y.alphaMode) << x.name;
    if (x.alphaMode == AlphaMode::Mask) {
      EXPECT_EQ(x.alphaCutoff, y.alphaCutoff) << x.name;
    }
  }
}

void expectSameInstances(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.instances.size(), b.instances.size());
  for (size_t i = 0; i < a.instances.size(); ++i) {
    const Instance& x = a.instances[i];
    const Instance& y = b.instances[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.mesh, y.mesh) << x.name;
    expectMatNear(x.transform, y.transform, 1e-6f, x.name);
    EXPECT_EQ(x.isStatic, y.isStatic) << x.name;
    EXPECT_EQ(x.lightmapScale, y.lightmapScale) << x.name;
    EXPECT_EQ(x.castShadows, y.castShadows) << x.name;
  }
}

TEST(GltfExport, CornellRoundTrip) {
  const Scene scene = decoratedCornellBox();
  const std::string dir = test::tempDir("export_cornell");
  const std::string path = dir + "/cornell.gltf";
  Status s = saveGltf(scene, path);
  ASSERT_TRUE(s.isOk()) << s.message();
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{"cornell.bin", "cornell.gltf"}));

  Result<Scene> loaded = loadGltf(path);
  ASSERT_TRUE(loaded.isOk()) << loaded.message();
  const Scene& back = loaded.value();
  EXPECT_TRUE(back.warnings.empty()) << back.warnings.front();
  expectSameGeometry(scene, back);
  expectSameMaterials(scene, back);
  expectSameInstances(scene, back);
  EXPECT_EQ(back.meshes[0].primitives[0].uv1.size(), 4u);
  EXPECT_EQ(back.instancedTriangleCount(), scene.instancedTriangleCount());

  ASSERT_EQ(back.lights.size(), scene.lights.size());
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const Light& x = scene.lights[i];
    const Light& y = back.lights[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.type, y.type) << x.name;
    EXPECT_EQ(x.color, y.color) << x.name;
    EXPECT_EQ(x.intensity, y.intensity) << x.name;
    EXPECT_EQ(x.range, y.range) << x.name;
    if (x.type != LightType::Directional) expectVecNear(x.position, y.position, 1e-6f, x.name);
    if (x.type != LightType::Point) expectVecNear(x.direction, y.direction, 1e-6f, x.name);
    if (x.type == LightType::Spot) {
      EXPECT_EQ(x.innerConeAngle, y.innerConeAngle);
      EXPECT_EQ(x.outerConeAngle, y.outerConeAngle);
    }
    EXPECT_EQ(x.radius, y.radius) << x.name;
    EXPECT_EQ(x.angularDiameter, y.angularDiameter) << x.name;
    EXPECT_EQ(x.bounceIntensity, y.bounceIntensity) << x.name;
  }

  ASSERT_EQ(back.cameras.size(), 1u);
  EXPECT_EQ(back.cameras[0].name, "Camera");
  EXPECT_EQ(back.cameras[0].yfov, scene.cameras[0].yfov);
  EXPECT_EQ(back.cameras[0].aspectRatio, 1.0f);
  expectMatNear(back.cameras[0].transform, scene.cameras[0].transform, 1e-6f, "camera");
}

// extras.afterglow.lightmap is how `afterglow uv` tells other tools where each instance's
// lightmap lives; reading the file back must give the same locations.
TEST(GltfExport, LightmapRecordRoundTrip) {
  const Scene scene = decoratedCornellBox();
  const std::string dir = test::tempDir("export_lightmap");
  ASSERT_TRUE(saveGltf(scene, dir + "/lm.gltf").isOk());
  Result<Scene> back = loadGltf(dir + "/lm.gltf");
  ASSERT_TRUE(back.isOk()) << back.message();
  ASSERT_EQ(back->instances.size(), scene.instances.size());
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const LightmapLocation& x = scene.instances[i].lightmap;
    const LightmapLocation& y = back->instances[i].lightmap;
    EXPECT_EQ(x.atlas, y.atlas) << scene.instances[i].name;
    EXPECT_EQ(x.width, y.width) << scene.instances[i].name;
    EXPECT_EQ(x.height, y.height) << scene.instances[i].name;
  }
}

// extras.afterglow.probeVolume survives a round trip: the box's node, turn and size, and its
// spacing only when it had one.
TEST(GltfExport, ProbeVolumeRoundTrip) {
  Scene scene = decoratedCornellBox();
  ProbeVolume turned;
  turned.name = "hall_probes";
  turned.transform = kTurnedNode;
  turned.size = glm::vec3(4.0f, 2.5f, 1.25f);
  turned.spacing = 0.5f;
  ProbeVolume plain;
  plain.name = "plain";
  plain.size = glm::vec3(1.0f);
  scene.probeVolumes = {turned, plain};
  const std::string dir = test::tempDir("export_probe_volume");
  ASSERT_TRUE(saveGltf(scene, dir + "/pv.gltf").isOk());
  Result<Scene> back = loadGltf(dir + "/pv.gltf");
  ASSERT_TRUE(back.isOk()) << back.message();
  ASSERT_EQ(back->probeVolumes.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const ProbeVolume& x = scene.probeVolumes[i];
    const ProbeVolume& y = back->probeVolumes[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_GE(y.node, 0);
    EXPECT_EQ(x.size, y.size) << x.name;
    EXPECT_EQ(x.spacing, y.spacing) << x.name;
    expectSameTransform(x.transform, y.transform, x.name);
  }
  EXPECT_EQ(back->instances.size(), scene.instances.size());  // no mesh on the volumes' nodes
}

// A probe volume of no size is an import error naming the file and node (a placement that
// ignored it would fill the whole level); so are a malformed size and spacing, and `{}`
// (which tinygltf alone would drop unseen).
TEST(GltfImport, BadProbeVolumeIsAnError) {
  const std::string dir = test::tempDir("import_probe_volume");
  auto write = [&](const std::string& name, const std::string& probeVolume) {
    return writeNodeExtras(dir, name, "attic_probes", "probeVolume", probeVolume);
  };
  Result<Scene> good = loadGltf(write("good", R"({"size": [2, 1, 0.5], "spacing": 0.25})"));
  ASSERT_TRUE(good.isOk()) << good.message();
  ASSERT_EQ(good->probeVolumes.size(), 1u);
  EXPECT_EQ(good->probeVolumes[0].name, "attic_probes");
  EXPECT_EQ(good->probeVolumes[0].size, glm::vec3(2.0f, 1.0f, 0.5f));
  EXPECT_EQ(good->probeVolumes[0].spacing, 0.25f);
  EXPECT_EQ(glm::vec3(good->probeVolumes[0].transform[3]), glm::vec3(1.0f, 2.0f, 3.0f));
  for (const char* bad : {R"({"size": [0, 1, 1]})", R"({"size": [1, -1, 1]})",
                          R"({"size": [1, 1]})", R"({"size": "big"})",
                          R"({"size": [1, 1, 1], "spacing": 0})",
                          R"({"size": [1, 1, 1], "spacing": "fine"})", R"(7)", R"({})"}) {
    const std::string path = write("bad", bad);
    Result<Scene> r = loadGltf(path);
    ASSERT_FALSE(r.isOk()) << bad;
    EXPECT_NE(r.message().find(path), std::string::npos) << r.message();
    EXPECT_NE(r.message().find("attic_probes"), std::string::npos) << r.message();
    EXPECT_EQ(r.message().find('\n'), std::string::npos) << r.message();
  }
}

// extras.afterglow.reflectionProbe survives a round trip: the node's turn, the box and every
// setting; a probe without a size keeps none (the bake fits it).
TEST(GltfExport, ReflectionProbeRoundTrip) {
  Scene scene = decoratedCornellBox();
  ReflectionProbe hall;
  hall.name = "hall_reflection";
  hall.transform = kTurnedNode;
  hall.size = glm::vec3(8.0f, 4.0f, 2.5f);
  hall.blendDistance = 0.5f;
  hall.importance = 3;
  hall.boxProjection = false;
  hall.resolution = 256;
  ReflectionProbe fitted;
  fitted.name = "fitted";
  scene.reflectionProbes = {hall, fitted};
  const std::string dir = test::tempDir("export_reflection_probe");
  ASSERT_TRUE(saveGltf(scene, dir + "/rp.gltf").isOk());
  Result<Scene> back = loadGltf(dir + "/rp.gltf");
  ASSERT_TRUE(back.isOk()) << back.message();
  ASSERT_EQ(back->reflectionProbes.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const ReflectionProbe& x = scene.reflectionProbes[i];
    const ReflectionProbe& y = back->reflectionProbes[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_GE(y.node, 0);
    EXPECT_EQ(x.size, y.size) << x.name;
    EXPECT_EQ(x.blendDistance, y.blendDistance) << x.name;
    EXPECT_EQ(x.importance, y.importance) << x.name;
    EXPECT_EQ(x.boxProjection, y.boxProjection) << x.name;
    EXPECT_EQ(x.resolution, y.resolution) << x.name;
    expectSameTransform(x.transform, y.transform, x.name);
  }
  EXPECT_EQ(back->instances.size(), scene.instances.size());  // no mesh on the probes' nodes
}

// `{}` takes every default; a malformed member is an import error naming the file, the node
// and the member, on one line.
TEST(GltfImport, ReflectionProbeDefaultsAndBadMembers) {
  const std::string dir = test::tempDir("import_reflection_probe");
  auto write = [&](const std::string& name, const std::string& probe) {
    return writeNodeExtras(dir, name, "nave_reflection", "reflectionProbe", probe);
  };
  Result<Scene> plain = loadGltf(write("plain", "{}"));
  ASSERT_TRUE(plain.isOk()) << plain.message();
  ASSERT_EQ(plain->reflectionProbes.size(), 1u);
  const ReflectionProbe defaults;
  const ReflectionProbe& p = plain->reflectionProbes[0];
  EXPECT_EQ(p.name, "nave_reflection");
  EXPECT_EQ(p.size, glm::vec3(0.0f));
  EXPECT_EQ(p.blendDistance, defaults.blendDistance);
  EXPECT_EQ(p.importance, defaults.importance);
  EXPECT_EQ(p.boxProjection, defaults.boxProjection);
  EXPECT_EQ(p.resolution, defaults.resolution);
  EXPECT_EQ(glm::vec3(p.transform[3]), glm::vec3(1.0f, 2.0f, 3.0f));
  Result<Scene> set = loadGltf(write("set", R"({"size": [6, 3, 4], "blendDistance": 0,
      "importance": -2, "boxProjection": false, "resolution": 64})"));
  ASSERT_TRUE(set.isOk()) << set.message();
  ASSERT_EQ(set->reflectionProbes.size(), 1u);
  EXPECT_EQ(set->reflectionProbes[0].size, glm::vec3(6.0f, 3.0f, 4.0f));
  EXPECT_EQ(set->reflectionProbes[0].blendDistance, 0.0f);
  EXPECT_EQ(set->reflectionProbes[0].importance, -2);
  EXPECT_FALSE(set->reflectionProbes[0].boxProjection);
  EXPECT_EQ(set->reflectionProbes[0].resolution, 64);
  const std::pair<const char*, const char*> bad[] = {
      {R"(7)", "not an object"},
      {R"({"size": [0, 1, 1]})", "size"},
      {R"({"size": [1, 1]})", "size"},
      {R"({"blendDistance": -1})", "blendDistance"},
      {R"({"blendDistance": "soft"})", "blendDistance"},
      {R"({"importance": 1.5})", "importance"},
      {R"({"boxProjection": 1})", "boxProjection"},
      {R"({"resolution": 100})", "resolution"},
      {R"({"resolution": 4096})", "resolution"}};
  for (const auto& [probe, member] : bad) {
    const std::string path = write("bad", probe);
    Result<Scene> r = loadGltf(path);
    ASSERT_FALSE(r.isOk()) << probe;
    EXPECT_NE(r.message().find(path), std::string::npos) << r.message();
    EXPECT_NE(r.message().find("nave_reflection"), std::string::npos) << r.message();
    EXPECT_NE(r.message().find(member), std::string::npos) << r.message();
    EXPECT_EQ(r.message().find('\n'), std::string::npos) << r.message();
  }
}

// The emission side survives a round trip (bake --single-sided-emission writes it for render
// and relight to follow), and the obsolete doubleSidedEmission of earlier versions is ignored
// with a warning that names the file and material.
TEST(GltfExport, SingleSidedEmissionRoundTrip) {
  Scene scene = decoratedCornellBox();
  ASSERT_GE(scene.materials.size(), 2u);
  for (Material& m : scene.materials) m.doubleSided = true;
  scene.materials[0].singleSidedEmission = true;
  const std::string dir = test::tempDir("export_emission_side");
  ASSERT_TRUE(saveGltf(scene, dir + "/e.gltf").isOk());
  Result<Scene> back = loadGltf(dir + "/e.gltf");
  ASSERT_TRUE(back.isOk()) << back.message();
  EXPECT_TRUE(back->materials[0].singleSidedEmission);
  EXPECT_FALSE(back->materials[0].emitsFromBack());
  EXPECT_FALSE(back->materials[1].singleSidedEmission);
  EXPECT_TRUE(back->materials[1].emitsFromBack());

  std::string text = test::slurp(dir + "/e.gltf");
  const size_t at = text.find("\"singleSidedEmission\"");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, std::string("\"singleSidedEmission\"").size(), "\"doubleSidedEmission\"");
  std::ofstream(dir + "/old.gltf") << text;
  Result<Scene> old = loadGltf(dir + "/old.gltf");
  ASSERT_TRUE(old.isOk()) << old.message();
  EXPECT_TRUE(old->materials[0].emitsFromBack());  // glTF's rule, whatever the old flag said
  bool warned = false;
  for (const std::string& w : old->warnings)
    warned |= w.find("old.gltf") != std::string::npos &&
              w.find(scene.materials[0].name) != std::string::npos &&
              w.find("doubleSidedEmission is obsolete") != std::string::npos;
  EXPECT_TRUE(warned);
}

// KHR_materials_transmission and alphaMode BLEND survive the round trip (the bake's output
// glTF keeps its glass).
TEST(GltfExport, TransmissionRoundTrip) {
  Scene scene = decoratedCornellBox();
  ASSERT_GE(scene.materials.size(), 2u);
  scene.materials[0].transmissionFactor = 0.75f;
  scene.materials[0].transmissionTexture.texture = scene.materials[0].baseColorTexture.texture;
  scene.materials[1].alphaMode = AlphaMode::Blend;
  scene.materials[1].baseColorFactor.a = 0.4f;
  const std::string dir = test::tempDir("export_transmission");
  ASSERT_TRUE(saveGltf(scene, dir + "/t.gltf").isOk());
  Result<Scene> back = loadGltf(dir + "/t.gltf");
  ASSERT_TRUE(back.isOk()) << back.message();
  EXPECT_EQ(back->materials[0].transmissionFactor, 0.75f);
  EXPECT_EQ(back->materials[0].transmissionTexture.valid(),
            scene.materials[0].transmissionTexture.valid());
  EXPECT_EQ(back->materials[1].alphaMode, AlphaMode::Blend);
  EXPECT_FLOAT_EQ(back->materials[1].baseColorFactor.a, 0.4f);
  EXPECT_EQ(back->materials[1].transmissionFactor, 0.0f);
  const json doc = readJson(dir + "/t.gltf");
  EXPECT_EQ(doc["materials"][0]["extensions"]["KHR_materials_transmission"]["transmissionFactor"],
            0.75);
  EXPECT_FALSE(doc["materials"][1].contains("extensions") &&
               doc["materials"][1]["extensions"].contains("KHR_materials_transmission"));
}

// What the importer does not model (accessor bounds, component types, the lightmap record) is
// checked in the JSON itself.
TEST(GltfExport, WritesTheExpectedJson) {
  const Scene scene = decoratedCornellBox();
  const std::string dir = test::tempDir("export_json");
  ASSERT_TRUE(saveGltf(scene, dir + "/c.gltf").isOk());
  const json doc = readJson(dir + "/c.gltf");
  EXPECT_EQ(doc["asset"]["version"], "2.0");
  const std::set<std::string> used = doc["extensionsUsed"].get<std::set<std::string>>();
  EXPECT_EQ(used, (std::set<std::string>{"KHR_lights_punctual", "KHR_materials_emissive_strength"}));
  EXPECT_FALSE(doc.contains("extensionsRequired"));
  EXPECT_EQ(doc["buffers"][0]["uri"], "c.bin");
  EXPECT_EQ(doc["buffers"][0]["byteLength"].get<uintmax_t>(), fs::file_size(dir + "/c.bin"));

  // 8 instances, 4 lights, 1 camera, all roots of scene 0.
  ASSERT_EQ(doc["nodes"].size(), 13u);
  EXPECT_EQ(doc["scenes"][0]["nodes"].size(), 13u);
  const json& floor = doc["nodes"][0];
  EXPECT_EQ(floor["name"], "floor");
  EXPECT_EQ(floor["extras"]["afterglow"]["lightmap"],
            (json{{"atlas", 3}, {"width", 512}, {"height", 256}}));
  EXPECT_FALSE(doc["nodes"][6].contains("extras"));  // defaults are not written
  EXPECT_EQ(doc["nodes"][1]["extras"]["afterglow"]["static"], false);
  EXPECT_EQ(doc["nodes"][3]["extras"]["afterglow"]["castShadows"], false);

  const json& prim = doc["meshes"][0]["primitives"][0];
  EXPECT_TRUE(prim["attributes"].contains("TEXCOORD_0"));
  EXPECT_TRUE(prim["attributes"].contains("TEXCOORD_1"));
  EXPECT_FALSE(doc["meshes"][1]["primitives"][0]["attributes"].contains("TEXCOORD_1"));
  const json& pos = doc["accessors"][prim["attributes"]["POSITION"].get<int>()];
  EXPECT_NEAR(pos["min"][0].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(pos["max"][0].get<double>(), 0.5528, 1e-7);
  EXPECT_NEAR(pos["max"][2].get<double>(), 0.5592, 1e-7);
  EXPECT_EQ(doc["accessors"][prim["indices"].get<int>()]["componentType"], 5123);

  const json& light = doc["materials"][3];
  EXPECT_EQ(light["name"], "light");
  EXPECT_EQ(light["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"], 17.0);
  EXPECT_EQ(light["emissiveFactor"][0], 1.0);
  EXPECT_FALSE(doc["materials"][0].contains("emissiveFactor"));
  // Floats are written as their shortest decimal form.
  EXPECT_EQ(doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"][0].get<double>(), 0.725);
}

TEST(GltfExport, GlbAndEmbeddedRoundTrips) {
  const Scene scene = decoratedCornellBox();
  const std::string dir = test::tempDir("export_glb");
  ASSERT_TRUE(saveGltf(scene, dir + "/box.glb").isOk());
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{"box.glb"}));
  Result<std::string> bytes = readFile(dir + "/box.glb");
  ASSERT_TRUE(bytes.isOk());
  EXPECT_EQ(bytes->substr(0, 4), "glTF");
  EXPECT_EQ(bytes->size() % 4, 0u);
  Result<Scene> glb = loadGltf(dir + "/box.glb");
  ASSERT_TRUE(glb.isOk()) << glb.message();
  expectSameGeometry(scene, glb.value());
  expectSameMaterials(scene, glb.value());
  expectSameInstances(scene, glb.value());
  EXPECT_EQ(glb->lights.size(), 4u);

  const std::string dir2 = test::tempDir("export_embedded");
  SaveOptions options;
  options.embedBuffers = true;
  ASSERT_TRUE(saveGltf(scene, dir2 + "/box.gltf", options).isOk());
  EXPECT_EQ(filesIn(dir2), (std::vector<std::string>{"box.gltf"}));
  Result<Scene> embedded = loadGltf(dir2 + "/box.gltf");
  ASSERT_TRUE(embedded.isOk()) << embedded.message();
  expectSameGeometry(scene, embedded.value());
}

TEST(GltfExport, LargeMeshUses32BitIndices) {
  FurnaceOptions options;
  options.subdivisions = 110;  // 6 * 111² = 73926 vertices, beyond 16-bit indices
  const Scene scene = makeFurnaceBox(options);
  const std::string dir = test::tempDir("export_large");
  ASSERT_TRUE(saveGltf(scene, dir + "/furnace.gltf").isOk());
  const json doc = readJson(dir + "/furnace.gltf");
  const int indices = doc["meshes"][0]["primitives"][0]["indices"];
  EXPECT_EQ(doc["accessors"][indices]["componentType"], 5125);
  Result<Scene> back = loadGltf(dir + "/furnace.gltf");
  ASSERT_TRUE(back.isOk()) << back.message();
  expectSameGeometry(scene, back.value());
  EXPECT_NEAR(back->materials[0].emission().x, 1.0f, 1e-6f);
  EXPECT_EQ(back->meshTriangleCount(), 6u * 110u * 110u * 2u);
}

TEST(GltfExport, FailedSaveLeavesNoFile) {
  const Scene scene = makeCornellBox();
  const std::string dir = test::tempDir("export_fail");
  // A folder that cannot exist: its parent is a regular file (works even when run as root).
  { std::ofstream(dir + "/blocker") << "x"; }
  Status s = saveGltf(scene, dir + "/blocker/out.gltf");
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.message().find("blocker/out"), std::string::npos) << s.message();
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{"blocker"}));

  // The .bin is written first and the .gltf fails: a folder squats on the .gltf's temporary
  // name (not empty, so cleaning up the temporaries cannot remove it). The .bin must not be
  // left behind either.
  const std::string squatter = ".out.gltf.tmp" + std::to_string(::getpid());
  fs::create_directory(dir + "/" + squatter);
  { std::ofstream(dir + "/" + squatter + "/keep") << "x"; }
  s = saveGltf(scene, dir + "/out.gltf");
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.message().find("out.gltf"), std::string::npos) << s.message();
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{squatter, "blocker"}));
}

TEST(GltfExport, InconsistentPrimitiveIsAnError) {
  Scene scene = makeCornellBox();
  scene.meshes[2].primitives[0].uv1.resize(3);
  const std::string dir = test::tempDir("export_bad");
  Status s = saveGltf(scene, dir + "/bad.gltf");
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.message().find("back_wall"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("TEXCOORD_1"), std::string::npos) << s.message();
  EXPECT_TRUE(filesIn(dir).empty());
}

TEST(GltfExport, TextureUrisAreRelativeToTheOutput) {
  const std::string dir = test::tempDir("export_textures");
  Scene scene = makeCornellBox();
  scene.sourcePath = dir + "/levels/source/level.gltf";
  Texture fileTex;
  fileTex.name = "bricks";
  fileTex.uri = "tex/my%20bricks.png";  // as written in the source glTF: URI-encoded
  Texture embedded;
  embedded.name = "from_glb";  // uri "" = embedded in the source: nothing to point at
  scene.textures = {fileTex, embedded, fileTex};
  scene.materials[0].baseColorTexture.texture = 0;
  scene.materials[0].baseColorTexture.hasTransform = true;
  scene.materials[0].baseColorTexture.scale = {2.0f, 3.0f};
  scene.materials[0].baseColorTexture.rotation = 0.5f;
  scene.materials[1].baseColorTexture.texture = 1;
  scene.materials[2].emissiveTexture.texture = 2;
  scene.materials[2].emissiveTexture.texCoord = 1;
  ASSERT_TRUE(saveGltf(scene, dir + "/levels/out/level.gltf").isOk());
  const json doc = readJson(dir + "/levels/out/level.gltf");
  // Both file textures share one image; the embedded one is dropped.
  ASSERT_EQ(doc["images"].size(), 1u);
  EXPECT_EQ(doc["images"][0]["uri"], "../source/tex/my%20bricks.png");
  ASSERT_EQ(doc["textures"].size(), 2u);
  const json& white = doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"];
  EXPECT_EQ(white["index"], 0);
  EXPECT_EQ(white["extensions"]["KHR_texture_transform"]["scale"], json::array({2.0, 3.0}));
  EXPECT_EQ(white["extensions"]["KHR_texture_transform"]["rotation"], 0.5);
  EXPECT_FALSE(white["extensions"]["KHR_texture_transform"].contains("offset"));
  EXPECT_FALSE(doc["materials"][1]["pbrMetallicRoughness"].contains("baseColorTexture"));
  EXPECT_EQ(doc["materials"][2]["emissiveTexture"], (json{{"index", 1}, {"texCoord", 1}}));
  EXPECT_EQ(doc["extensionsRequired"], json::array({"KHR_texture_transform"}));
}

// KHR_materials_specular and KHR_materials_ior survive load -> save -> load, factors and
// textures (with their transforms and colour spaces), and are listed in extensionsUsed only.
TEST(GltfExport, SpecularAndIorRoundTrip) {
  const std::string dir = test::tempDir("export_specular");
  fs::create_directories(dir + "/in");
  {
    // A 1×1 RGBA PNG: the strength in A, the colour in RGB (OpenImageIO takes associated alpha:
    // 204, 128, 0 at alpha 0.8 read back as 1, 0.50196, 0).
    auto out = OIIO::ImageOutput::create(dir + "/in/spec.png");
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(1, 1, 4, OIIO::TypeDesc::UINT8);
    ASSERT_TRUE(out->open(dir + "/in/spec.png", spec));
    const uint8_t px[4] = {204, 128, 0, 204};
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px));
    out->close();
  }
  Scene source = makeFurnaceBox();
  source.materials.push_back(source.materials[0]);
  source.materials[1].name = "plain";
  ASSERT_TRUE(saveGltf(source, dir + "/in/level.gltf").isOk());
  json doc = readJson(dir + "/in/level.gltf");
  doc["images"] = json::array({{{"uri", "spec.png"}}});
  doc["textures"] = json::array({{{"source", 0}}});
  doc["materials"][0]["extensions"]["KHR_materials_ior"] = {{"ior", 1.45}};
  doc["materials"][0]["extensions"]["KHR_materials_specular"] = {
      {"specularFactor", 0.5},
      {"specularTexture", {{"index", 0}}},
      {"specularColorFactor", {1.5, 1.0, 0.25}},
      {"specularColorTexture",
       {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"scale", {2, 2}}}}}}}}};
  doc["extensionsUsed"] = {"KHR_materials_ior", "KHR_materials_specular", "KHR_texture_transform"};
  {
    std::ofstream out(dir + "/in/level.gltf", std::ios::binary | std::ios::trunc);
    out << doc.dump(1);
  }
  Result<Scene> a = loadGltf(dir + "/in/level.gltf");
  ASSERT_TRUE(a) << a.message();
  for (const std::string& w : a->warnings) ADD_FAILURE() << w;
  const Material& m = a->materials[0];
  EXPECT_FLOAT_EQ(m.ior, 1.45f);
  EXPECT_FLOAT_EQ(m.specularFactor, 0.5f);
  EXPECT_EQ(m.specularColorFactor, glm::vec3(1.5f, 1.0f, 0.25f));
  ASSERT_TRUE(m.specularTexture.valid());
  ASSERT_TRUE(m.specularColorTexture.valid());
  EXPECT_NEAR(a->textures[size_t(m.specularTexture.texture)].texels[0].a, 0.8f, 1e-6f);
  EXPECT_NEAR(a->textures[size_t(m.specularColorTexture.texture)].texels[0].g, 0.21586f, 2e-4f);

  ASSERT_TRUE(saveGltf(*a, dir + "/out/level.gltf").isOk());
  const json written = readJson(dir + "/out/level.gltf");
  const std::set<std::string> used = written["extensionsUsed"].get<std::set<std::string>>();
  EXPECT_TRUE(used.count("KHR_materials_ior"));
  EXPECT_TRUE(used.count("KHR_materials_specular"));
  // Only the texture transform is required (a scale of 2 moves the texture).
  EXPECT_EQ(written["extensionsRequired"], json::array({"KHR_texture_transform"}));
  const json& ext = written["materials"][0]["extensions"];
  EXPECT_EQ(ext["KHR_materials_ior"]["ior"], 1.45);
  EXPECT_EQ(ext["KHR_materials_specular"]["specularFactor"], 0.5);
  EXPECT_EQ(ext["KHR_materials_specular"]["specularColorFactor"], json::array({1.5, 1.0, 0.25}));
  EXPECT_TRUE(ext["KHR_materials_specular"].contains("specularTexture"));
  EXPECT_EQ(ext["KHR_materials_specular"]["specularColorTexture"]["extensions"]
               ["KHR_texture_transform"]["scale"],
            json::array({2.0, 2.0}));
  // Defaults are not written.
  EXPECT_FALSE(written["materials"][1].contains("extensions"));

  Result<Scene> b = loadGltf(dir + "/out/level.gltf");
  ASSERT_TRUE(b) << b.message();
  for (const std::string& w : b->warnings) ADD_FAILURE() << w;
  expectSameMaterials(*a, *b);
  const Material& n = b->materials[0];
  EXPECT_EQ(n.specularColorTexture.scale, glm::vec2(2.0f));
  const Texture& strength = b->textures[size_t(n.specularTexture.texture)];
  const Texture& colour = b->textures[size_t(n.specularColorTexture.texture)];
  EXPECT_FALSE(strength.srgb);
  EXPECT_TRUE(colour.srgb);
  EXPECT_NEAR(strength.texels[0].a, 0.8f, 1e-6f);
  EXPECT_NEAR(colour.texels[0].g, 0.21586f, 2e-4f);
  EXPECT_EQ(b->materials[1].ior, 1.5f);
  EXPECT_EQ(b->materials[1].specularFactor, 1.0f);
}

TEST(GltfExport, SponzaRoundTrip) {
  AG_REQUIRE_SHARED_SCENE(path, "sponza/Sponza.gltf");
  LoadOptions options;
  options.loadTextures = false;
  Result<Scene> original = loadGltf(path, options);
  ASSERT_TRUE(original.isOk()) << original.message();
  EXPECT_EQ(original->meshes.size(), 44u);
  const std::string dir = test::tempDir("export_sponza");
  Status s = saveGltf(original.value(), dir + "/sponza.gltf");
  ASSERT_TRUE(s.isOk()) << s.message();
  Result<Scene> back = loadGltf(dir + "/sponza.gltf", options);
  ASSERT_TRUE(back.isOk()) << back.message();
  EXPECT_EQ(back->meshes.size(), 44u);
  EXPECT_EQ(back->instances.size(), 170u);
  EXPECT_EQ(back->instancedTriangleCount(), 262087u);
  EXPECT_EQ(back->meshTriangleCount(), original->meshTriangleCount());
  expectSameMaterials(original.value(), back.value());
  // Texture URIs now point back into the shared folder and still name existing files.
  const json doc = readJson(dir + "/sponza.gltf");
  ASSERT_TRUE(doc.contains("images"));
  for (const json& image : doc["images"]) {
    const std::string uri = image["uri"];
    EXPECT_TRUE(fs::exists(fs::path(dir) / uri)) << uri;
  }
  std::set<std::string> names, backNames;
  for (const Texture& t : original->textures) names.insert(fs::path(t.uri).filename().string());
  for (const Texture& t : back->textures) backNames.insert(fs::path(t.uri).filename().string());
  EXPECT_EQ(names, backNames);
}

TEST(GltfExport, MixedLightingKeepsUv1AndTextureTransforms) {
  AG_REQUIRE_SHARED_SCENE(path, "mixed_lighting_bevy/MixedLightingExample.gltf");
  LoadOptions options;
  options.loadTextures = false;
  Result<Scene> original = loadGltf(path, options);
  ASSERT_TRUE(original.isOk()) << original.message();
  const std::string dir = test::tempDir("export_mixed");
  Status s = saveGltf(original.value(), dir + "/mixed.glb");
  ASSERT_TRUE(s.isOk()) << s.message();
  Result<Scene> back = loadGltf(dir + "/mixed.glb", options);
  ASSERT_TRUE(back.isOk()) << back.message();
  expectSameGeometry(original.value(), back.value());
  expectSameMaterials(original.value(), back.value());
  expectSameInstances(original.value(), back.value());
  EXPECT_EQ(back->lights.size(), original->lights.size());

  size_t withUv1 = 0;
  for (const Mesh& m : back->meshes)
    for (const Primitive& p : m.primitives) withUv1 += p.uv1.empty() ? 0 : 1;
  EXPECT_GT(withUv1, 0u);

  size_t transforms = 0;
  auto sameRef = [&](const TextureRef& a, const TextureRef& b, const Scene& sa, const Scene& sb,
                     const std::string& what) {
    ASSERT_EQ(a.valid(), b.valid()) << what;
    if (!a.valid()) return;
    EXPECT_EQ(fs::path(sa.textures[size_t(a.texture)].uri).filename(),
              fs::path(sb.textures[size_t(b.texture)].uri).filename())
        << what;
    EXPECT_EQ(a.texCoord, b.texCoord) << what;
    EXPECT_EQ(a.hasTransform, b.hasTransform) << what;
    EXPECT_EQ(a.offset, b.offset) << what;
    EXPECT_EQ(a.scale, b.scale) << what;
    EXPECT_EQ(a.rotation, b.rotation) << what;
    transforms += a.hasTransform ? 1 : 0;
  };
  for (size_t i = 0; i < original->materials.size(); ++i) {
    const Material& a = original->materials[i];
    const Material& b = back->materials[i];
    sameRef(a.baseColorTexture, b.baseColorTexture, *original, *back, a.name + " base");
    sameRef(a.metallicRoughnessTexture, b.metallicRoughnessTexture, *original, *back,
            a.name + " mr");
    sameRef(a.normalTexture, b.normalTexture, *original, *back, a.name + " normal");
    sameRef(a.occlusionTexture, b.occlusionTexture, *original, *back, a.name + " occlusion");
    sameRef(a.emissiveTexture, b.emissiveTexture, *original, *back, a.name + " emissive");
  }
  EXPECT_GE(transforms, 3u);  // wood base colour and metallic-roughness, fabric normal
}

}  // namespace
}  // namespace afterglow::scenes
