#include "common.h"

#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>

#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"

namespace afterglow::cli {

bool parseFloats(const std::string& text, std::vector<float>& out) {
  out.clear();
  const char* p = text.c_str();
  while (true) {
    char* end = nullptr;
    const float v = std::strtof(p, &end);
    if (end == p || !std::isfinite(v)) return false;
    out.push_back(v);
    if (*end == '\0') return true;
    if (*end != ',') return false;
    p = end + 1;
  }
}

bool parseVec3(const std::string& text, glm::vec3* out) {
  std::vector<float> v;
  if (!parseFloats(text, v) || v.size() != 3) return false;
  *out = glm::vec3(v[0], v[1], v[2]);
  return true;
}

void printError(const std::string& message) {
  std::fprintf(stderr, "afterglow: %s\n", message.c_str());
}

namespace {
constexpr const char kBuiltinPrefix[] = "builtin:";
}

bool isBuiltinScene(const std::string& scene) { return scene.rfind(kBuiltinPrefix, 0) == 0; }

Result<scenes::Scene> loadSceneArgument(const std::string& scene, bool loadTextures,
                                        bool* usageError) {
  *usageError = false;
  if (isBuiltinScene(scene)) {
    std::string name = scene.substr(sizeof(kBuiltinPrefix) - 1);
    if (name == "cornell") return scenes::makeCornellBox();
    if (name == "furnace") return scenes::makeFurnaceBox();
    *usageError = true;
    return Status::error(format("unknown built-in scene '%s' (there are builtin:cornell and "
                                "builtin:furnace)",
                                scene.c_str()));
  }
  scenes::LoadOptions options;
  options.loadTextures = loadTextures;
  return scenes::loadGltf(scene, options);
}

namespace {
// Plain pointers and a sig_atomic_t: the handler may only touch lock-free state.
Progress* volatile gProgress = nullptr;
volatile std::sig_atomic_t gInterrupted = 0;

extern "C" void onInterrupt(int) {
  gInterrupted = 1;
  if (gProgress) gProgress->cancel();
  std::signal(SIGINT, SIG_DFL);
}
}  // namespace

InterruptGuard::InterruptGuard(Progress& progress) {
  gProgress = &progress;
  std::signal(SIGINT, onInterrupt);
}

InterruptGuard::~InterruptGuard() {
  std::signal(SIGINT, SIG_DFL);
  gProgress = nullptr;
}

bool interrupted() { return gInterrupted != 0; }

}  // namespace afterglow::cli
