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

// Every subcommand: its name, help and entry point.
struct Subcommand {
  const char* name;
  const char* help;
  int (*run)(int argc, char** argv, int first);
};
const Subcommand kSubcommands[] = {
    {"uv", kUvHelp, runUv},           {"info", kInfoHelp, runInfo},
    {"bake", kBakeHelp, runBake},     {"render", kRenderHelp, runRender},
    {"relight", kRelightHelp, runRelight}, {"probes", kProbesHelp, runProbes}};

const Subcommand* find(const std::string& name) {
  for (const Subcommand& c : kSubcommands)
    if (name == c.name) return &c;
  return nullptr;
}

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
    const Subcommand* about = find(topic);
    if (about)
      printHelp(about->help);
    else
      std::printf("%s%s", kMainHelp, kExitCodesHelp);
    return kExitOk;
  }
  if (command == "--version") {
    std::printf("afterglow %s\n", AFTERGLOW_VERSION);
    return kExitOk;
  }
  if (const Subcommand* run = find(command)) return run->run(argc, argv, 2);
  printError((command[0] == '-' ? "unknown option '" : "unknown command '") + command +
             "' (see afterglow --help)");
  return kExitUsage;
}
