#include "common.h"

#include <signal.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>

#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/scenes/units.h"
#include "commands.h"

namespace afterglow::cli {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

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

int Command::usage(const std::string& message) const {
  printError(std::string(name) + ": " + message + " (see afterglow " + helpTopic + " --help)");
  return kExitUsage;
}

void printHelp(const char* help) { std::printf("%s\n%s", help, kExitCodesHelp); }

std::optional<int> parseOrExit(Args& args, int argc, char** argv, int first,
                               const std::vector<OptionSpec>& specs, const Command& command) {
  if (!args.parse(argc, argv, first, specs)) return command.usage(args.error());
  if (args.has("help")) {
    printHelp(command.help);
    return kExitOk;
  }
  return std::nullopt;
}

namespace {
constexpr const char kBuiltinPrefix[] = "builtin:";
}

bool isBuiltinScene(const std::string& scene) { return scene.rfind(kBuiltinPrefix, 0) == 0; }

namespace {

// *usageError is set when the argument itself is wrong rather than the file.
Result<scenes::Scene> loadSceneArgument(const std::string& scene, bool loadTextures,
                                        bool loadNormalTextures, bool* usageError) {
  *usageError = false;
  if (isBuiltinScene(scene)) {
    std::string name = scene.substr(sizeof(kBuiltinPrefix) - 1);
    if (name == "cornell") return scenes::makeCornellBox();
    if (name == "cornell-metal") return scenes::makeCornellMetalBox();
    if (name == "furnace") return scenes::makeFurnaceBox();
    *usageError = true;
    return Status::error(format("unknown built-in scene '%s' (there are builtin:cornell, "
                                "builtin:cornell-metal and builtin:furnace)",
                                scene.c_str()));
  }
  scenes::LoadOptions options;
  options.loadTextures = loadTextures;
  options.loadNormalTextures = loadTextures && loadNormalTextures;
  options.loadIndirectUvs = loadNormalTextures;
  return scenes::loadGltf(scene, options);
}

}  // namespace

Result<scenes::Scene> loadSceneOrExit(const std::string& scene, bool loadTextures,
                                      int* exitCode, bool loadNormalTextures) {
  bool badArgument = false;
  Result<scenes::Scene> loaded =
      loadSceneArgument(scene, loadTextures, loadNormalTextures, &badArgument);
  if (interrupted()) {
    *exitCode = interruptedExit();
    return Status::error("interrupted");
  }
  if (!loaded) {
    printError(loaded.message());
    *exitCode = badArgument ? kExitUsage : kExitBadInput;
  }
  return loaded;
}

const OptionSpec kUnitScaleOption = {"unit-scale"};

bool getUnitScale(Args& args, float* unitScale) {
  return args.getFloat("unit-scale", 1.0f, 0.0f, 1e6f, unitScale);
}

void applyUnitScale(scenes::Scene& scene, float unitScale, const std::string& input) {
  if (unitScale != 1.0f) scenes::scaleScene(scene, unitScale);
  const std::string warning = scenes::unitsWarning(scenes::guessUnits(scene), input);
  if (!warning.empty()) scene.warnings.push_back(warning);
}

namespace {
// Lock-free state only: the handler may run on any thread at any moment.
std::atomic<Progress*> gProgress{nullptr};
volatile std::sig_atomic_t gInterrupted = 0;
static_assert(std::atomic<Progress*>::is_always_lock_free, "the SIGINT handler needs it");

extern "C" void onInterrupt(int) {
  gInterrupted = 1;
  if (Progress* progress = gProgress.load()) progress->cancel();
  // SA_RESETHAND has already put back the default action: a second Ctrl-C kills the process.
}
}  // namespace

void installInterruptHandler() {
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND | SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
}

InterruptGuard::InterruptGuard(Progress& progress) {
  // Published before the check, so an interrupt arriving in between is seen by one or the other.
  gProgress.store(&progress);
  if (interrupted()) progress.cancel();
}

InterruptGuard::~InterruptGuard() { gProgress.store(nullptr); }

bool interrupted() { return gInterrupted != 0; }

int interruptedExit() {
  printError("interrupted; nothing written");
  return kExitInterrupted;
}

}  // namespace afterglow::cli
