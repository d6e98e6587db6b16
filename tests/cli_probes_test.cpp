// `afterglow probes place` run as a user would: the probes file holds probes inside the room,
// off its surfaces, a valid tetrahedral mesh over them, the user's pinned probes by name, and a
// picture; with --bake, probes added only across edges where the bake's light changes, never in
// geometry, the same for any thread count; bad user files and budgets are refused with a message
// naming the cause and nothing written; --reflection proposes reflection probes in the same file,
// which the bake captures.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/trace/raytracer.h"
#include "afterglow/probes/bake_refinement.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/scenes/procedural.h"
#include "test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::test {
namespace {

TEST(CliProbes, PlaceWritesProbesInsideTheRoomTheirTetrahedraAndAPicture) {
  const std::string dir = tempDir("cli_probes_place");
  std::ofstream(dir + "/mine.json")
      << R"({"positions": [[0.278, 0.3, 0.28], [0.1, 0.45, 0.45]], "names": ["desk", "shelf"]})";
  CliRun run = runCli(dir, "probes place builtin:cornell -o '" + dir + "/p.json' --add '" + dir +
                               "/mine.json' --width 160 --height 100");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("placed"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("rejected"), std::string::npos) << run.out;

  const json doc = json::parse(slurp(dir + "/p.json"), nullptr, false);
  ASSERT_TRUE(doc.is_object());
  EXPECT_EQ(doc["format"], "afterglow-light-probes");
  runtime::ProbeTetrahedra mesh;
  for (const json& p : doc["positions"])
    mesh.positions.push_back({p[0].get<float>(), p[1].get<float>(), p[2].get<float>()});
  for (const json& t : doc["tetrahedra"])
    mesh.tetrahedra.push_back({t[0].get<int>(), t[1].get<int>(), t[2].get<int>(), t[3].get<int>()});
  for (const json& n : doc["neighbours"])
    mesh.neighbours.push_back({n[0].get<int>(), n[1].get<int>(), n[2].get<int>(), n[3].get<int>()});
  ASSERT_GT(mesh.positions.size(), 20u);
  ASSERT_GT(mesh.tetrahedra.size(), 20u);
  EXPECT_EQ(runtime::checkProbeTetrahedra(mesh), "");
  ASSERT_EQ(doc["kinds"].size(), mesh.positions.size());

  // The Cornell box's room is 0.556 × 0.549 × 0.559 m from the origin; its two blocks stand on
  // the floor. Every probe lies inside the room and off its walls by the margin.
  const float margin = doc["settings"]["margin"].get<float>();
  EXPECT_GT(margin, 0.0f);
  size_t pinned = 0;
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const glm::vec3 p = mesh.positions[i];
    const std::string kind = doc["kinds"][i];
    if (kind == "pinned") {
      ++pinned;
      continue;
    }
    // (The right wall leans by 6.4 mm over its depth, so x is checked against its far end.)
    const float room[3] = {0.556f, 0.5488f, 0.5592f};
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(p[k], margin * 0.99f) << "probe " << i;
      EXPECT_LE(p[k], room[k] - (k == 0 ? 0.0f : margin * 0.99f)) << "probe " << i;
    }
  }
  // The user's probes are kept as given, with their names.
  EXPECT_EQ(pinned, 2u);
  bool desk = false;
  for (auto it = doc["names"].begin(); it != doc["names"].end(); ++it) {
    if (it.value() != "desk") continue;
    const glm::vec3 p = mesh.positions[size_t(std::stoi(it.key()))];
    desk = std::abs(p.x - 0.278f) < 1e-6f && std::abs(p.y - 0.3f) < 1e-6f;
  }
  EXPECT_TRUE(desk);

  auto picture = OIIO::ImageInput::open(dir + "/p.png");
  ASSERT_TRUE(picture);
  EXPECT_EQ(picture->spec().width, 160);
  EXPECT_EQ(picture->spec().height, 100);
}

// A placement added back with --add pins every probe it holds: the placed probes at those very
// positions give way, so the second file has the same positions, all pinned.
TEST(CliProbes, APlacementAddedBackIsPinnedWithoutDuplicates) {
  const std::string dir = tempDir("cli_probes_add_back");
  CliRun first = runCli(dir, "probes place builtin:cornell -o '" + dir + "/a.json' --quiet");
  ASSERT_EQ(first.exitCode, 0) << first.err;
  CliRun again = runCli(dir, "probes place builtin:cornell -o '" + dir + "/b.json' --add '" +
                                 dir + "/a.json' --quiet");
  ASSERT_EQ(again.exitCode, 0) << again.err;
  const json a = json::parse(slurp(dir + "/a.json"), nullptr, false);
  const json b = json::parse(slurp(dir + "/b.json"), nullptr, false);
  ASSERT_TRUE(a.is_object() && b.is_object());
  EXPECT_EQ(b["positions"].size(), a["positions"].size());
  size_t pinned = 0;
  for (const json& k : b["kinds"]) pinned += k == "pinned";
  EXPECT_EQ(pinned, a["positions"].size());
}

std::vector<glm::vec3> positionsOf(const json& doc) {
  std::vector<glm::vec3> out;
  for (const json& p : doc.at("positions"))
    out.push_back({p[0].get<float>(), p[1].get<float>(), p[2].get<float>()});
  return out;
}

// The Cornell box's lamp lights the room from a small patch of its ceiling: E/π changes by more
// than 25% across most of the coarse grid's edges (1/r² below the lamp, the blocks' shadows, the
// coloured walls), so --bake adds probes, each at the midpoint of an edge of the plain
// placement's tetrahedra whose ends differ by more than the threshold in the bake.
TEST(CliProbes, BakeRefinementSplitsEdgesWhereTheBakesLightChanges) {
  const std::string dir = tempDir("cli_probes_bake_refine");
  CliRun bake = runCli(dir, "bake builtin:cornell -o '" + dir +
                                "/out' --quality draft --texels-per-unit 32 --quiet");
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  CliRun plain = runCli(dir, "probes place builtin:cornell -o '" + dir + "/plain.json' --quiet");
  ASSERT_EQ(plain.exitCode, 0) << plain.err;
  const std::string withBake = " --bake '" + dir + "/out' --width 160 --height 100";
  CliRun one = runCli(dir, "probes place builtin:cornell -o '" + dir + "/one.json' --threads 1" +
                               withBake);
  ASSERT_EQ(one.exitCode, 0) << one.err;
  EXPECT_NE(one.out.find("by the bake"), std::string::npos) << one.out;
  CliRun two = runCli(dir, "probes place builtin:cornell -o '" + dir + "/two.json' --threads 2" +
                               withBake + " --quiet");
  ASSERT_EQ(two.exitCode, 0) << two.err;

  // The same output for any thread count, but for the count and the timings it records.
  json a = json::parse(slurp(dir + "/one.json")), b = json::parse(slurp(dir + "/two.json"));
  for (json* doc : {&a, &b}) {
    (*doc)["settings"].erase("threads");
    for (const char* key : {"placeSeconds", "tetrahedraSeconds"}) (*doc)["summary"].erase(key);
    (*doc)["summary"]["bakeRefinement"].erase("seconds");
  }
  EXPECT_EQ(a, b);
  EXPECT_EQ(slurp(dir + "/one.png"), slurp(dir + "/two.png"));

  // The plain placement's probes first, then the added ones, of kind refined.
  const json base = json::parse(slurp(dir + "/plain.json"));
  const std::vector<glm::vec3> before = positionsOf(base), after = positionsOf(a);
  const size_t added = a.at("summary").at("refinedByBake").get<size_t>();
  ASSERT_GT(added, 10u);
  ASSERT_EQ(after.size(), before.size() + added);
  for (size_t i = 0; i < before.size(); ++i) ASSERT_EQ(after[i], before[i]) << "probe " << i;
  for (size_t i = before.size(); i < after.size(); ++i) EXPECT_EQ(a["kinds"][i], "refined");

  // The bake's E/π at the plain placement's probes, as the command samples it (the transport
  // solved from scratch, walking in probe order).
  std::string error;
  std::unique_ptr<runtime::Runtime> rt = runtime::Runtime::load(dir + "/out/transport.agt", &error);
  ASSERT_TRUE(rt) << error;
  runtime::UpdateOptions update;
  update.fromScratch = true;
  rt->update(update);
  std::vector<probes::AxisIrradiance> irradiance(before.size());
  int hint = 0;
  for (size_t i = 0; i < before.size(); ++i) {
    const runtime::ShL2 sh = rt->sampleProbes(before[i], &hint);
    for (int k = 0; k < 6; ++k)
      irradiance[i][size_t(k)] = runtime::Runtime::evaluateIrradiance(sh, probes::axisNormal(k));
  }
  // Each added probe is the midpoint of an edge whose ends differ by more than the threshold.
  const float floor = a["summary"]["bakeRefinement"].at("floor").get<float>();
  EXPECT_GT(floor, 0.0f);
  std::map<std::array<float, 3>, float> splits;  // midpoint -> largest difference of its edges
  for (const json& t : base.at("tetrahedra"))
    for (size_t i = 0; i < 4; ++i)
      for (size_t j = i + 1; j < 4; ++j) {
        const size_t p = t[i].get<size_t>(), q = t[j].get<size_t>();
        const glm::vec3 m = 0.5f * (before[p] + before[q]);
        float& d = splits[{m.x, m.y, m.z}];
        d = std::max(d, probes::irradianceDifference(irradiance[p], irradiance[q], floor));
      }
  for (size_t i = before.size(); i < after.size(); ++i) {
    const glm::vec3 p = after[i];
    auto it = splits.find({p.x, p.y, p.z});
    ASSERT_NE(it, splits.end()) << "probe " << i << " is no edge's midpoint";
    EXPECT_GT(it->second, 0.25f) << "probe " << i;
  }

  // None inside geometry: inside the room, off its walls by the margin, and no ray from it meets
  // the back of a surface (the blocks are closed boxes; every surface faces into the room).
  const scenes::Scene scene = scenes::makeCornellBox();
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  const float margin = a["settings"].at("margin").get<float>();
  const float room[3] = {0.556f, 0.5488f, 0.5592f};
  for (size_t i = before.size(); i < after.size(); ++i) {
    const glm::vec3 p = after[i];
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(p[k], margin * 0.99f) << "probe " << i;
      EXPECT_LE(p[k], room[k] - (k == 0 ? 0.0f : margin * 0.99f)) << "probe " << i;
    }
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
          if (x == 0 && y == 0 && z == 0) continue;
          trace::Ray ray;
          ray.origin = p;
          ray.direction = glm::normalize(glm::vec3(x, y, z));
          const trace::Hit hit = tracer.value()->intersect(ray);
          EXPECT_TRUE(!hit.valid() || hit.frontFace) << "probe " << i << " sees a back face";
        }
  }

  // A budget keeps the largest differences and says so.
  const size_t budget = before.size() + added / 2;
  CliRun capped = runCli(dir, "probes place builtin:cornell -o '" + dir + "/capped.json'" +
                                  withBake + " --max-probes " + std::to_string(budget));
  ASSERT_EQ(capped.exitCode, 0) << capped.err;
  EXPECT_NE(capped.out.find("--max-probes"), std::string::npos) << capped.out;
  EXPECT_EQ(json::parse(slurp(dir + "/capped.json")).at("positions").size(), budget);

  CliRun lone = runCli(dir, "probes place builtin:cornell -o '" + dir +
                                "/lone.json' --refine-threshold 0.5");
  EXPECT_EQ(lone.exitCode, 2);
  EXPECT_NE(lone.err.find("--bake"), std::string::npos) << lone.err;
}

TEST(CliProbes, BadUserProbesAndBudgetsAreRefusedAndWriteNothing) {
  const std::string dir = tempDir("cli_probes_bad");
  std::ofstream(dir + "/nan.json") << R"({"positions": [[0, 0, 0], [0.1, "x", 0.2]]})";
  CliRun bad = runCli(dir, "probes place builtin:cornell -o '" + dir + "/p.json' --add '" + dir +
                               "/nan.json'");
  EXPECT_EQ(bad.exitCode, 1);
  EXPECT_NE(bad.err.find("nan.json"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("probe 1"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir + "/p.json"));
  EXPECT_FALSE(fs::exists(dir + "/p.png"));

  CliRun budget = runCli(dir, "probes place builtin:cornell -o '" + dir +
                                  "/p.json' --spacing 0.01 --max-probes 1000");
  EXPECT_EQ(budget.exitCode, 1);
  EXPECT_NE(budget.err.find("--spacing"), std::string::npos) << budget.err;
  EXPECT_FALSE(fs::exists(dir + "/p.json"));

  CliRun verb = runCli(dir, "probes scatter builtin:cornell");
  EXPECT_EQ(verb.exitCode, 2);
  EXPECT_NE(verb.err.find("place"), std::string::npos) << verb.err;
}

// --reflection proposes one reflection probe for the Cornell box, its box the room (open at the
// front, where it reaches the scene's bounds), written beside the light probes; the bake takes
// it from the file, and a node of the scene authoring a probe of the same name wins.
TEST(CliProbes, ReflectionProposesOneProbeForTheCornellBoxAndTheBakeCapturesIt) {
  const std::string dir = tempDir("cli_probes_reflection");
  CliRun run = runCli(dir, "probes place builtin:cornell --reflection -o '" + dir +
                               "/p.json' --width 160 --height 100");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("reflection    1 reflection probe proposed"), std::string::npos)
      << run.out;
  const json doc = json::parse(slurp(dir + "/p.json"), nullptr, false);
  ASSERT_TRUE(doc.is_object());
  ASSERT_TRUE(doc.contains("reflectionProbes"));
  ASSERT_EQ(doc["reflectionProbes"].size(), 1u);
  const json& r = doc["reflectionProbes"][0];
  EXPECT_EQ(r["name"], "reflection_probe_0");
  const float room[3] = {0.556f, 0.5488f, 0.5592f};
  // The projection box is the room (the influence box reaches past its walls: issue 28).
  for (size_t k = 0; k < 3; ++k) {
    const float c = r["position"][k].get<float>();
    const float half = 0.5f * r["projectionSize"][k].get<float>();
    EXPECT_NEAR(c - half, 0.0f, 0.03f) << "axis " << k;
    EXPECT_NEAR(c + half, room[k], 0.03f) << "axis " << k;
    EXPECT_GT(r["size"][k].get<float>(), 2.0f * half);
  }
  EXPECT_EQ(r["resolution"], 128);
  EXPECT_EQ(r["boxProjection"], true);
  EXPECT_EQ(doc["settings"]["reflection"], true);
  EXPECT_EQ(doc["summary"]["reflection"]["proposed"], 1);
  // Without --reflection the file has none, and its budget alone is a usage error.
  CliRun plain = runCli(dir, "probes place builtin:cornell -o '" + dir + "/q.json' --quiet");
  ASSERT_EQ(plain.exitCode, 0) << plain.err;
  EXPECT_FALSE(json::parse(slurp(dir + "/q.json")).contains("reflectionProbes"));
  CliRun lone = runCli(dir, "probes place builtin:cornell -o '" + dir +
                                "/q.json' --max-reflection-probes 4");
  EXPECT_EQ(lone.exitCode, 2);
  EXPECT_NE(lone.err.find("--reflection"), std::string::npos) << lone.err;

  // The bake captures the file's probe where the file puts it.
  CliRun bake = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' --quality draft "
                            "--texels-per-unit 16 --probes '" + dir + "/p.json'");
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  EXPECT_NE(bake.out.find("1 reflection probe from"), std::string::npos) << bake.out;
  const json baked = json::parse(slurp(dir + "/out/probes/reflection_probes.json"), nullptr, false);
  ASSERT_TRUE(baked.is_object());
  ASSERT_EQ(baked["probes"].size(), 2u);  // the sky, then ours
  EXPECT_EQ(baked["probes"][1]["name"], "reflection_probe_0");
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_FLOAT_EQ(baked["probes"][1]["capturePosition"][k].get<float>(),
                    r["position"][k].get<float>());
    EXPECT_FLOAT_EQ(baked["probes"][1]["projectionBox"]["halfSize"][k].get<float>(),
                    0.5f * r["projectionSize"][k].get<float>());
    EXPECT_FLOAT_EQ(baked["probes"][1]["box"]["halfSize"][k].get<float>(),
                    0.5f * r["size"][k].get<float>());
  }

  // Named as builtin:cornell-metal's own probe, the scene's node wins.
  json renamed = doc;
  renamed["reflectionProbes"][0]["name"] = "room_probe";
  renamed["reflectionProbes"][0]["blendDistance"] = 0.5;
  std::ofstream(dir + "/renamed.json") << renamed.dump();
  CliRun metal = runCli(dir, "bake builtin:cornell-metal -o '" + dir + "/metal' --quality draft "
                             "--texels-per-unit 16 --probes '" + dir + "/renamed.json'");
  ASSERT_EQ(metal.exitCode, 0) << metal.err;
  EXPECT_NE(metal.out.find("0 reflection probes from"), std::string::npos) << metal.out;
  const json kept = json::parse(slurp(dir + "/metal/probes/reflection_probes.json"), nullptr, false);
  ASSERT_TRUE(kept.is_object());
  ASSERT_EQ(kept["probes"].size(), 2u);
  EXPECT_EQ(kept["probes"][1]["name"], "room_probe");
  EXPECT_FLOAT_EQ(kept["probes"][1]["blendDistance"].get<float>(), 0.1f);
}

}  // namespace
}  // namespace afterglow::test
