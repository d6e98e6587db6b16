// Directional lightmaps (issue 29, runtime/directional.h): a wall lit by bounced light from one
// side (a sunlit floor in front of it, below) is evaluated at perturbed normals, as a normal map
// would tilt them, against the reference path tracer's irradiance for those normals. The flat
// lightmap gives every normal the same light; the gradient follows where the light comes from.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/runtime/directional.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/uv/indirect.h"
#include "bake_fixtures.h"

namespace afterglow::baker {
namespace {

// A 4 × 4 m sunlit floor (albedo 0.8) and, along its far edge, a black wall 2 m high facing
// it under a black awning 1.2 m deep: the sun (straight down) reaches neither the wall nor any
// normal tilted off it, so all the wall's light is the floor's, from below and in front.
scenes::Scene wallOverASunlitFloor() {
  scenes::Scene scene = groundQuad("floor", 2.0f, 0.8f, 0.0f);
  scenes::Material black;
  black.name = "wall";
  black.baseColorFactor = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
  black.metallicFactor = 0.0f;
  scene.materials.push_back(black);
  scenes::Primitive prim;
  prim.material = 1;
  addQuad(prim, {-2, 0, -2}, {2, 0, -2}, {2, 2, -2}, {-2, 2, -2}, {0, 0, 1});
  // A black awning over it, facing down: no normal a normal map tilts up sees the sun.
  addQuad(prim, {-2, 2, -2}, {2, 2, -2}, {2, 2, -0.8f}, {-2, 2, -0.8f}, {0, -1, 0});
  scenes::Mesh mesh;
  mesh.name = "wall";
  mesh.primitives.push_back(prim);
  scene.meshes.push_back(mesh);
  scenes::Instance inst;
  inst.name = "wall";
  inst.mesh = 1;
  scene.instances.push_back(inst);
  scene.lights.push_back(hardSun({0.0f, -1.0f, 0.0f}));
  return scene;
}

// n turned by `angle` radians about `axis`.
glm::vec3 turned(glm::vec3 n, glm::vec3 axis, float angle) {
  return glm::normalize(n * std::cos(angle) + glm::cross(axis, n) * std::sin(angle) +
                        axis * glm::dot(axis, n) * (1.0f - std::cos(angle)));
}

struct Errors {
  double flat = 0.0, directional = 0.0;
};

// The wall's texels away from its edges at normals tilted up, down and sideways by 20 and 35
// degrees: relative RMSE of the flat lightmap and of the directional one against the reference.
Errors compare(const scenes::Scene& scene, const BakeResult& b,
               const std::vector<runtime::LightGradient>& gradient) {
  std::vector<glm::vec3> points, normals, flat, directional;
  const glm::vec3 axes[] = {{1, 0, 0}, {0, 1, 0}};
  const float angles[] = {-0.61f, -0.35f, 0.35f, 0.61f};
  for (uint32_t t = 0; t < b.texels.size(); t += 3) {
    const glm::vec3 p = b.texels.position[t];
    if (!b.texels.valid[t] || b.texels.instance[t] != 1 || std::abs(p.x) > 1.5f || p.y < 0.3f ||
        p.y > 1.7f)
      continue;
    const glm::vec3 n0 = b.texels.normal[t];
    const glm::vec3 value = b.texelIndirect[t] + b.texelDirect[t];
    for (glm::vec3 axis : axes)
      for (float angle : angles) {
        const glm::vec3 n = turned(n0, axis, angle);
        points.push_back(p);
        normals.push_back(n);
        flat.push_back(value);
        directional.push_back(runtime::shadeDirectional(value, gradient[t], n, n0));
      }
  }
  EXPECT_GT(points.size(), 400u);
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  EXPECT_TRUE(tracer) << tracer.message();
  if (!tracer) return {};
  ReferenceOptions options;
  options.samples = 2048;
  Result<ReferencePoints> ref =
      referenceIrradiance(scene, *tracer.value(), Environment{}, points, normals, options);
  EXPECT_TRUE(ref) << ref.message();
  if (!ref) return {};
  double mean = 0.0;
  for (const glm::vec3& r : ref->irradiance) mean += r.x;
  mean /= double(points.size());
  Errors e;
  for (size_t i = 0; i < points.size(); ++i) {
    const double want = std::max(double(ref->irradiance[i].x), 0.1 * mean);
    e.flat += std::pow((flat[i].x - ref->irradiance[i].x) / want, 2.0);
    e.directional += std::pow((directional[i].x - ref->irradiance[i].x) / want, 2.0);
  }
  e.flat = std::sqrt(e.flat / double(points.size()));
  e.directional = std::sqrt(e.directional / double(points.size()));
  return e;
}

void check(bool grid) {
  scenes::Scene scene = wallOverASunlitFloor();
  unwrapAt(scene, grid ? 16.0f : 8.0f);
  if (grid) {
    uv::clearIndirect(scene);
    Result<uv::IndirectLayout> packed = uv::packIndirect(scene, 4.0f);
    ASSERT_TRUE(packed) << packed.message();
  }
  BakeOptions options = draftOptions();
  options.links.texelRays = 128;
  const BakeResult b = bakeOrDie(scene, options);
  ASSERT_EQ(b.transport.lightmap.active(), grid);
  ASSERT_TRUE(b.transport.hasDirections());
  runtime::Solver solver(b.transport);
  solver.solve();
  runtime::DirectionalLight directional(b.transport);
  std::vector<runtime::LightGradient> gradient(b.transport.texelCount);
  directional.texels(solver, gradient.data());
  if (grid) {
    std::vector<runtime::LightGradient> fine(b.transport.lightmap.texelCount);
    directional.upsample(gradient.data(), fine.data());
    gradient.swap(fine);
  }
  const Errors e = compare(scene, b, gradient);
  std::printf("%s: at normals tilted 20 and 35 degrees, relative RMSE flat %.1f%%, directional "
              "%.1f%%\n", grid ? "two resolutions (16 / 4 texels/m)" : "one resolution (8 texels/m)",
              100.0 * e.flat, 100.0 * e.directional);
  EXPECT_LE(e.directional, 0.10);
  EXPECT_GE(e.flat, 2.0 * e.directional);
}

TEST(Directional, TiltedNormalsOnAWallLitFromBelowFollowTheReference) { check(false); }

TEST(Directional, TiltedNormalsFollowTheReferenceWithTwoResolutions) { check(true); }

}  // namespace
}  // namespace afterglow::baker
