// afterglow: the command-line front end. Subcommands live in cmd_*.cpp.
#include <cstdio>
#include <cstring>
#include <string>

#include "args.h"
#include "commands.h"
#include "common.h"

namespace afterglow::cli {

const char kExitCodesHelp[] =
    "Exit codes:\n"
    "  0    success\n"
    "  1    bad input: the scene could not be loaded or failed validation (e.g. --uv keep)\n"
    "  2    usage error: unknown option, missing or malformed argument\n"
    "  3    an output file could not be written\n"
    "  130  interrupted (Ctrl-C); nothing was written\n";

namespace {

const char kMainHelp[] =
    "Usage: afterglow COMMAND [options]\n"
    "\n"
    "afterglow is a physically based, Enlighten-style lightmapper for glTF levels.\n"
    "\n"
    "Commands:\n"
    "  uv SCENE -o OUT.gltf   generate (or check) lightmap UVs and pack them into atlases\n"
    "  info SCENE             print what afterglow loads from a scene\n"
    "  bake SCENE -o OUT/     bake lightmaps (EXR + PNG), a glTF using them, and a report\n"
    "  render SCENE.gltf -o VIEW.png|VIEW.exr\n"
    "                         ray trace a view of a baked scene (tone mapped or linear)\n"
    "  relight OUT/ -o RELIT/ new lightmaps from a bake's transport with changed lights,\n"
    "                         sky, albedo or emission (the runtime's re-solve)\n"
    "  probes place SCENE -o PROBES.json\n"
    "                         place light probes and tetrahedralise them\n"
    "  probes sample OUT/ --at x,y,z\n"
    "                         a bake's light probes interpolated at points (E/pi, SH)\n"
    "\n"
    "SCENE is a .gltf or .glb file, or a built-in scene: builtin:cornell,\n"
    "builtin:cornell-metal (mirror and copper blocks, a reflection probe), builtin:furnace.\n"
    "Run 'afterglow COMMAND --help' for a command's options.\n"
    "\n"
    "Options:\n"
    "  -h, --help     this help\n"
    "  --version      print the version\n"
    "\n";

}  // namespace
}  // namespace afterglow::cli

int main(int argc, char** argv) {
  using namespace afterglow::cli;
  // Before anything else: a Ctrl-C from here on exits 130 with nothing written, whatever the
  // command is doing (the commands check interrupted() before they write).
  installInterruptHandler();
  if (argc < 2) {
    std::fprintf(stderr, "%s%s", kMainHelp, kExitCodesHelp);
    return kExitUsage;
  }
  const std::string command = argv[1];
  if (command == "-h" || command == "--help" || command == "help") {
    const std::string topic = command == "help" && argc > 2 ? argv[2] : "";
    if (topic == "uv")
      std::printf("%s\n%s", kUvHelp, kExitCodesHelp);
    else if (topic == "info")
      std::printf("%s\n%s", kInfoHelp, kExitCodesHelp);
    else if (topic == "bake")
      std::printf("%s\n%s", kBakeHelp, kExitCodesHelp);
    else if (topic == "render")
      std::printf("%s\n%s", kRenderHelp, kExitCodesHelp);
    else if (topic == "relight")
      std::printf("%s\n%s", kRelightHelp, kExitCodesHelp);
    else if (topic == "probes")
      std::printf("%s\n%s", kProbesHelp, kExitCodesHelp);
    else
      std::printf("%s%s", kMainHelp, kExitCodesHelp);
    return kExitOk;
  }
  if (command == "--version") {
    std::printf("afterglow %s\n", AFTERGLOW_VERSION);
    return kExitOk;
  }
  if (command == "uv") return runUv(argc, argv, 2);
  if (command == "info") return runInfo(argc, argv, 2);
  if (command == "bake") return runBake(argc, argv, 2);
  if (command == "render") return runRender(argc, argv, 2);
  if (command == "relight") return runRelight(argc, argv, 2);
  if (command == "probes") return runProbes(argc, argv, 2);
  printError((command[0] == '-' ? "unknown option '" : "unknown command '") + command +
             "' (see afterglow --help)");
  return kExitUsage;
}
