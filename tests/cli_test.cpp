// The `afterglow` command line, run as a user would: exit codes, files written, and nothing
// written when the input is bad.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include <nlohmann/json.hpp>

#include "test_util.h"

namespace fs = std::filesystem;

namespace afterglow::test {
namespace {

// Files in dir other than the captured output; the CLI must leave nothing else on failure.
std::vector<std::string> filesIn(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(Cli, VersionPrintsTheProjectVersion) {
  std::string dir = tempDir("cli_version");
  CliRun r = runCli(dir, "--version");
  EXPECT_EQ(r.exitCode, 0);
  EXPECT_EQ(r.out.rfind("afterglow ", 0), 0u) << r.out;
  EXPECT_NE(r.out.find('.'), std::string::npos) << r.out;
}

TEST(Cli, HelpOnTheProgramAndEverySubcommand) {
  std::string dir = tempDir("cli_help");
  CliRun main = runCli(dir, "--help");
  EXPECT_EQ(main.exitCode, 0);
  EXPECT_NE(main.out.find("Exit codes"), std::string::npos);
  CliRun uv = runCli(dir, "uv --help");
  EXPECT_EQ(uv.exitCode, 0);
  EXPECT_NE(uv.out.find("Usage: afterglow uv SCENE -o OUT.gltf"), std::string::npos) << uv.out;
  EXPECT_NE(uv.out.find("--texels-per-unit"), std::string::npos);
  CliRun info = runCli(dir, "info -h");
  EXPECT_EQ(info.exitCode, 0);
  EXPECT_NE(info.out.find("Usage: afterglow info SCENE"), std::string::npos) << info.out;
}

TEST(Cli, UsageErrorsExitTwo) {
  std::string dir = tempDir("cli_usage");
  CliRun unknown = runCli(dir, "uv builtin:cornell -o '" + dir + "/x.gltf' --bogus 3");
  EXPECT_EQ(unknown.exitCode, 2);
  EXPECT_NE(unknown.err.find("afterglow: uv: unknown option '--bogus'"), std::string::npos)
      << unknown.err;
  EXPECT_EQ(runCli(dir, "").exitCode, 2);
  EXPECT_EQ(runCli(dir, "frobnicate").exitCode, 2);
  EXPECT_EQ(runCli(dir, "uv builtin:cornell").exitCode, 2);  // no -o
  EXPECT_EQ(runCli(dir, "uv builtin:cornell -o '" + dir + "/x.gltf' --padding lots").exitCode, 2);
  EXPECT_EQ(runCli(dir, "uv builtin:nothing -o '" + dir + "/x.gltf'").exitCode, 2);
  EXPECT_TRUE(filesIn(dir).empty());
}

TEST(Cli, UvOnTheBuiltinCornellBoxWritesGltfPicturesAndReport) {
  std::string dir = tempDir("cli_uv_cornell");
  CliRun r = runCli(dir, "uv builtin:cornell -o '" + dir + "/cornell.gltf' --quiet --threads 2");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(r.out.empty()) << "--quiet printed: " << r.out;
  EXPECT_EQ(filesIn(dir), (std::vector<std::string>{"cornell.bin", "cornell.gltf",
                                                    "cornell_atlas0.png", "cornell_uv.json"}));

  nlohmann::json gltf = nlohmann::json::parse(slurp(dir + "/cornell.gltf"));
  size_t withUv1 = 0, primitives = 0;
  for (const auto& mesh : gltf["meshes"])
    for (const auto& prim : mesh["primitives"]) {
      ++primitives;
      withUv1 += prim["attributes"].contains("TEXCOORD_1") ? 1 : 0;
    }
  EXPECT_EQ(withUv1, primitives);
  EXPECT_EQ(primitives, 8u);  // 5 walls, 2 blocks, the lamp: each instance its own mesh
  size_t lightmapped = 0;
  for (const auto& node : gltf["nodes"]) {
    if (!node.contains("mesh")) continue;
    const auto& lm = node["extras"]["afterglow"]["lightmap"];
    EXPECT_EQ(lm["atlas"], 0);
    EXPECT_GE(lm["width"].get<int>(), 16);
    EXPECT_GE(lm["height"].get<int>(), 16);
    ++lightmapped;
  }
  EXPECT_EQ(lightmapped, 8u);

  nlohmann::json report = nlohmann::json::parse(slurp(dir + "/cornell_uv.json"));
  EXPECT_EQ(report["metrics"]["overlappingTexels"], 0);
  EXPECT_EQ(report["options"]["uv"], "generate");
  EXPECT_EQ(report["instances"]["lightmapped"], 8);
  EXPECT_TRUE(report["timings"].contains("charts"));

  // The result reads back, and its authored UVs pass --uv keep.
  CliRun info = runCli(dir, "info '" + dir + "/cornell.gltf'");
  EXPECT_EQ(info.exitCode, 0) << info.err;
  EXPECT_NE(info.out.find("8 of 8 static instances have TEXCOORD_1"), std::string::npos)
      << info.out;
  std::string keepDir = tempDir("cli_uv_cornell_keep");
  CliRun keep = runCli(keepDir, "uv '" + dir + "/cornell.gltf' --uv keep -o '" + keepDir +
                                 "/kept.gltf'");
  EXPECT_EQ(keep.exitCode, 0) << keep.err;
  // The layout recorded in extras.afterglow.lightmap is kept: still one shared atlas.
  EXPECT_NE(keep.out.find("atlases       1: "), std::string::npos) << keep.out;
}

TEST(Cli, KeepWithoutAuthoredUvsExitsOneAndWritesNothing) {
  std::string dir = tempDir("cli_keep_missing");
  CliRun r = runCli(dir, "uv builtin:cornell --uv keep -o '" + dir + "/out.gltf'");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("has no TEXCOORD_1"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--uv generate"), std::string::npos) << r.err;
  EXPECT_TRUE(filesIn(dir).empty());
}

TEST(Cli, BrokenGltfExitsOneNamingTheFileAndWritesNothing) {
  std::string dir = tempDir("cli_broken");
  const std::string broken = dir + "/broken.gltf";
  std::ofstream(broken) << "{ \"asset\": { \"version\": \"2.0\" }, \"meshes\": [ { \"primitives\"";
  std::string outDir = tempDir("cli_broken_out");
  CliRun r = runCli(outDir, "uv '" + broken + "' -o '" + outDir + "/out.gltf'");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err.rfind("afterglow: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("broken.gltf"), std::string::npos) << r.err;
  EXPECT_TRUE(filesIn(outDir).empty());
  CliRun info = runCli(outDir, "info '" + broken + "'");
  EXPECT_EQ(info.exitCode, 1);
  EXPECT_NE(info.err.find("broken.gltf"), std::string::npos) << info.err;

  CliRun missing = runCli(outDir, "info '" + dir + "/does_not_exist.gltf'");
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_NE(missing.err.find("does_not_exist.gltf"), std::string::npos) << missing.err;
}

TEST(Cli, UnwritableOutputExitsThree) {
  std::string dir = tempDir("cli_unwritable");
  // A regular file where the output folder should be.
  std::ofstream(dir + "/blocker") << "x";
  CliRun r = runCli(dir, "uv builtin:furnace -o '" + dir + "/blocker/out.gltf' --quiet");
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"blocker"});
}

// The processor time a running child has used so far (all its threads), from /proc; -1 when
// it cannot be read.
double processorSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t name = stat.rfind(')');  // the command name may hold spaces
  if (name == std::string::npos) return -1.0;
  std::istringstream fields(stat.substr(name + 2));
  std::string field;
  // Fields 3 (state) to 13 precede utime (14) and stime (15).
  for (int i = 3; i <= 13 && fields >> field; ++i) {
  }
  unsigned long long user = 0, system = 0;
  if (!(fields >> user >> system)) return -1.0;
  return double(user + system) / double(sysconf(_SC_CLK_TCK));
}

TEST(Cli, CtrlCExits130AndWritesNothing) {
  AG_REQUIRE_SHARED_SCENE(sponza, "sponza/Sponza.gltf");
  std::string dir = tempDir("cli_interrupt");
  const std::string out = dir + "/sponza.gltf";
  // Progress lines arrive one per stage as it ends.
  CliChild child({"uv", sponza, "-o", out, "--threads", "2", "--texels-per-unit", "32"});
  ASSERT_TRUE(child.started());
  // Interrupt once the charts are done, while it packs Sponza at 32 texels per metre (which
  // takes many seconds, so the signal always lands inside the packing).
  ASSERT_TRUE(child.waitForStderr("charts")) << child.err();
  // Promptness in the child's processor time after the signal, not in wall time: with other
  // tests running beside this one, the child may wait seconds for a processor.
  const double before = processorSeconds(child.pid());
  ASSERT_GE(before, 0.0);
  double total = 0.0;
  const int status = child.interruptAndWait(&total);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status) << "\n" << child.err();
  EXPECT_EQ(WEXITSTATUS(status), 130) << child.err();
  EXPECT_TRUE(filesIn(dir).empty());
  // Two threads for under two seconds.
  EXPECT_LT(total - before, 4.0) << "the packing did not stop promptly";
}

TEST(Cli, InfoDescribesTheBuiltinCornellBox) {
  std::string dir = tempDir("cli_info");
  CliRun r = runCli(dir, "info builtin:cornell");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("instances     8 (8 static, 0 dynamic)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cameras       1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("materials     4 (1 emissive)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("size          0.556 x 0.549 x 0.559 m"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace afterglow::test
