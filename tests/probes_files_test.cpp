// The light probes' files read back: a placement (`afterglow bake --probes PROBES.json`) and the
// baked SH file round trip, and so do the reflection probes of probes place --reflection; bad
// placements (NaN, a tetrahedron index out of range, neighbours that do not match, a reflection
// probe's negative size or resolution that is not a power of two) and bad SH files are refused
// with one line naming the file and the object;
// and `afterglow bake` refuses them, or an automatic placement over --max-probes, writing
// nothing.
#include <filesystem>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/probes/probes_file.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::test {
namespace {

// A valid placement of five probes in two tetrahedra.
json placement() {
  return json::parse(R"({"format": "afterglow-light-probes", "version": 1,
    "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]],
    "kinds": ["grid", "refined", "moved", "pinned", "grid"], "names": {"3": "door"},
    "tetrahedra": [[0, 1, 2, 3], [1, 4, 2, 3]], "neighbours": [[1, -1, -1, -1], [-1, 0, -1, -1]]})");
}

std::string errorOf(const json& doc) {
  Result<probes::ProbesFile> r = probes::parseProbesFile(doc.dump(), "level.probes.json");
  EXPECT_FALSE(r) << doc.dump();
  if (r) return {};
  EXPECT_EQ(r.message().find('\n'), std::string::npos);
  EXPECT_EQ(r.message().rfind("level.probes.json: ", 0), 0u) << r.message();
  return r.message();
}

TEST(ProbesFiles, APlacementReadsBackWithItsKindsNamesAndTetrahedra) {
  Result<probes::ProbesFile> r = probes::parseProbesFile(placement().dump(), "p.json");
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->positions.size(), 5u);
  EXPECT_EQ(r->kinds[1], probes::ProbeKind::Refined);
  EXPECT_EQ(r->kinds[3], probes::ProbeKind::Pinned);
  EXPECT_EQ(r->names[3], "door");
  EXPECT_EQ(r->mesh.tetrahedra.size(), 2u);
  EXPECT_EQ(r->mesh.neighbours[0], glm::ivec4(1, -1, -1, -1));
  // What probes::probesJson writes reads back to the same mesh.
  probes::Placement written;
  written.positions = r->positions;
  written.kinds = r->kinds;
  Result<probes::ProbesFile> again = probes::parseProbesFile(
      probes::probesJson(written, r->names, r->mesh, "{}", "{}"), "again.json");
  ASSERT_TRUE(again) << again.message();
  EXPECT_EQ(again->mesh.tetrahedra, r->mesh.tetrahedra);
  EXPECT_EQ(again->mesh.neighbours, r->mesh.neighbours);
  EXPECT_EQ(again->names, r->names);
}

TEST(ProbesFiles, BadPlacementsNameTheFileAndTheObject) {
  json nan = placement();
  nan["positions"][2] = json::array({0, 3.5e39, 0});  // finite, but infinite as a float
  EXPECT_NE(errorOf(nan).find("probe 2"), std::string::npos);
  nan["positions"][2] = json::array({0, "NaN", 0});
  EXPECT_NE(errorOf(nan).find("probe 2"), std::string::npos);

  json index = placement();
  index["tetrahedra"][1] = json::array({1, 5, 2, 3});
  EXPECT_NE(errorOf(index).find("tetrahedron 1"), std::string::npos) << errorOf(index);

  json negative = placement();
  negative["tetrahedra"][0] = json::array({0, -1, 2, 3});
  EXPECT_NE(errorOf(negative).find("tetrahedron 0"), std::string::npos);

  json neighbours = placement();
  neighbours["neighbours"][1] = json::array({-1, -1, -1, -1});  // no longer mutual
  EXPECT_NE(errorOf(neighbours).find("tetrahedron"), std::string::npos) << errorOf(neighbours);

  json inverted = placement();
  inverted["tetrahedra"][0] = json::array({1, 0, 2, 3});  // negative orientation
  EXPECT_NE(errorOf(inverted).find("tetrahedron 0"), std::string::npos) << errorOf(inverted);

  json kind = placement();
  kind["kinds"][4] = "floating";
  EXPECT_NE(errorOf(kind).find("probe 4"), std::string::npos);

  json format = placement();
  format.erase("format");
  EXPECT_NE(errorOf(format).find("afterglow probes place"), std::string::npos);
  format["format"] = 0;  // not a string (the fuzzer's find: it used to throw)
  EXPECT_NE(errorOf(format).find("afterglow probes place"), std::string::npos);
}

TEST(ProbesFiles, TheShFileRoundTripsAndRefusesDamage) {
  runtime::ProbeShFile file;
  file.sh.resize(3);
  for (size_t p = 0; p < 3; ++p)
    for (int i = 0; i < runtime::kShCount; ++i)
      file.sh[p].c[i] = glm::vec3(float(p) + 0.1f * float(i), -0.5f * float(i), 1e-3f * float(p));
  file.deringWindow = 4.0f;
  const std::vector<uint8_t> bytes = runtime::serializeProbeSh(file);
  ASSERT_EQ(bytes.size(), runtime::kProbeShHeaderSize + 3 * 27 * 4);
  runtime::ProbeShFile back;
  std::string error;
  ASSERT_TRUE(runtime::parseProbeSh(bytes.data(), bytes.size(), back, &error)) << error;
  EXPECT_EQ(back.deringWindow, 4.0f);
  for (size_t p = 0; p < 3; ++p)
    for (int i = 0; i < runtime::kShCount; ++i) EXPECT_EQ(back.sh[p].c[i], file.sh[p].c[i]);

  std::vector<uint8_t> shorter(bytes.begin(), bytes.end() - 4);
  EXPECT_FALSE(runtime::parseProbeSh(shorter.data(), shorter.size(), back, &error));
  EXPECT_NE(error.find("3 probes need"), std::string::npos) << error;
  EXPECT_TRUE(back.sh.empty());
  std::vector<uint8_t> nan = bytes;
  const float bad = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan.data() + runtime::kProbeShHeaderSize + (27 + 5) * 4, &bad, 4);
  EXPECT_FALSE(runtime::parseProbeSh(nan.data(), nan.size(), back, &error));
  EXPECT_NE(error.find("probe 1"), std::string::npos) << error;
  std::vector<uint8_t> version = bytes;
  version[8] = 3;
  EXPECT_FALSE(runtime::parseProbeSh(version.data(), version.size(), back, &error));
  EXPECT_NE(error.find("version 3"), std::string::npos) << error;
  // Version 1 (the same bytes without directions) still reads.
  std::vector<uint8_t> one = bytes;
  one[8] = 1;
  EXPECT_TRUE(runtime::parseProbeSh(one.data(), one.size(), back, &error)) << error;

  // With directions (probe_lights.h): probe 0 has two, probe 1 none, probe 2 one.
  file.directions.start = {0, 2, 2, 3};
  file.directions.lights = {{glm::vec3(0, 1, 0), glm::vec3(1, 2, 3)},
                            {glm::normalize(glm::vec3(1, 1, 0)), glm::vec3(0.5f)},
                            {glm::vec3(0, 0, -1), glm::vec3(4, 0, 0)}};
  const std::vector<uint8_t> withDirections = runtime::serializeProbeSh(file);
  ASSERT_EQ(withDirections.size(), bytes.size() + 4 + 4 * 4 + 3 * 6 * 4);
  ASSERT_TRUE(runtime::parseProbeSh(withDirections.data(), withDirections.size(), back, &error))
      << error;
  EXPECT_EQ(back.directions.start, file.directions.start);
  ASSERT_EQ(back.directions.lights.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(back.directions.lights[k].direction, file.directions.lights[k].direction);
    EXPECT_EQ(back.directions.lights[k].power, file.directions.lights[k].power);
  }
  const size_t section = bytes.size();  // M, then start[0..3], then the directions
  std::vector<uint8_t> order = withDirections;
  order[section + 4 + 2 * 4] = 1;  // start[2] = 1 < start[1] = 2
  EXPECT_FALSE(runtime::parseProbeSh(order.data(), order.size(), back, &error));
  EXPECT_NE(error.find("probe 2: its directions start at 1"), std::string::npos) << error;
  std::vector<uint8_t> count = withDirections;
  count[section] = 200;  // M no longer matches the size
  EXPECT_FALSE(runtime::parseProbeSh(count.data(), count.size(), back, &error));
  EXPECT_NE(error.find("bytes"), std::string::npos) << error;
  // With depth maps (probe_visibility.h) after the directions.
  file.depth.assign(3 * runtime::kProbeDepthValues, runtime::floatToHalf(1.5f));
  file.depth[5] = runtime::floatToHalf(0.25f);
  const std::vector<uint8_t> withDepth = runtime::serializeProbeSh(file);
  ASSERT_EQ(withDepth.size(), withDirections.size() + 3 * runtime::kProbeDepthValues * 2);
  ASSERT_TRUE(runtime::parseProbeSh(withDepth.data(), withDepth.size(), back, &error)) << error;
  EXPECT_EQ(back.depth, file.depth);
  std::vector<uint8_t> negative = withDepth;
  const uint16_t minus = runtime::floatToHalf(-1.0f);
  const size_t probe2 = withDirections.size() + 2 * runtime::kProbeDepthValues * 2;
  negative[probe2] = uint8_t(minus), negative[probe2 + 1] = uint8_t(minus >> 8);
  EXPECT_FALSE(runtime::parseProbeSh(negative.data(), negative.size(), back, &error));
  EXPECT_NE(error.find("probe 2: its depth map"), std::string::npos) << error;
  file.depth.clear();

  std::vector<uint8_t> length = withDirections;
  const float two = 2.0f;
  std::memcpy(length.data() + section + 4 + 4 * 4 + 6 * 4, &two, 4);  // direction 1's x
  EXPECT_FALSE(runtime::parseProbeSh(length.data(), length.size(), back, &error));
  EXPECT_NE(error.find("direction 1"), std::string::npos) << error;
}

TEST(ProbesFiles, BakeRefusesBadProbesAndWritesNothing) {
  const std::string dir = tempDir("probes_files_bake");
  json index = placement();
  index["tetrahedra"][1] = json::array({1, 7, 2, 3});
  std::ofstream(dir + "/bad.json") << index.dump();
  CliRun bad = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' --quality draft "
                           "--texels-per-unit 16 --quiet --probes '" + dir + "/bad.json'");
  EXPECT_EQ(bad.exitCode, 1) << bad.err;
  EXPECT_NE(bad.err.find("bad.json: tetrahedron 1"), std::string::npos) << bad.err;
  EXPECT_EQ(bad.err.find('\n'), bad.err.size() - 1) << "one line: " << bad.err;
  EXPECT_FALSE(fs::exists(dir + "/out"));

  CliRun budget = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' --quality draft "
                              "--texels-per-unit 16 --quiet --probe-spacing 0.01 --max-probes 500");
  EXPECT_EQ(budget.exitCode, 1) << budget.err;
  EXPECT_NE(budget.err.find("--spacing"), std::string::npos) << budget.err;
  EXPECT_FALSE(fs::exists(dir + "/out"));

  // And a good placement is baked as given.
  std::ofstream(dir + "/good.json") << placement().dump();
  CliRun good = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' --quality draft "
                            "--texels-per-unit 16 --quiet --probes '" + dir + "/good.json'");
  ASSERT_EQ(good.exitCode, 0) << good.err;
  const json written = json::parse(slurp(dir + "/out/probes/light_probes.json"));
  EXPECT_EQ(written["positions"], placement()["positions"]);
  EXPECT_EQ(written["tetrahedra"], placement()["tetrahedra"]);
  runtime::ProbeShFile sh;
  std::string error;
  ASSERT_TRUE(runtime::readProbeSh(dir + "/out/probes/light_probes_sh.bin", sh, &error)) << error;
  EXPECT_EQ(sh.sh.size(), 5u);
}

// Two reflection probes as probes place --reflection writes them, beside the light probes.
json withReflections() {
  json doc = placement();
  doc["reflectionProbes"] = json::parse(R"([
    {"name": "hall", "position": [2.5, 1.5, 2], "size": [5, 3, 4], "blendDistance": 0.75,
     "importance": 1, "boxProjection": true, "resolution": 128},
    {"name": "porch", "position": [7.3, 1.75, 2], "size": [4, 3.5, 4]}])");
  return doc;
}

TEST(ProbesFiles, ReflectionProbesRoundTripAndAreOptional) {
  Result<probes::ProbesFile> none = probes::parseProbesFile(placement().dump(), "p.json");
  ASSERT_TRUE(none) << none.message();
  EXPECT_TRUE(none->reflectionProbes.empty());

  Result<probes::ProbesFile> r = probes::parseProbesFile(withReflections().dump(), "p.json");
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->reflectionProbes.size(), 2u);
  const probes::ReflectionProbeEntry& hall = r->reflectionProbes[0];
  EXPECT_EQ(hall.name, "hall");
  EXPECT_EQ(hall.position, glm::vec3(2.5f, 1.5f, 2.0f));
  EXPECT_EQ(hall.size, glm::vec3(5.0f, 3.0f, 4.0f));
  EXPECT_EQ(hall.blendDistance, 0.75f);
  // The second takes the glTF extras' defaults for what it leaves out.
  const probes::ReflectionProbeEntry& porch = r->reflectionProbes[1];
  EXPECT_EQ(porch.blendDistance, 1.0f);
  EXPECT_EQ(porch.importance, 1);
  EXPECT_TRUE(porch.boxProjection);
  EXPECT_EQ(porch.resolution, 128);

  // Written by probesJson and read back: the same probes, to the float, in tidy decimals.
  std::vector<probes::ReflectionProbeEntry> entries = r->reflectionProbes;
  entries[1].position = glm::vec3(0.1f, 1.234f, -2.5f);
  entries[1].size = glm::vec3(0.3f, 1e-3f, 12.345f);
  entries[1].blendDistance = 0.075f;
  entries[1].importance = -3;
  entries[1].boxProjection = false;
  entries[1].resolution = 2048;
  probes::Placement written;
  written.positions = r->positions;
  written.kinds = r->kinds;
  const std::string text =
      probes::probesJson(written, r->names, r->mesh, "{}", "{}", "", entries);
  EXPECT_NE(text.find("[0.1,1.234,-2.5]"), std::string::npos) << text;
  Result<probes::ProbesFile> again = probes::parseProbesFile(text, "again.json");
  ASSERT_TRUE(again) << again.message();
  ASSERT_EQ(again->reflectionProbes.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const probes::ReflectionProbeEntry &a = entries[i], &b = again->reflectionProbes[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.position, b.position);
    EXPECT_EQ(a.size, b.size);
    EXPECT_EQ(a.blendDistance, b.blendDistance);
    EXPECT_EQ(a.importance, b.importance);
    EXPECT_EQ(a.boxProjection, b.boxProjection);
    EXPECT_EQ(a.resolution, b.resolution);
  }
  // Without reflection probes the file has no such member.
  EXPECT_EQ(probes::probesJson(written, r->names, r->mesh, "{}", "{}").find("reflectionProbes"),
            std::string::npos);
}

TEST(ProbesFiles, BadReflectionProbesNameTheFileAndTheProbe) {
  auto bad = [](const char* key, const json& value) {
    json doc = withReflections();
    doc["reflectionProbes"][1][key] = value;
    return doc;
  };
  const std::string porch = "reflection probe 1 ('porch')";
  std::string e = errorOf(bad("size", json::array({4, -3.5, 4})));
  EXPECT_NE(e.find(porch + ": \"size\" must be three positive"), std::string::npos) << e;
  e = errorOf(bad("size", json::array({4, 0, 4})));
  EXPECT_NE(e.find(porch), std::string::npos) << e;
  e = errorOf(bad("resolution", 100));
  EXPECT_NE(e.find(porch + ": \"resolution\" must be a power of two"), std::string::npos) << e;
  e = errorOf(bad("resolution", 4096));
  EXPECT_NE(e.find(porch), std::string::npos) << e;
  e = errorOf(bad("position", json::array({0, "NaN", 0})));
  EXPECT_NE(e.find(porch + ": \"position\""), std::string::npos) << e;
  e = errorOf(bad("position", json::array({0, 3.5e39, 0})));  // infinite as a float
  EXPECT_NE(e.find(porch + ": \"position\""), std::string::npos) << e;
  e = errorOf(bad("blendDistance", -1));
  EXPECT_NE(e.find(porch + ": \"blendDistance\""), std::string::npos) << e;
  e = errorOf(bad("importance", 1.5));
  EXPECT_NE(e.find(porch + ": \"importance\""), std::string::npos) << e;
  e = errorOf(bad("boxProjection", "yes"));
  EXPECT_NE(e.find(porch + ": \"boxProjection\""), std::string::npos) << e;
  e = errorOf(bad("blendDistnace", 1));
  EXPECT_NE(e.find(porch + ": unknown member \"blendDistnace\""), std::string::npos) << e;
  e = errorOf(bad("name", "hall"));
  EXPECT_NE(e.find("reflection probe 1 ('hall'): the name is taken"), std::string::npos) << e;
  e = errorOf(bad("name", 7));
  EXPECT_NE(e.find("reflection probe 1 has no \"name\""), std::string::npos) << e;

  json missing = withReflections();
  missing["reflectionProbes"][0].erase("size");
  e = errorOf(missing);
  EXPECT_NE(e.find("reflection probe 0 ('hall'): \"size\""), std::string::npos) << e;
  json notArray = placement();
  notArray["reflectionProbes"] = json::object();
  EXPECT_NE(errorOf(notArray).find("\"reflectionProbes\" is not an array"), std::string::npos);
  json notObject = placement();
  notObject["reflectionProbes"] = json::array({1});
  EXPECT_NE(errorOf(notObject).find("reflection probe 0 is not an object"), std::string::npos);
}

}  // namespace
}  // namespace afterglow::test
