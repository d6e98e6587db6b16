// Helpers shared by the tests.
#pragma once

#include <string>

namespace afterglow::test {

// Path to ../shared/scenes/<relative>, or "" when ../shared is absent (a user's fresh clone).
std::string sharedScene(const std::string& relative);
// A fresh empty folder under the build tree for one test's files.
std::string tempDir(const std::string& name);
// A whole file's bytes ("" when it cannot be read).
std::string slurp(const std::string& path);

// The built `afterglow` binary run as a user would, through the shell.
struct CliRun {
  int exitCode = -1;
  std::string out, err;
};
// Runs `afterglow <args>`, capturing stdout and stderr through files in `dir`.
CliRun runCli(const std::string& dir, const std::string& args);

}  // namespace afterglow::test

// Skips the current test with a clear message when a shared scene is missing.
#define AG_REQUIRE_SHARED_SCENE(var, relative)                                          \
  std::string var = ::afterglow::test::sharedScene(relative);                           \
  if (var.empty()) GTEST_SKIP() << "../shared/scenes/" << relative                      \
                                << " is absent (it sits beside the checkout in CI)"
