// Pieces shared by the afterglow subcommands: parsing their arguments and reporting usage errors
// once, loading SCENE arguments, errors, Ctrl-C.
#pragma once

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/core/timer.h"
#include "afterglow/scenes/scene.h"
#include "args.h"

namespace afterglow::cli {

// "a,b,c,...": comma-separated finite floats, nothing else. False when malformed.
bool parseFloats(const std::string& text, std::vector<float>& out);
// Exactly three of them ("r,g,b", "x,y,z").
bool parseVec3(const std::string& text, glm::vec3* out);

// Prints "afterglow: <message>" to stderr.
void printError(const std::string& message);
// Whether s ends in suffix (output file extensions).
bool endsWith(const std::string& s, const std::string& suffix);

// A subcommand as its messages and its help name it.
struct Command {
  const char* name;       // "probes place": starts its usage errors
  const char* helpTopic;  // "probes": the help its usage errors point to
  const char* help;       // what --help prints (before the exit codes)

  // Prints "afterglow: <name>: <message> (see afterglow <helpTopic> --help)"; returns
  // kExitUsage.
  int usage(const std::string& message) const;
};

// Prints a command's help text, then the exit codes.
void printHelp(const char* help);
// Parses a command's arguments into `args`. The exit code to stop with when there is nothing
// more to do: kExitUsage after a parse error (printed), kExitOk after --help (printed);
// nullopt to go on.
std::optional<int> parseOrExit(Args& args, int argc, char** argv, int first,
                               const std::vector<OptionSpec>& specs, const Command& command);

// True when SCENE names a built-in scene ("builtin:cornell", "builtin:furnace").
bool isBuiltinScene(const std::string& scene);
// Loads a .gltf/.glb path or a built-in scene for a command. On failure (printed) *exitCode says
// how to stop: kExitInterrupted for a Ctrl-C during the load (checked first: a large level loads
// a while and the load itself is not interrupted), kExitUsage when the argument itself is wrong
// (an unknown built-in name), kExitBadInput when the file is. loadNormalTextures decodes the
// normal textures and reads a baked indirect grid's UVs too (scenes::LoadOptions), for reading
// directional lightmaps.
Result<scenes::Scene> loadSceneOrExit(const std::string& scene, bool loadTextures,
                                      int* exitCode, bool loadNormalTextures = false);

// `--unit-scale X`, in the option list of every command that reads a level for its geometry
// (info, bake, probes place): the level's metres per unit.
extern const OptionSpec kUnitScaleOption;
// --unit-scale's value (1 without it); false with args.error() set when it is not a positive
// number.
bool getUnitScale(Args& args, float* unitScale);
// Scales a loaded level by unitScale (scenes::scaleScene) before anything reads it, then judges
// its units (scenes/units.h): a level still not in metres gets the warning among its
// warnings, which info, bake and probes place print and the bake's report keeps.
void applyUnitScale(scenes::Scene& scene, float unitScale, const std::string& input);

// Ctrl-C handling. installInterruptHandler(), first thing in main, makes the first SIGINT only
// record the interrupt (interrupted() turns true) and cancel the Progress of the living
// InterruptGuard, if any; it also puts back the default action, so a second Ctrl-C kills the
// process. Every command that writes output checks interrupted() before it starts writing (and
// before it commits), so an interrupt at any point, loading included, exits 130 with nothing
// written.
void installInterruptHandler();
// While a guard lives, SIGINT cancels the given Progress (the work stops at its next check). A
// guard made after an interrupt cancels its Progress at once.
class InterruptGuard {
 public:
  explicit InterruptGuard(Progress& progress);
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
};
bool interrupted();
// Prints "interrupted; nothing written" and returns kExitInterrupted (130).
int interruptedExit();

}  // namespace afterglow::cli
