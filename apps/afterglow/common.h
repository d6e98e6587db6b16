// Pieces shared by the afterglow subcommands: loading SCENE arguments, errors, Ctrl-C.
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/core/timer.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::cli {

// "a,b,c,...": comma-separated finite floats, nothing else. False when malformed.
bool parseFloats(const std::string& text, std::vector<float>& out);
// Exactly three of them ("r,g,b", "x,y,z").
bool parseVec3(const std::string& text, glm::vec3* out);

// Prints "afterglow: <message>" to stderr.
void printError(const std::string& message);
// Whether s ends in suffix (output file extensions).
bool endsWith(const std::string& s, const std::string& suffix);

// True when SCENE names a built-in scene ("builtin:cornell", "builtin:furnace").
bool isBuiltinScene(const std::string& scene);
// Loads a .gltf/.glb path or a built-in scene. *usageError is set when the argument itself is
// wrong (an unknown built-in name) rather than the file.
Result<scenes::Scene> loadSceneArgument(const std::string& scene, bool loadTextures,
                                        bool* usageError);

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
