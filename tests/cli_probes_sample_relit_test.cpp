// `afterglow probes sample RELIT/` on the folder `afterglow relight` wrote (no transport; its
// relit probes in probes/light_probes.json and light_probes_sh.bin): at a probe it gives that
// probe's relit SH from the file, between probes what the runtime gives for the relit transport
// (the relight's own solve, through bakefiles/relight.h), and the relight changed them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/bakefiles/relight.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "test_util.h"

using nlohmann::json;

namespace afterglow::test {
namespace {

// The 27 SH floats per point that `probes sample --json` printed.
std::vector<std::vector<float>> sampledSh(const std::string& dir, const std::string& folder,
                                          const std::string& at) {
  CliRun run = runCli(dir, "probes sample '" + folder + "'" + at + " --json");
  EXPECT_EQ(run.exitCode, 0) << run.err;
  std::vector<std::vector<float>> out;
  const json got = json::parse(run.out, nullptr, false);
  if (!got.is_array()) return out;
  for (const json& point : got) out.push_back(point.at("sh").get<std::vector<float>>());
  return out;
}

float largest(const std::vector<float>& sh) {
  float m = 1e-30f;
  for (float v : sh) m = std::max(m, std::abs(v));
  return m;
}

// DIR/out, the Cornell box baked, and DIR/relit, it relit under a blue sky: the exit codes.
std::pair<int, int> bakeAndRelight(const std::string& dir) {
  const CliRun bake =
      runCli(dir, "bake builtin:cornell --quality draft --texels-per-unit 32 --quiet -o '" +
                      dir + "/out'");
  EXPECT_EQ(bake.exitCode, 0) << bake.err;
  const CliRun relight =
      runCli(dir, "relight --sky 0.5,0.7,1.4 --quiet -o '" + dir + "/relit' '" + dir + "/out'");
  EXPECT_EQ(relight.exitCode, 0) << relight.err;
  return {bake.exitCode, relight.exitCode};
}

TEST(CliProbesSampleRelit, ARelitFolderGivesTheRelitProbes) {
  const std::string dir = tempDir("cli_probes_sample_relit");
  ASSERT_EQ(bakeAndRelight(dir), std::make_pair(0, 0));

  runtime::ProbeShFile file;
  std::string error;
  ASSERT_TRUE(runtime::readProbeSh(dir + "/relit/probes/light_probes_sh.bin", file, &error))
      << error;
  const json placement = json::parse(slurp(dir + "/relit/probes/light_probes.json"));
  const size_t probe = file.sh.size() / 3;
  const json& p = placement.at("positions").at(probe);
  char onProbe[128];
  std::snprintf(onProbe, sizeof onProbe, " --at %.9g,%.9g,%.9g", p[0].get<double>(),
                p[1].get<double>(), p[2].get<double>());
  const std::vector<glm::vec3> between = {{0.28f, 0.3f, 0.28f}, {0.1f, 0.45f, 0.2f},
                                          {0.45f, 0.1f, 0.05f}};
  std::string at = onProbe;
  for (const glm::vec3& q : between)
    at += " --at " + std::to_string(q.x) + "," + std::to_string(q.y) + "," + std::to_string(q.z);
  const std::vector<std::vector<float>> relit = sampledSh(dir, dir + "/relit", at);
  const std::vector<std::vector<float>> baked = sampledSh(dir, dir + "/out", at);
  ASSERT_EQ(relit.size(), 1 + between.size());
  ASSERT_EQ(baked.size(), relit.size());

  // On a probe: its relit SH as the file holds it.
  for (size_t i = 0; i < 27; ++i)
    EXPECT_NEAR(relit[0][i], file.sh[probe].c[i / 3][int(i % 3)], 1e-6f * largest(relit[0]))
        << "coefficient " << i;

  // Between probes: what the runtime gives for the relit transport.
  bakefiles::RelitBake rt;
  ASSERT_FALSE(bakefiles::openBakeForRelight(dir + "/out", &rt));
  bakefiles::RelightChanges changes;
  changes.sky = glm::vec3(0.5f, 0.7f, 1.4f);
  ASSERT_FALSE(bakefiles::applyRelightChanges(changes, rt));
  ASSERT_FALSE(bakefiles::relightBake(rt));
  for (size_t k = 0; k < between.size(); ++k) {
    int hint = 0;
    const runtime::ShL2 want = rt.runtime->sampleProbes(between[k], &hint);
    const std::vector<float>& got = relit[1 + k];
    for (size_t i = 0; i < 27; ++i)
      EXPECT_NEAR(got[i], want.c[i / 3][int(i % 3)], 1e-5f * largest(got))
          << "point " << k << " coefficient " << i;
    // The sky did change them (the box is open towards -Z).
    EXPECT_GT(got[0], baked[1 + k][0] * 1.01f) << "point " << k;
  }
}

}  // namespace
}  // namespace afterglow::test
