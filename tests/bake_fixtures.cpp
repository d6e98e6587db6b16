#include "bake_fixtures.h"

#include <cstdio>
#include <fstream>

#include <gtest/gtest.h>

#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/uv/indirect.h"
#include "afterglow/bakefiles/pipeline.h"
#include "afterglow/trace/raytracer.h"
#include "test_util.h"

namespace afterglow::baker {

BakeOptions draftOptions() {
  BakeOptions o;
  o.links.texelRays = 32;
  o.links.clusterRays = 128;
  o.direct.lightSamples = 4;
  o.direct.emissiveSamples = 16;
  return o;
}

void unwrapAt(scenes::Scene& scene, float texelsPerUnit) {
  bakefiles::BakeJob job;
  job.texelsPerUnit = texelsPerUnit;
  Result<bakefiles::UnwrapStep> r = bakefiles::unwrapForBake(scene, job);
  ASSERT_TRUE(r) << r.message();
}

size_t unwrapIntoAtlas(scenes::Scene& scene, int atlasSize) {
  bakefiles::BakeJob job;
  job.atlasSize = atlasSize;
  Result<bakefiles::UnwrapStep> r = bakefiles::unwrapForBake(scene, job);
  EXPECT_TRUE(r) << r.message();
  return r ? r->atlases : 0;
}

BakeResult bakeOrDie(const scenes::Scene& scene, const BakeOptions& options) {
  Result<BakeResult> r = bake(scene, options);
  EXPECT_TRUE(r) << r.message();
  return r ? std::move(r.value()) : BakeResult{};
}

ReferenceTexels referenceOrDie(const scenes::Scene& scene, const TexelSet& texels,
                               const Environment& environment, int samples,
                               const std::vector<uint32_t>& subset) {
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  EXPECT_TRUE(tracer) << tracer.message();
  if (!tracer) return {};
  ReferenceOptions options;
  options.samples = samples;
  Result<ReferenceTexels> ref =
      referenceTexels(scene, *tracer.value(), texels, environment, options, subset);
  EXPECT_TRUE(ref) << ref.message();
  return ref ? std::move(ref.value()) : ReferenceTexels{};
}

scenes::Light hardSun(glm::vec3 direction) {
  scenes::Light sun;
  sun.name = "sun";
  sun.type = scenes::LightType::Directional;
  sun.direction = glm::normalize(direction);
  sun.angularDiameter = 0.0f;
  return sun;
}

scenes::Scene floorUnderASlit(bool roof, float from, float width) {
  scenes::Scene scene = groundQuad("floor", 2.0f, 0.8f, 0.0f);
  if (roof) {
    addBox(scene, "roof_west", {-2.5f, 1.0f, -2.5f}, {from, 1.1f, 2.5f}, 0);
    addBox(scene, "roof_east", {from + width, 1.0f, -2.5f}, {2.5f, 1.1f, 2.5f}, 0);
  }
  scene.lights.push_back(hardSun({0.0f, -1.0f, 0.0f}));
  return scene;
}

scenes::Scene groundQuad(const std::string& name, float halfSize, float baseColor,
                         float specularFactor) {
  scenes::Scene scene;
  scenes::Material m;
  m.name = name;
  m.baseColorFactor = glm::vec4(glm::vec3(baseColor), 1.0f);
  m.metallicFactor = 0.0f;
  m.specularFactor = specularFactor;
  scene.materials.push_back(m);
  scenes::Primitive prim;
  prim.material = 0;
  const float h = halfSize;
  prim.positions = {{-h, 0, -h}, {h, 0, -h}, {h, 0, h}, {-h, 0, h}};
  prim.normals.assign(4, glm::vec3(0, 1, 0));
  prim.indices = {0, 2, 1, 0, 3, 2};
  scenes::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(prim);
  scene.meshes.push_back(mesh);
  scenes::Instance inst;
  inst.name = name;
  inst.mesh = 0;
  scene.instances.push_back(inst);
  return scene;
}

scenes::Scene lampLitCornell(scenes::Light lamp, glm::vec3 where, bool grid) {
  scenes::Scene scene = scenes::makeCornellBox();
  for (scenes::Material& m : scene.materials) m.emissiveFactor = glm::vec3(0.0f);
  const scenes::Bounds box = scene.bounds();
  lamp.position = box.min + (box.max - box.min) * where;
  scene.lights.push_back(lamp);
  unwrapAt(scene, 60.0f);
  uv::clearIndirect(scene);
  if (grid) {
    Result<uv::IndirectLayout> packed = uv::packIndirect(scene, 20.0f);
    EXPECT_TRUE(packed) << packed.message();
  }
  return scene;
}

void addQuad(scenes::Primitive& p, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 n) {
  const uint32_t base = uint32_t(p.positions.size());
  for (glm::vec3 v : {a, b, c, d}) {
    p.positions.push_back(v);
    p.normals.push_back(n);
  }
  for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) p.indices.push_back(base + i);
}

void addRoomWalls(scenes::Primitive& p, float half, float height) {
  const float s = half, h = height;
  addQuad(p, {-s, 0, -s}, {-s, h, -s}, {-s, h, s}, {-s, 0, s}, {1, 0, 0});
  addQuad(p, {s, 0, s}, {s, h, s}, {s, h, -s}, {s, 0, -s}, {-1, 0, 0});
  addQuad(p, {-s, 0, -s}, {s, 0, -s}, {s, h, -s}, {-s, h, -s}, {0, 0, 1});
  addQuad(p, {s, 0, s}, {-s, 0, s}, {-s, h, s}, {s, h, s}, {0, 0, -1});
}

scenes::Primitive box(glm::vec3 lo, glm::vec3 hi, int material) {
  scenes::Primitive p;
  p.material = material;
  // Faces counter-clockwise seen from outside.
  auto face = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 n) {
    addQuad(p, a, b, c, d, n);
  };
  const glm::vec3 l = lo, h = hi;
  face({h.x, l.y, h.z}, {h.x, l.y, l.z}, {h.x, h.y, l.z}, {h.x, h.y, h.z}, {1, 0, 0});
  face({l.x, l.y, l.z}, {l.x, l.y, h.z}, {l.x, h.y, h.z}, {l.x, h.y, l.z}, {-1, 0, 0});
  face({l.x, h.y, h.z}, {h.x, h.y, h.z}, {h.x, h.y, l.z}, {l.x, h.y, l.z}, {0, 1, 0});
  face({l.x, l.y, l.z}, {h.x, l.y, l.z}, {h.x, l.y, h.z}, {l.x, l.y, h.z}, {0, -1, 0});
  face({l.x, l.y, h.z}, {h.x, l.y, h.z}, {h.x, h.y, h.z}, {l.x, h.y, h.z}, {0, 0, 1});
  face({h.x, l.y, l.z}, {l.x, l.y, l.z}, {l.x, h.y, l.z}, {h.x, h.y, l.z}, {0, 0, -1});
  return p;
}

void addBox(scenes::Scene& scene, const std::string& name, glm::vec3 lo, glm::vec3 hi,
            int material) {
  scenes::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(box(lo, hi, material));
  scene.meshes.push_back(mesh);
  scenes::Instance inst;
  inst.name = name;
  inst.mesh = int(scene.meshes.size()) - 1;
  scene.instances.push_back(inst);
}

scenes::Scene furnaceLevel(const std::string& name, float baseColor, const nlohmann::json& specular) {
  scenes::FurnaceOptions f;
  f.albedo = glm::vec3(baseColor);
  f.emission = glm::vec3(1.0f);
  const std::string path = test::tempDir("furnace_level_" + name) + "/furnace.gltf";
  Status saved = scenes::saveGltf(scenes::makeFurnaceBox(f), path);
  EXPECT_TRUE(saved) << saved.message();
  nlohmann::json doc = nlohmann::json::parse(test::slurp(path));
  EXPECT_EQ(doc["materials"].size(), 1u);
  if (!specular.is_null()) {
    doc["materials"][0]["extensions"]["KHR_materials_specular"] = specular;
    doc["extensionsUsed"].push_back("KHR_materials_specular");
  }
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << doc.dump(1);
  }
  Result<scenes::Scene> loaded = scenes::loadGltf(path);
  EXPECT_TRUE(loaded) << loaded.message();
  if (!loaded) return {};
  scenes::Scene scene = std::move(loaded.value());
  for (const std::string& w : scene.warnings) ADD_FAILURE() << "warning: " << w;
  EXPECT_EQ(scene.materials.size(), 1u);
  unwrapAt(scene, 4.0f);
  return scene;
}

scenes::Scene cornellForAccuracy(const std::string& path) {
  Result<scenes::Scene> loaded = scenes::loadGltf(path);
  EXPECT_TRUE(loaded) << loaded.message();
  if (!loaded) return {};
  scenes::Scene scene = std::move(loaded.value());
  for (scenes::Material& m : scene.materials) m.singleSidedEmission = true;
  const size_t atlases = unwrapIntoAtlas(scene, 256);
  if (atlases == 0) return {};
  EXPECT_EQ(atlases, 1u);
  return scene;
}

void printComparison(const std::string& what, const ReferenceComparison& c) {
  std::printf("%s, %zu texels: total RMSE %.2f%% bias %+.2f%% (direct %.2f%% %+.2f%%, indirect "
              "%.2f%% %+.2f%%; reference noise %.2f%%)\n",
              what.c_str(), c.texels, 100.0 * c.total.relativeRmse, 100.0 * c.total.bias,
              100.0 * c.direct.relativeRmse, 100.0 * c.direct.bias,
              100.0 * c.indirect.relativeRmse, 100.0 * c.indirect.bias,
              100.0 * c.total.referenceNoise);
}

}  // namespace afterglow::baker
