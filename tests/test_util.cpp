#include "test_util.h"

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace afterglow::test {

std::string sharedScene(const std::string& relative) {
  fs::path p = fs::path(AFTERGLOW_SHARED_DIR) / "scenes" / relative;
  return fs::exists(p) ? p.lexically_normal().string() : std::string();
}

std::string tempDir(const std::string& name) {
  fs::path p = fs::path(AFTERGLOW_BINARY_DIR) / "test_tmp" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CliRun runCli(const std::string& dir, const std::string& args) {
  const std::string out = dir + "/.stdout", err = dir + "/.stderr";
  const std::string command =
      std::string("'") + AFTERGLOW_CLI + "' " + args + " >'" + out + "' 2>'" + err + "'";
  const int status = std::system(command.c_str());
  CliRun r;
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  fs::remove(out);
  fs::remove(err);
  return r;
}

}  // namespace afterglow::test
