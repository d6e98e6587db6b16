// Normal textures as glTF defines them, where `afterglow render` tilts the directional
// lightmaps' normals (scenes/material_eval.h): tangent space +X along increasing u, +Y up the
// image (against v: glTF's v grows downwards), +Z the surface normal; x and y scaled by the
// texture's scale.
#include <gtest/gtest.h>

#include <cmath>

#include "afterglow/scenes/material_eval.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::scenes {
namespace {

// A 2 × 2 m quad in the z = 0 plane facing +z, its texture's top row (v = 0) at +y and u along
// +x (or along -x when `mirrored`), with a one-texel normal texture of this colour.
Scene quadWithNormalTexture(glm::vec3 rgb, float scale, bool mirrored) {
  Scene scene;
  Texture texture;
  texture.width = texture.height = 1;
  texture.texels = {glm::vec4(rgb, 1.0f)};
  scene.textures.push_back(texture);
  Material m;
  m.normalTexture.texture = 0;
  m.normalScale = scale;
  scene.materials.push_back(m);
  Primitive p;
  p.material = 0;
  p.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  p.normals.assign(4, glm::vec3(0, 0, 1));
  const float u0 = mirrored ? 1.0f : 0.0f, u1 = 1.0f - u0;
  p.uv0 = {{u0, 1}, {u1, 1}, {u1, 0}, {u0, 0}};
  p.indices = {0, 1, 2, 0, 2, 3};
  Mesh mesh;
  mesh.primitives.push_back(p);
  scene.meshes.push_back(mesh);
  Instance inst;
  inst.mesh = 0;
  scene.instances.push_back(inst);
  return scene;
}

glm::vec3 mappedNormal(const Scene& scene, uint32_t triangle) {
  const glm::vec3 n(0, 0, 1);
  glm::vec3 t, b;
  EXPECT_TRUE(triangleTangents(scene, 0, 0, triangle, n, &t, &b));
  return normalMapped(scene, 0, glm::vec2(0.5f), n, t, b);
}

TEST(NormalMaps, TangentSpaceFollowsTheTexturesUAndItsUpwardImage) {
  // (0.5, 0.75, 0.75): tilted up the image by atan(0.5 / 0.5) = 45 degrees.
  const glm::vec3 up(0.5f, 0.75f, 0.75f), right(0.75f, 0.5f, 0.75f);
  for (uint32_t triangle : {0u, 1u}) {
    const glm::vec3 n = mappedNormal(quadWithNormalTexture(up, 1.0f, false), triangle);
    EXPECT_NEAR(n.x, 0.0f, 1e-5f);
    EXPECT_NEAR(n.y, std::sqrt(0.5f), 1e-5f) << "the image's top lies at +y";
    EXPECT_NEAR(n.z, std::sqrt(0.5f), 1e-5f);
    const glm::vec3 r = mappedNormal(quadWithNormalTexture(right, 1.0f, false), triangle);
    EXPECT_NEAR(r.x, std::sqrt(0.5f), 1e-5f) << "u grows along +x";
    // Mirrored UVs (u along -x): +X of the texture turns with them, +Y stays up the image.
    const glm::vec3 m = mappedNormal(quadWithNormalTexture(right, 1.0f, true), triangle);
    EXPECT_NEAR(m.x, -std::sqrt(0.5f), 1e-5f);
    const glm::vec3 mu = mappedNormal(quadWithNormalTexture(up, 1.0f, true), triangle);
    EXPECT_NEAR(mu.y, std::sqrt(0.5f), 1e-5f);
  }
  // The scale multiplies x and y: half the tilt's tangent.
  const glm::vec3 half = mappedNormal(quadWithNormalTexture(up, 0.5f, false), 0);
  EXPECT_NEAR(half.y / half.z, 0.5f, 1e-5f);
  // No normal texture: the normal itself.
  Scene plain = quadWithNormalTexture(up, 1.0f, false);
  plain.materials[0].normalTexture.texture = -1;
  EXPECT_EQ(mappedNormal(plain, 0), glm::vec3(0, 0, 1));
}

}  // namespace
}  // namespace afterglow::scenes
