// The procedural scenes against the numbers they are built from: Cornell's published
// measurements and the furnace box's closed-cube invariants.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <tuple>

#include "afterglow/scenes/procedural.h"

namespace afterglow::scenes {
namespace {

const Instance* findInstance(const Scene& scene, const std::string& name) {
  for (const Instance& inst : scene.instances)
    if (inst.name == name) return &inst;
  return nullptr;
}

double meshArea(const Mesh& mesh) {
  double area = 0.0;
  for (const Primitive& p : mesh.primitives)
    for (size_t t = 0; t < p.triangleCount(); ++t) {
      const glm::dvec3 a = p.positions[p.indices[3 * t]], b = p.positions[p.indices[3 * t + 1]],
                       c = p.positions[p.indices[3 * t + 2]];
      area += 0.5 * glm::length(glm::cross(b - a, c - a));
    }
  return area;
}

// Area of a planar quad given in millimetres (the data page's numbers), in square metres.
double quadAreaMm(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d) {
  return 0.5e-6 * (glm::length(glm::cross(b - a, c - a)) + glm::length(glm::cross(c - a, d - a)));
}

TEST(CornellBox, NamesMeshesAndMaterials) {
  const Scene scene = makeCornellBox();
  EXPECT_EQ(scene.sourcePath, "");
  const char* names[] = {"floor",      "ceiling",     "back_wall",  "left_wall",
                         "right_wall", "short_block", "tall_block", "light"};
  ASSERT_EQ(scene.instances.size(), 8u);
  ASSERT_EQ(scene.meshes.size(), 8u);
  for (const char* name : names) {
    const Instance* inst = findInstance(scene, name);
    ASSERT_NE(inst, nullptr) << name;
    EXPECT_EQ(scene.meshes[size_t(inst->mesh)].name, name);
    EXPECT_EQ(inst->transform, glm::mat4(1.0f));
  }
  // 5 walls and the light are one quad each; each block has a top and four sides.
  EXPECT_EQ(scene.meshTriangleCount(), 6u * 2u + 2u * 5u * 2u);
  ASSERT_EQ(scene.materials.size(), 4u);
  for (const Material& m : scene.materials) {
    EXPECT_FALSE(m.name.empty());
    EXPECT_FALSE(m.doubleSided) << m.name;
  }
  auto materialOf = [&](const char* name) {
    return scene.material(scene.meshes[size_t(findInstance(scene, name)->mesh)].primitives[0].material);
  };
  EXPECT_EQ(glm::vec3(materialOf("floor").baseColorFactor), glm::vec3(0.725f, 0.71f, 0.68f));
  EXPECT_EQ(glm::vec3(materialOf("left_wall").baseColorFactor), glm::vec3(0.63f, 0.065f, 0.05f));
  EXPECT_EQ(glm::vec3(materialOf("right_wall").baseColorFactor), glm::vec3(0.14f, 0.45f, 0.091f));
  const Material& light = materialOf("light");
  EXPECT_EQ(light.name, "light");
  EXPECT_FLOAT_EQ(light.emissiveStrength, 17.0f);
  EXPECT_FLOAT_EQ(light.emissiveFactor.x, 1.0f);
  EXPECT_NEAR(light.emission().x, 17.0f, 1e-5);
  EXPECT_NEAR(light.emission().y, 12.0f, 1e-5);
  EXPECT_NEAR(light.emission().z, 4.0f, 1e-5);
  for (const char* name : names)
    if (std::string(name) != "light") {
      EXPECT_FALSE(materialOf(name).emissive()) << name;
    }
}

TEST(CornellBox, BoundsAreThePublishedRoomSize) {
  const Scene scene = makeCornellBox();
  const Bounds b = scene.bounds();
  EXPECT_NEAR(b.min.x, 0.0, 1e-7);
  EXPECT_NEAR(b.min.y, 0.0, 1e-7);
  EXPECT_NEAR(b.min.z, 0.0, 1e-7);
  EXPECT_NEAR(b.max.x, 0.556, 1e-6);
  EXPECT_NEAR(b.max.y, 0.5488, 1e-6);
  EXPECT_NEAR(b.max.z, 0.5592, 1e-6);
}

TEST(CornellBox, SurfaceAreasMatchTheMeasurements) {
  const Scene scene = makeCornellBox();
  auto area = [&](const char* name) {
    return meshArea(scene.meshes[size_t(findInstance(scene, name)->mesh)]);
  };
  // Floor and back wall are trapezoids (552.8/549.6 and 549.6/556 mm wide edges).
  EXPECT_NEAR(area("floor"), (552.8 + 549.6) / 2 * 559.2 * 1e-6, 1e-7);
  EXPECT_NEAR(area("ceiling"), 556.0 * 559.2 * 1e-6, 1e-7);
  EXPECT_NEAR(area("back_wall"), (549.6 + 556.0) / 2 * 548.8 * 1e-6, 1e-7);
  EXPECT_NEAR(area("right_wall"), 559.2 * 548.8 * 1e-6, 1e-7);
  // The left wall leans (552.8 -> 556 at the top, 549.6 -> 556 at the back): not a rectangle,
  // split along the 0-2 diagonal like the mesh.
  EXPECT_NEAR(area("left_wall"),
              quadAreaMm({552.8, 0, 0}, {549.6, 0, 559.2}, {556, 548.8, 559.2}, {556, 548.8, 0}),
              1e-7);
  EXPECT_NEAR(area("light"), 0.130 * 0.105, 1e-8);
  // Short block: a 165 mm high prism over the top quad; its sides are vertical rectangles.
  const double shortTop =
      quadAreaMm({130, 165, 65}, {82, 165, 225}, {240, 165, 272}, {290, 165, 114});
  const double shortPerimeter = glm::length(glm::dvec2(130 - 82, 65 - 225)) +
                                glm::length(glm::dvec2(82 - 240, 225 - 272)) +
                                glm::length(glm::dvec2(240 - 290, 272 - 114)) +
                                glm::length(glm::dvec2(290 - 130, 114 - 65));
  EXPECT_NEAR(area("short_block"), shortTop + shortPerimeter * 165.0 * 1e-6, 1e-7);
  const double tallTop =
      quadAreaMm({423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406});
  const double tallPerimeter = glm::length(glm::dvec2(423 - 265, 247 - 296)) +
                               glm::length(glm::dvec2(265 - 314, 296 - 456)) +
                               glm::length(glm::dvec2(314 - 472, 456 - 406)) +
                               glm::length(glm::dvec2(472 - 423, 406 - 247));
  EXPECT_NEAR(area("tall_block"), tallTop + tallPerimeter * 330.0 * 1e-6, 1e-7);
}

TEST(CornellBox, NormalsFaceTheInteriorAndAgreeWithWinding) {
  const Scene scene = makeCornellBox();
  const Bounds room = scene.bounds();
  size_t triangles = 0;
  for (const Instance& inst : scene.instances) {
    const Mesh& mesh = scene.meshes[size_t(inst.mesh)];
    for (const Primitive& p : mesh.primitives) {
      ASSERT_EQ(p.normals.size(), p.positions.size());
      for (size_t t = 0; t < p.triangleCount(); ++t, ++triangles) {
        const uint32_t* idx = &p.indices[3 * t];
        const glm::vec3 a = p.positions[idx[0]], b = p.positions[idx[1]], c = p.positions[idx[2]];
        const glm::vec3 geometric = glm::normalize(glm::cross(b - a, c - a));
        for (int k = 0; k < 3; ++k) {
          EXPECT_NEAR(glm::length(p.normals[idx[k]]), 1.0f, 1e-5);
          // Counter-clockwise winding and the stored normal agree (up to the few-mm lean of
          // the measured, slightly non-planar quads).
          EXPECT_GT(glm::dot(geometric, p.normals[idx[k]]), 0.999f) << mesh.name << " tri " << t;
        }
        const glm::vec3 centroid = (a + b + c) / 3.0f;
        const glm::vec3 front = centroid + 1e-3f * geometric;
        EXPECT_TRUE(front.x > room.min.x && front.y > room.min.y && front.z > room.min.z &&
                    front.x < room.max.x && front.y < room.max.y && front.z < room.max.z)
            << mesh.name << " tri " << t;
      }
    }
  }
  EXPECT_EQ(triangles, 32u);
  // Specific directions: floor up, ceiling and light down, back wall towards the camera (-Z),
  // red wall (+X side) towards -X, green wall (x = 0) towards +X.
  auto normalOf = [&](const char* name) {
    return scene.meshes[size_t(findInstance(scene, name)->mesh)].primitives[0].normals[0];
  };
  EXPECT_GT(normalOf("floor").y, 0.999f);
  EXPECT_LT(normalOf("ceiling").y, -0.999f);
  EXPECT_LT(normalOf("light").y, -0.999f);
  EXPECT_LT(normalOf("back_wall").z, -0.999f);
  EXPECT_LT(normalOf("left_wall").x, -0.999f);
  EXPECT_GT(normalOf("right_wall").x, 0.999f);
}

TEST(CornellBox, LightSitsJustBelowTheCeilingCentre) {
  const Scene scene = makeCornellBox();
  const Primitive& p = scene.meshes[size_t(findInstance(scene, "light")->mesh)].primitives[0];
  Bounds b;
  for (const glm::vec3& q : p.positions) b.extend(q);
  EXPECT_NEAR(b.size().x, 0.130, 1e-6);
  EXPECT_NEAR(b.size().z, 0.105, 1e-6);
  EXPECT_EQ(b.min.y, b.max.y);
  EXPECT_LT(b.max.y, 0.5488f);
  EXPECT_GT(b.max.y, 0.5488f - 0.002f);
  EXPECT_NEAR((b.min.x + b.max.x) / 2, 0.278, 1e-6);
  EXPECT_NEAR((b.min.z + b.max.z) / 2, 0.2795, 1e-6);
}

TEST(CornellBox, ClassicCamera) {
  const Scene scene = makeCornellBox();
  ASSERT_EQ(scene.cameras.size(), 1u);
  const Camera& cam = scene.cameras[0];
  EXPECT_EQ(cam.name, "Camera");
  EXPECT_NEAR(cam.yfov, 0.6860, 1e-4);
  const glm::vec3 eye(cam.transform[3]);
  EXPECT_NEAR(eye.x, 0.278, 1e-6);
  EXPECT_NEAR(eye.y, 0.273, 1e-6);
  EXPECT_NEAR(eye.z, -0.8, 1e-6);
  const glm::vec3 forward = -glm::vec3(cam.transform[2]);  // glTF cameras look down -Z
  EXPECT_NEAR(forward.z, 1.0, 1e-6);
  const glm::vec3 up(cam.transform[1]);
  EXPECT_NEAR(up.y, 1.0, 1e-6);
  // The red wall must be on the screen's left: camera right (+X) points to world -X.
  EXPECT_NEAR(cam.transform[0].x, -1.0, 1e-6);
}

// Edge key by exact positions: the furnace box duplicates vertices along cube edges.
using PointKey = std::tuple<float, float, float>;
PointKey key(glm::vec3 p) { return {p.x, p.y, p.z}; }

TEST(FurnaceBox, WatertightInwardAndSized) {
  FurnaceOptions options;
  options.size = 2.5f;
  options.subdivisions = 3;
  options.albedo = glm::vec3(0.8f, 0.5f, 0.25f);
  options.emission = glm::vec3(3.0f, 1.5f, 0.0f);
  const Scene scene = makeFurnaceBox(options);
  EXPECT_EQ(scene.sourcePath, "");
  ASSERT_EQ(scene.instances.size(), 1u);
  EXPECT_FALSE(scene.instances[0].name.empty());
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_FALSE(scene.meshes[0].name.empty());
  EXPECT_EQ(scene.meshTriangleCount(), 6u * 3u * 3u * 2u);

  std::map<std::pair<PointKey, PointKey>, int> directed;
  double area = 0.0;
  for (const Primitive& p : scene.meshes[0].primitives) {
    for (size_t t = 0; t < p.triangleCount(); ++t) {
      const uint32_t* idx = &p.indices[3 * t];
      const glm::vec3 v[3] = {p.positions[idx[0]], p.positions[idx[1]], p.positions[idx[2]]};
      const glm::vec3 cr = glm::cross(v[1] - v[0], v[2] - v[0]);
      area += 0.5 * glm::length(glm::dvec3(cr));
      const glm::vec3 centroid = (v[0] + v[1] + v[2]) / 3.0f;
      // Winding and stored normals both point at the cube's centre (the origin).
      EXPECT_LT(glm::dot(cr, centroid), 0.0f);
      for (int k = 0; k < 3; ++k) {
        EXPECT_GT(glm::dot(p.normals[idx[k]], glm::normalize(cr)), 0.9999f);
        ++directed[{key(v[k]), key(v[(k + 1) % 3])}];
      }
    }
  }
  EXPECT_NEAR(area, 6.0 * 2.5 * 2.5, 1e-4);
  // Closed and consistently oriented: every directed edge appears once, and its reverse once.
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    auto reverse = directed.find({edge.second, edge.first});
    ASSERT_NE(reverse, directed.end());
    EXPECT_EQ(reverse->second, 1);
  }
  const Bounds b = scene.bounds();
  EXPECT_NEAR(b.size().x, 2.5, 1e-6);
  EXPECT_NEAR(b.size().y, 2.5, 1e-6);
  EXPECT_NEAR(b.size().z, 2.5, 1e-6);

  ASSERT_EQ(scene.materials.size(), 1u);
  const Material& m = scene.materials[0];
  EXPECT_FALSE(m.doubleSided);
  EXPECT_FALSE(m.name.empty());
  EXPECT_EQ(glm::vec3(m.baseColorFactor), options.albedo);
  EXPECT_FLOAT_EQ(std::max(m.emissiveFactor.x, std::max(m.emissiveFactor.y, m.emissiveFactor.z)),
                  1.0f);
  EXPECT_NEAR(m.emission().x, 3.0f, 1e-6);
  EXPECT_NEAR(m.emission().y, 1.5f, 1e-6);
  EXPECT_NEAR(m.emission().z, 0.0f, 1e-6);
  for (const Primitive& p : scene.meshes[0].primitives) EXPECT_EQ(p.material, 0);
}

TEST(FurnaceBox, DefaultsAndNoEmission) {
  const Scene defaults = makeFurnaceBox();
  EXPECT_EQ(defaults.meshTriangleCount(), 6u * 4u * 4u * 2u);
  EXPECT_EQ(defaults.materials[0].emission(), glm::vec3(1.0f));
  FurnaceOptions dark;
  dark.emission = glm::vec3(0.0f);
  dark.subdivisions = 1;
  const Scene scene = makeFurnaceBox(dark);
  EXPECT_EQ(scene.meshTriangleCount(), 12u);
  EXPECT_FALSE(scene.materials[0].emissive());
  EXPECT_EQ(scene.materials[0].emissiveStrength, 1.0f);
}

}  // namespace
}  // namespace afterglow::scenes
