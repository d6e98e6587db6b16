// Light probes do not carry light through a wall: two closed rooms side by side, a lamp in
// one, the probes placed as `afterglow bake` places them. Tetrahedra cross the wall between
// them; a point in the dark room must read dark, however its tetrahedron's corners lie.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "afterglow/baker/bake.h"
#include "afterglow/probes/placement.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/probe_lights.h"
#include "afterglow/runtime/probe_visibility.h"
#include "afterglow/trace/raytracer.h"
#include "bake_fixtures.h"
#include "runtime/test_rng.h"

namespace afterglow::baker {
namespace {

// A closed room 4 × 3 × 4 m (x, z in [-2, 2], walls facing in) parted at x = 0 by a wall
// 10 cm thick (a closed box), a point lamp in the left room.
scenes::Scene twoRooms() {
  scenes::Scene scene = groundQuad("rooms", 2.0f, 0.6f, 0.0f);  // the floor, facing up
  scenes::Primitive& p = scene.meshes[0].primitives[0];
  const float h = 3.0f;
  addRoomWalls(p, 2.0f, h);
  addQuad(p, {-2, h, -2}, {2, h, -2}, {2, h, 2}, {-2, h, 2}, {0, -1, 0});  // the ceiling
  addBox(scene, "wall", {-0.05f, 0.0f, -2.0f}, {0.05f, h, 2.0f}, 0);
  scenes::Light lamp;
  lamp.name = "lamp";
  lamp.type = scenes::LightType::Point;
  lamp.intensity = 20.0f;
  lamp.position = glm::vec3(-1.0f, 2.0f, 0.0f);
  scene.lights.push_back(lamp);
  return scene;
}

const glm::vec3 kAxes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

// E/π at 40 points of the dark room 10-45 cm from the wall, against the same points mirrored
// into the lit room: the leak as a share of the light beside it, with and without the probes'
// visibility (probe_visibility.h). Probes as `bake` places them (they crowd the wall on both
// sides, so few tetrahedra cross it), and as a hand-made grid 1 m apart (Unity's probe groups),
// whose tetrahedra all cross it.
struct Leak {
  int crossing = 0;          // probes in the lit room weighing on the dark room's points
  double dark[2] = {0, 0};   // mean brightest-axis E/π there: SH as located, then weighed
  double lit = 0.0;          // and at the mirrored points, weighed
};
Leak leakThroughTheWall(const scenes::Scene& scene, const std::vector<glm::vec3>& positions) {
  Leak out;
  Result<runtime::ProbeTetrahedra> mesh = probes::tetrahedralize(positions);
  EXPECT_TRUE(mesh) << mesh.message();
  if (!mesh) return out;
  BakeOptions options = draftOptions();
  options.probes = mesh.value();
  const BakeResult baked = bakeOrDie(scene, options);
  EXPECT_EQ(baked.probeSh.size(), positions.size());
  const runtime::ProbeTransport& probes = baked.transport.probes;
  EXPECT_EQ(probes.depth.size(), probes.count() * runtime::kProbeDepthValues);
  const runtime::ProbeDirectionList directions =
      runtime::probeLights(baked.transport, runtime::directScales(baked.transport));
  runtime::test::Rng rng{29};
  for (int i = 0; i < 40; ++i) {
    const glm::vec3 p(0.1f + 0.35f * rng.unit(), 0.3f + 2.4f * rng.unit(), -1.7f + 3.4f * rng.unit());
    for (const glm::vec3& q : {p, glm::vec3(-p.x, p.y, p.z)})
      for (int visible = 0; visible < 2; ++visible) {
        runtime::ProbeLocation where = runtime::locateProbe(probes.mesh, q, 0);
        if (q.x > 0.0f && visible == 0)
          for (int k = 0; k < 4; ++k)
            out.crossing += where.probes[k] >= 0 && where.weights[k] > 0.0f &&
                            probes.mesh.positions[size_t(where.probes[k])].x < 0.0f;
        if (visible) where = runtime::weighByVisibility(where, probes, q);
        const runtime::ProbeLighting l = runtime::mixProbeLighting(where, baked.probeSh, directions);
        double e = 0.0;
        for (const glm::vec3& n : kAxes)
          e = std::max(e, double(glm::max(l.irradianceOverPi(n), 0.0f).g));
        if (q.x > 0.0f) out.dark[visible] += e / 40.0;
        else if (visible) out.lit += e / 40.0;
      }
  }
  return out;
}

TEST(ProbesLeak, NoLightThroughAWallIntoTheDarkRoom) {
  scenes::Scene scene = twoRooms();
  unwrapAt(scene, 4.0f);
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  Result<probes::Placement> placed = probes::placeProbes(scene, *tracer.value());
  ASSERT_TRUE(placed) << placed.message();
  std::vector<glm::vec3> grid;
  for (float x = -1.5f; x < 2.0f; x += 1.0f)
    for (float y = 0.5f; y < 3.0f; y += 1.0f)
      for (float z = -1.5f; z < 2.0f; z += 1.0f) grid.emplace_back(x, y, z);
  const struct {
    const char* name;
    const std::vector<glm::vec3>& positions;
  } kCases[] = {{"placed as bake places them", placed->positions},
                {"a grid 1 m apart", grid}};
  for (const auto& c : kCases) {
    const Leak leak = leakThroughTheWall(scene, c.positions);
    std::printf("two rooms, probes %s (%zu): 40 points 10-45 cm from the wall in the dark room "
                "(%d weights on probes in the lit room): mean brightest axis E/pi %.4f as "
                "located, %.5f weighed by visibility; the mirrored points in the lit room %.3f\n",
                c.name, c.positions.size(), leak.crossing, leak.dark[0], leak.dark[1], leak.lit);
    EXPECT_LT(leak.dark[1], 0.01 * leak.lit) << c.name;
  }
}

}  // namespace
}  // namespace afterglow::baker
