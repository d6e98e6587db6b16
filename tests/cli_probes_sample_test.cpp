// `afterglow probes sample` run as a user would: at a probe's own position it gives that probe's
// SH from the bake's light_probes_sh.bin (the transport solved as the bake solved it), its E/π
// per normal is that SH's, as text or JSON; a missing transport, a bake without probes and bad
// vectors are refused with one line naming the file or the argument.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "test_util.h"

using nlohmann::json;

namespace afterglow::test {
namespace {

const char* kBake = "--quality draft --texels-per-unit 32 --quiet";

// x,y,z that parse back to the same floats.
std::string point(const json& p) {
  char text[128];
  std::snprintf(text, sizeof text, "%.9g,%.9g,%.9g", p[0].get<double>(), p[1].get<double>(),
                p[2].get<double>());
  return text;
}

TEST(CliProbesSample, AtAProbeGivesItsShFromTheBakesFile) {
  const std::string dir = tempDir("cli_probes_sample");
  CliRun bake = runCli(dir, "bake builtin:cornell -o '" + dir + "/out' " + kBake);
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  const json probes = json::parse(slurp(dir + "/out/probes/light_probes.json"));
  runtime::ProbeShFile file;
  std::string error;
  ASSERT_TRUE(runtime::readProbeSh(dir + "/out/probes/light_probes_sh.bin", file, &error)) << error;
  const size_t n = file.sh.size();
  ASSERT_EQ(probes.at("positions").size(), n);
  ASSERT_GT(n, 100u);
  EXPECT_FALSE(file.directions.lights.empty()) << "the lamp is read as a direction";

  const std::vector<size_t> which = {0, n / 3, n / 2, n - 1};
  std::string at;
  for (size_t i : which) at += " --at " + point(probes["positions"][i]);
  CliRun run = runCli(dir, "probes sample '" + dir + "/out'" + at + " --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  const json got = json::parse(run.out, nullptr, false);
  ASSERT_TRUE(got.is_array()) << run.out;
  ASSERT_EQ(got.size(), which.size());
  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (size_t k = 0; k < which.size(); ++k) {
    const runtime::ShL2& want = file.sh[which[k]];
    const json& g = got[k];
    EXPECT_TRUE(g.at("inside").get<bool>()) << "probe " << which[k];
    // The probe itself carries (all but) the whole weight.
    float weight = 0.0f;
    for (size_t c = 0; c < 4; ++c)
      if (g.at("probes")[c].get<size_t>() == which[k]) weight = g.at("weights")[c].get<float>();
    EXPECT_NEAR(weight, 1.0f, 1e-6f) << "probe " << which[k];
    ASSERT_EQ(g.at("sh").size(), 27u);
    float scale = 0.0f;
    for (const glm::vec3& c : want.c) scale = std::max({scale, std::abs(c.r), std::abs(c.g), std::abs(c.b)});
    ASSERT_GT(scale, 0.0f);
    for (size_t i = 0; i < 27; ++i)
      EXPECT_NEAR(g["sh"][i].get<float>(), want.c[i / 3][int(i % 3)], 1e-6f * scale)
          << "probe " << which[k] << " coefficient " << i;
    // E/π: the SH with the probe's small sources as directions, as the file holds them.
    ASSERT_EQ(file.directions.count(), n);
    runtime::ProbeLighting lighting{want, {}};
    for (uint32_t d = file.directions.start[which[k]]; d < file.directions.start[which[k] + 1]; ++d)
      lighting.lights.push_back(file.directions.lights[d]);
    ASSERT_EQ(g.at("directions").size(), lighting.lights.size()) << "probe " << which[k];
    ASSERT_EQ(g.at("irradiance").size(), 6u);
    for (size_t a = 0; a < 6; ++a) {
      const glm::vec3 e = lighting.irradianceOverPi(axes[a], file.deringWindow);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(g["irradiance"][a]["value"][size_t(c)].get<float>(), e[c], 1e-5f * scale)
            << "probe " << which[k] << " normal " << a;
    }
  }

  // As text: a line per point, x,y,z then E/π for the given normal.
  const size_t probe = which[1];
  CliRun text = runCli(dir, "probes sample '" + dir + "/out' --at " +
                                point(probes["positions"][probe]) + " --at 0.2,0.3,0.25 " +
                                "--normal 0,2,0");
  ASSERT_EQ(text.exitCode, 0) << text.err;
  std::istringstream lines(text.out);
  std::string first, second, extra;
  ASSERT_TRUE(std::getline(lines, first));
  ASSERT_TRUE(std::getline(lines, second));
  EXPECT_FALSE(std::getline(lines, extra)) << text.out;
  const size_t value = first.find("n=0,1,0 ");
  ASSERT_NE(value, std::string::npos) << first;
  float r = 0, g = 0, b = 0;
  ASSERT_EQ(std::sscanf(first.c_str() + value + 8, "%f,%f,%f", &r, &g, &b), 3) << first;
  runtime::ProbeLighting atProbe{file.sh[probe], {}};
  for (uint32_t d = file.directions.start[probe]; d < file.directions.start[probe + 1]; ++d)
    atProbe.lights.push_back(file.directions.lights[d]);
  const glm::vec3 up = atProbe.irradianceOverPi({0, 1, 0}, file.deringWindow);
  EXPECT_NEAR(r, up.r, 1e-5f * up.r);
  EXPECT_NEAR(g, up.g, 1e-5f * up.g);
  EXPECT_NEAR(b, up.b, 1e-5f * up.b);
  EXPECT_EQ(second.rfind("0.2,0.3,0.25  n=0,1,0 ", 0), 0u) << second;
}

TEST(CliProbesSample, BadFoldersAndArgumentsAreRefusedNamingThem) {
  const std::string dir = tempDir("cli_probes_sample_errors");
  CliRun missing = runCli(dir, "probes sample '" + dir + "/nowhere' --at 0,0,0");
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_NE(missing.err.find("nowhere/transport.agt"), std::string::npos) << missing.err;

  CliRun bake = runCli(dir, "bake builtin:cornell -o '" + dir + "/none' --probes none " + kBake);
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  CliRun none = runCli(dir, "probes sample '" + dir + "/none' --at 0.2,0.2,0.2");
  EXPECT_EQ(none.exitCode, 1);
  EXPECT_NE(none.err.find("transport.agt: has no light probes"), std::string::npos) << none.err;

  const std::string out = "probes sample '" + dir + "/none'";
  CliRun vector = runCli(dir, out + " --at 0.2,0.2");
  EXPECT_EQ(vector.exitCode, 2);
  EXPECT_NE(vector.err.find("--at wants x,y,z"), std::string::npos) << vector.err;
  EXPECT_NE(vector.err.find("'0.2,0.2'"), std::string::npos) << vector.err;
  CliRun normal = runCli(dir, out + " --at 0.2,0.2,0.2 --normal 0,0,0");
  EXPECT_EQ(normal.exitCode, 2);
  EXPECT_NE(normal.err.find("--normal"), std::string::npos) << normal.err;
  CliRun noPoint = runCli(dir, out);
  EXPECT_EQ(noPoint.exitCode, 2);
  EXPECT_NE(noPoint.err.find("--at"), std::string::npos) << noPoint.err;
  for (const CliRun* r : {&missing, &none, &vector, &normal, &noPoint}) {
    EXPECT_EQ(r->out, "");
    EXPECT_EQ(std::count(r->err.begin(), r->err.end(), '\n'), 1) << r->err;
  }
}

}  // namespace
}  // namespace afterglow::test
