// `afterglow probes place` run as a user would: the probes file holds probes inside the room,
// off its surfaces, a valid tetrahedral mesh over them, the user's pinned probes by name, and a
// picture; bad user files and budgets are refused with a message naming the cause and nothing
// written.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/runtime/probe_tetrahedra.h"
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

}  // namespace
}  // namespace afterglow::test
