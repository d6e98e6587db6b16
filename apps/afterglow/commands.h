// The afterglow subcommands. Each takes the whole argv and the index of its first own argument,
// and returns a process exit code (ExitCode in args.h).
#pragma once

namespace afterglow::cli {

int runUv(int argc, char** argv, int first);
int runInfo(int argc, char** argv, int first);
int runBake(int argc, char** argv, int first);
int runRender(int argc, char** argv, int first);
int runRelight(int argc, char** argv, int first);
int runProbes(int argc, char** argv, int first);
int runProbesSample(int argc, char** argv, int first);  // `probes sample`, from runProbes

// Help texts (printed by --help, and after a usage error hint).
extern const char kUvHelp[];
extern const char kInfoHelp[];
extern const char kBakeHelp[];
extern const char kRenderHelp[];
extern const char kRelightHelp[];
extern const char kProbesHelp[];
extern const char kExitCodesHelp[];

}  // namespace afterglow::cli
