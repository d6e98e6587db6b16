// Helpers shared by the tests.
#pragma once

#include <string>

namespace afterglow::test {

// Path to ../shared/scenes/<relative>, or "" when ../shared is absent (a user's fresh clone).
std::string sharedScene(const std::string& relative);
// A fresh empty folder under the build tree for one test's files.
std::string tempDir(const std::string& name);

}  // namespace afterglow::test

// Skips the current test with a clear message when a shared scene is missing.
#define AG_REQUIRE_SHARED_SCENE(var, relative)                                          \
  std::string var = ::afterglow::test::sharedScene(relative);                           \
  if (var.empty()) GTEST_SKIP() << "../shared/scenes/" << relative                      \
                                << " is absent (it sits beside the checkout in CI)"
