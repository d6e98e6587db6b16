// A probes file that is not JSON (a NaN, a 1e999, a trailing comma) or holds a bad value is
// refused with one line naming the file, the probe (or tetrahedron, or reflection probe) at
// fault and the line and column of the value, through every reader: parseProbesFile (bake
// --probes, probes sample), parseUserProbes (probes place --add), and the CLI, which writes
// nothing.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "afterglow/probes/probes_file.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace afterglow::test {
namespace {

// A valid placement of five probes in two tetrahedra, as a person would lay it out, with `probe2`
// as the third probe's position (line 4) and `tetrahedron1` as the second tetrahedron (line 7).
std::string placementText(const std::string& probe2 = "[0, 1, 0]",
                          const std::string& tetrahedron1 = "[1, 4, 2, 3]") {
  return "{\"format\": \"afterglow-light-probes\", \"version\": 1,\n"
         "  \"positions\": [[0, 0, 0],\n"
         "    [1, 0, 0],\n"
         "    " + probe2 + ",\n"
         "    [0, 0, 1], [1, 1, 1]],\n"
         "  \"tetrahedra\": [[0, 1, 2, 3],\n"
         "    " + tetrahedron1 + "],\n"
         "  \"neighbours\": [[1, -1, -1, -1], [-1, 0, -1, -1]]}\n";
}

std::string placementError(const std::string& text) {
  Result<probes::ProbesFile> r = probes::parseProbesFile(text, "level.probes.json");
  EXPECT_FALSE(r) << text;
  if (r) return {};
  EXPECT_EQ(r.message().find('\n'), std::string::npos) << r.message();
  EXPECT_EQ(r.message().rfind("level.probes.json: ", 0), 0u) << r.message();
  return r.message();
}

TEST(ProbesFilePlaces, NanAndHugeNumbersNameTheProbeAndItsLineAndColumn) {
  ASSERT_TRUE(probes::parseProbesFile(placementText(), "p.json")) << placementText();
  // nlohmann::json reads no NaN: a syntax error at the N.
  std::string e = placementError(placementText("[0, NaN, 0]"));
  EXPECT_NE(e.find("level.probes.json: probe 2: not valid JSON"), std::string::npos) << e;
  EXPECT_NE(e.find("(line 4, column 9)"), std::string::npos) << e;
  // Nor a number beyond a double's range (it refuses it whole): placed at its first digit.
  e = placementError(placementText("[0, 0, 1e999]"));
  EXPECT_NE(e.find("probe 2: not valid JSON"), std::string::npos) << e;
  EXPECT_NE(e.find("1e999"), std::string::npos) << e;
  EXPECT_NE(e.find("(line 4, column 12)"), std::string::npos) << e;
  e = placementError(placementText("[-1e999, 0, 0]"));
  EXPECT_NE(e.find("(line 4, column 6)"), std::string::npos) << e;
  // Finite as a double, infinite as a float: JSON, but a bad position, placed at its array.
  e = placementError(placementText("[0, 3.5e39, 0]"));
  EXPECT_NE(e.find("probe 2 is not three finite numbers"), std::string::npos) << e;
  EXPECT_NE(e.find("(line 4, column 5)"), std::string::npos) << e;
  e = placementError(placementText("[0, \"NaN\", 0]"));
  EXPECT_NE(e.find("probe 2 is not three finite numbers"), std::string::npos) << e;
  EXPECT_NE(e.find("(line 4, column 5)"), std::string::npos) << e;
}

TEST(ProbesFilePlaces, MalformedJsonSaysWhereItBreaks) {
  // A trailing comma breaks the probe it promised (probe 5 of five).
  std::string text = placementText();
  text.replace(text.find("[1, 1, 1]]"), 10, "[1, 1, 1],]");
  std::string e = placementError(text);
  EXPECT_NE(e.find("probe 5: not valid JSON"), std::string::npos) << e;
  EXPECT_NE(e.find("(line 5, column 26)"), std::string::npos) << e;
  // Cut short.
  e = placementError(placementText().substr(0, 40));
  EXPECT_NE(e.find("not valid JSON"), std::string::npos) << e;
  EXPECT_NE(e.find("(line 1, column 41)"), std::string::npos) << e;
  // JSON, but not an object.
  e = placementError("\n  [1, 2, 3]");
  EXPECT_NE(e.find("not a JSON object (line 2, column 3)"), std::string::npos) << e;
}

TEST(ProbesFilePlaces, BadValuesAreNamedAndPlaced) {
  std::string e = placementError(placementText("[0, 1, 0]", "[1, 9, 2, 3]"));
  EXPECT_NE(e.find("level.probes.json: tetrahedron 1 is not four probe indices"),
            std::string::npos) << e;
  EXPECT_NE(e.find("(line 7, column 5)"), std::string::npos) << e;
  // Found by the mesh's check (negative orientation): placed at its tetrahedron too.
  e = placementError(placementText("[0, 1, 0]", "[4, 1, 2, 3]"));
  EXPECT_NE(e.find("tetrahedron 1"), std::string::npos) << e;
  EXPECT_NE(e.find("(line 7, column 5)"), std::string::npos) << e;

  std::string text = placementText();
  text.insert(text.rfind('}'), ",\n  \"reflectionProbes\": [{\"name\": \"hall\",\n"
                               "    \"position\": [1, 1, 1], \"size\": [4, -3, 4]}]");
  e = placementError(text);
  EXPECT_NE(e.find("reflection probe 0 ('hall'): \"size\" must be three positive"),
            std::string::npos) << e;
  EXPECT_NE(e.find("(line 10, column 36)"), std::string::npos) << e;
}

TEST(ProbesFilePlaces, TheUsersProbesAreRefusedAlike) {
  const std::string nan = "{\"positions\": [[0, 0, 0],\n  [0, 1, NaN]]}";
  Result<probes::UserProbes> r = probes::parseUserProbes(nan, "mine.json");
  ASSERT_FALSE(r);
  EXPECT_NE(r.message().find("mine.json: probe 1: not valid JSON"), std::string::npos)
      << r.message();
  EXPECT_NE(r.message().find("(line 2, column 10)"), std::string::npos) << r.message();
  r = probes::parseUserProbes("{\"positions\": [[0, 0, 0]],\n \"names\": [7]}", "mine.json");
  ASSERT_FALSE(r);
  EXPECT_NE(r.message().find("mine.json: name 0 is not a string (line 2, column 12)"),
            std::string::npos)
      << r.message();
}

TEST(ProbesFilePlaces, TheCommandsRefuseThemAndWriteNothing) {
  const std::string dir = tempDir("probes_file_places");
  std::ofstream(dir + "/nan.json") << placementText("[0, NaN, 0]");
  std::ofstream(dir + "/huge.json") << placementText("[0, 1e999, 0]");
  CliRun bake = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' --quality draft "
                            "--texels-per-unit 16 --quiet --probes '" + dir + "/nan.json'");
  EXPECT_EQ(bake.exitCode, 1) << bake.err;
  EXPECT_NE(bake.err.find("nan.json: probe 2: not valid JSON"), std::string::npos) << bake.err;
  EXPECT_NE(bake.err.find("(line 4, column 9)"), std::string::npos) << bake.err;
  EXPECT_EQ(bake.err.find('\n'), bake.err.size() - 1) << "one line: " << bake.err;
  EXPECT_FALSE(fs::exists(dir + "/out"));

  CliRun place = runCli(dir, "probes place builtin:cornell -o '" + dir + "/p.json' --quiet "
                             "--add '" + dir + "/huge.json'");
  EXPECT_EQ(place.exitCode, 1) << place.err;
  EXPECT_NE(place.err.find("huge.json: probe 2: not valid JSON"), std::string::npos)
      << place.err;
  EXPECT_NE(place.err.find("(line 4, column 9)"), std::string::npos) << place.err;
  EXPECT_FALSE(fs::exists(dir + "/p.json"));
}

}  // namespace
}  // namespace afterglow::test
