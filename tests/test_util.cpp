#include "test_util.h"

#include <filesystem>

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

}  // namespace afterglow::test
