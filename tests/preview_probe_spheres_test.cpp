// The probe spheres of `afterglow render --probe-spheres` (baker/probe_spheres.h), below the
// command line: the probes' spacing, which probes a handful of spheres go to, and the screen
// tiles that find a sphere for a pixel (checked against testing every sphere).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/preview/probe_spheres.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/preview/render.h"
#include "afterglow/core/parallel.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/procedural.h"

namespace afterglow::preview {
namespace {

// A grid of probes filling the Cornell box's room (0.556 × 0.549 × 0.559 m) `step` apart.
bakefiles::LightProbes cornellProbes(float step) {
  bakefiles::LightProbes probes;
  for (float z = step * 0.5f; z < 0.55f; z += step)
    for (float y = step * 0.5f; y < 0.54f; y += step)
      for (float x = step * 0.5f; x < 0.55f; x += step) probes.mesh.positions.push_back({x, y, z});
  Result<runtime::ProbeTetrahedra> mesh = probes::tetrahedralize(probes.mesh.positions);
  EXPECT_TRUE(mesh) << mesh.message();
  if (mesh) probes.mesh = mesh.value();
  // Every probe sees a constant 1: what is checked here is where spheres go, not their light.
  runtime::ShL2 one;
  runtime::constantSkySh(glm::vec3(1.0f), one.c);
  probes.sh.assign(probes.mesh.positions.size(), one);
  return probes;
}

// A sphere put at a point (render --sphere-at) is lit by the probes there: at a probe, that
// probe's SH and its directions.
TEST(ProbeSpheres, ASphereAtAPointTakesTheProbesThere) {
  bakefiles::LightProbes probes = cornellProbes(0.1f);
  const size_t n = probes.mesh.positions.size();
  probes.directions.start.assign(1, 0);
  for (size_t p = 0; p < n; ++p) {
    probes.sh[p].c[1] = glm::vec3(0.01f * float(p));  // tells the probes apart
    if (p % 2 == 0) probes.directions.lights.push_back({glm::vec3(0, -1, 0), glm::vec3(float(p))});
    probes.directions.start.push_back(uint32_t(probes.directions.lights.size()));
  }
  const size_t at = n / 2 - (n / 2) % 2;  // an even probe: one direction
  const ProbeSphere s = sphereAt(probes, probes.mesh.positions[at], 0.02f);
  EXPECT_EQ(s.radius, 0.02f);
  EXPECT_NEAR(s.sh.c[1].x, probes.sh[at].c[1].x, 1e-5f);
  ASSERT_EQ(s.directions.size(), 1u);
  EXPECT_NEAR(s.directions[0].power.x, float(at), 1e-3f);
}

TEST(ProbeSpheres, MedianSpacingIsTheGridStep) {
  const bakefiles::LightProbes probes = cornellProbes(0.1f);
  EXPECT_NEAR(medianProbeSpacing(probes.mesh), 0.1f, 1e-5f);
  const std::vector<float> nearest = nearestProbeDistances(probes.mesh);
  ASSERT_EQ(nearest.size(), probes.mesh.positions.size());
  for (float d : nearest) EXPECT_NEAR(d, 0.1f, 1e-5f);
  // Without tetrahedra (two probes), over all pairs; one probe has no spacing.
  runtime::ProbeTetrahedra two;
  two.positions = {{0, 0, 0}, {0, 0.3f, 0}};
  EXPECT_NEAR(medianProbeSpacing(two), 0.3f, 1e-6f);
  two.positions.pop_back();
  EXPECT_EQ(medianProbeSpacing(two), 0.0f);
}

// In the Cornell box from its camera, a handful of spheres go to probes the camera sees (no
// surface between the eye and the sphere's front), wholly inside the picture, apart from each
// other on it and clear of the walls, the same for one thread and two; the tall block hides the
// probes behind it.
TEST(ProbeSpheres, AHandfulGoToVisibleProbesSpreadOverThePicture) {
  const scenes::Scene scene = scenes::makeCornellBox();
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  const bakefiles::LightProbes probes = cornellProbes(0.05f);
  const trace::View view = trace::cameraView(scene.cameras.front());
  const int width = 200, height = 150;
  setThreadCount(1);
  Result<std::vector<ProbeSphere>> one =
      chooseProbeSpheres(**tracer, probes, view, width, height, 8);
  setThreadCount(2);
  Result<std::vector<ProbeSphere>> two =
      chooseProbeSpheres(**tracer, probes, view, width, height, 8);
  setThreadCount(0);
  ASSERT_TRUE(one) << one.message();
  ASSERT_TRUE(two) << two.message();
  ASSERT_EQ(one->size(), 8u);
  ASSERT_EQ(two->size(), 8u);
  const glm::vec3 right = glm::normalize(glm::cross(view.forward, view.up));
  const float tanHalf = std::tan(0.5f * view.yfov);
  std::vector<glm::vec2> centres;
  for (size_t i = 0; i < one->size(); ++i) {
    const ProbeSphere& s = (*one)[i];
    EXPECT_EQ(s.probe, (*two)[i].probe);
    EXPECT_EQ(s.radius, (*two)[i].radius);
    EXPECT_EQ(s.centre, probes.mesh.positions[size_t(s.probe)]);
    // 2/5 of the 5 cm step at most, and clear of the walls (the room's inner faces).
    EXPECT_GT(s.radius, 0.0f);
    EXPECT_LE(s.radius, 0.02f + 1e-6f);
    for (int k = 0; k < 3; ++k) {
      EXPECT_GT(s.centre[k] - s.radius, 0.0f) << s.probe;
      EXPECT_LT(s.centre[k] + s.radius, 0.549f) << s.probe;
    }
    // Seen: nothing between the eye and the sphere.
    trace::Ray ray;
    ray.origin = view.position;
    ray.direction = glm::normalize(s.centre - view.position);
    ray.tfar = glm::length(s.centre - view.position) - s.radius;
    EXPECT_FALSE((*tracer)->occluded(ray)) << s.probe;
    // Inside the picture, outline and all.
    const glm::vec3 d = s.centre - view.position;
    const float z = glm::dot(d, view.forward);
    const glm::vec2 c((glm::dot(d, right) / (z * tanHalf * float(width) / float(height)) * 0.5f +
                       0.5f) * float(width),
                      (0.5f - glm::dot(d, view.up) / (z * tanHalf) * 0.5f) * float(height));
    const float r = s.radius / (z * tanHalf) * 0.5f * float(height);
    EXPECT_GE(c.x - r, -0.5f);
    EXPECT_GE(c.y - r, -0.5f);
    EXPECT_LE(c.x + r, float(width) + 0.5f);
    EXPECT_LE(c.y + r, float(height) + 0.5f);
    for (const glm::vec2& other : centres) EXPECT_GT(glm::length(c - other), 2.0f * r);
    centres.push_back(c);
  }
  // The first is the one nearest the picture's centre.
  EXPECT_LT(glm::length(centres.front() - glm::vec2(100.0f, 75.0f)), 15.0f);
}

// For every ray of a picture, the tiles give the very sphere (and shade) that testing every
// sphere gives: the tiles' outlines hold whole spheres, including ones reaching past the
// picture's edge, one crossing the camera's plane and one holding the camera (seen through).
TEST(ProbeSpheres, TilesFindTheSameSphereAsTestingEvery) {
  const trace::View view = trace::lookAtView(glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, -1.0f), 1.0f);
  std::vector<ProbeSphere> spheres;
  auto add = [&](glm::vec3 c, float r) {
    ProbeSphere s;
    s.centre = c;
    s.radius = r;
    s.probe = int(spheres.size());
    s.sh.c[0] = glm::vec3(float(spheres.size() + 1));  // tells the spheres apart by value
    spheres.push_back(s);
  };
  for (int i = 0; i < 40; ++i) {
    const float a = float(i) * 2.399963f;  // golden angle: a spiral over the picture
    const float spread = 0.02f * float(i);
    add({spread * std::cos(a), spread * 0.7f * std::sin(a), -1.0f - 0.05f * float(i % 7)},
        0.03f + 0.002f * float(i % 5));
  }
  add({0.55f, 0.0f, -1.0f}, 0.1f);    // past the right edge
  add({-0.1f, 0.05f, -0.08f}, 0.1f);  // across the camera's plane
  add({0.0f, 0.0f, 0.02f}, 0.05f);    // holding the camera
  add({0.0f, 0.0f, 2.0f}, 0.3f);      // behind the camera
  const int width = 97, height = 61;  // not whole tiles
  const ProbeSphereIndex index(spheres, view, width, height);
  size_t hits = 0;
  for (int py = 0; py < height; ++py)
    for (int px = 0; px < width; ++px)
      for (float f : {0.01f, 0.5f, 0.99f}) {
        const trace::Ray ray = trace::cameraRay(view, width, height, float(px) + f, float(py) + 1.0f - f);
        float nearest = std::numeric_limits<float>::infinity();
        int expected = -1;
        for (size_t i = 0; i < spheres.size(); ++i) {
          const glm::vec3 oc = ray.origin - spheres[i].centre;
          const float b = glm::dot(oc, ray.direction);
          const glm::vec3 across = oc - b * ray.direction;
          const float r2 = spheres[i].radius * spheres[i].radius;
          const float disc = r2 - glm::dot(across, across);
          if (disc < 0.0f || glm::dot(oc, oc) <= r2) continue;
          const float t = -b - std::sqrt(disc);
          if (t > 0.0f && t < nearest) {
            nearest = t;
            expected = int(i);
          }
        }
        glm::vec3 shaded(0.0f);
        const bool hit = index.shade(ray, px, py, std::numeric_limits<float>::infinity(), &shaded);
        ASSERT_EQ(hit, expected >= 0) << px << ", " << py;
        if (!hit) continue;
        ++hits;
        // Constant radiance c0 Y00 = c0 / (2√π) gives E/π = that, whatever the normal.
        EXPECT_NEAR(shaded.x, kProbeSphereAlbedo * float(expected + 1) * 0.2820948f, 1e-4f)
            << px << ", " << py;
        // A scene hit in front of the sphere hides it.
        EXPECT_FALSE(index.shade(ray, px, py, nearest * 0.999f, &shaded));
      }
  EXPECT_GT(hits, size_t(width * height / 4));
}

}  // namespace
}  // namespace afterglow::preview
