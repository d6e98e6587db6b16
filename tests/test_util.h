// Helpers shared by the tests.
#pragma once

#include <string>
#include <vector>

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

// `afterglow <args>` started in the background, stdout to /dev/null and stderr through a pipe
// (so progress prints one plain line per stage as it ends): for interrupting it at a known point
// of its work rather than after a guessed time, which its start-up (loading hundreds of shared
// libraries before main) can outlast on a loaded machine.
class CliChild {
 public:
  explicit CliChild(const std::vector<std::string>& args);
  // Kills and reaps the child if it is still running.
  ~CliChild();
  CliChild(const CliChild&) = delete;
  CliChild& operator=(const CliChild&) = delete;

  int pid() const { return pid_; }
  bool started() const { return pid_ > 0; }
  // Reads stderr until it holds `text` (true) or the child closes it (false).
  bool waitForStderr(const std::string& text);
  // Sends SIGINT, reads stderr to its end (so the child never writes to a closed pipe) and
  // reaps the child. Returns its wait status; *cpuSeconds, when given, gets its processor time.
  int interruptAndWait(double* cpuSeconds = nullptr);
  // What the child wrote to stderr so far.
  const std::string& err() const { return err_; }

 private:
  int pid_ = -1;
  int fd_ = -1;
  std::string err_;
};

}  // namespace afterglow::test

// Skips the current test with a clear message when a shared scene is missing.
#define AG_REQUIRE_SHARED_SCENE(var, relative)                                          \
  std::string var = ::afterglow::test::sharedScene(relative);                           \
  if (var.empty()) GTEST_SKIP() << "../shared/scenes/" << relative                      \
                                << " is absent (it sits beside the checkout in CI)"
