// `afterglow probes place`: the command line into a probes::PlacementJob (placement_job.h:
// light probes placed, refined where a bake's light changes with --bake, tetrahedralised,
// reflection probes proposed with --reflection), the bake's light read through
// bakefiles::BakedProbes, and PROBES.json written with a picture beside it. `probes sample` is
// in cmd_probes_sample.cpp.
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "afterglow/bakefiles/read.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/parallel.h"
#include "afterglow/core/progress.h"
#include "afterglow/preview/render.h"
#include "afterglow/probes/placement_job.h"
#include "afterglow/probes/probes_file.h"
#include "args.h"
#include "commands.h"
#include "common.h"

namespace fs = std::filesystem;

namespace afterglow::cli {

const char kProbesHelp[] =
    "Usage: afterglow probes place SCENE -o PROBES.json [options]\n"
    "       afterglow probes sample OUT/ --at x,y,z [--at x,y,z ...] [--normal x,y,z] [--json]\n"
    "\n"
    "probes place: places light probes for dynamic objects: a grid over the static geometry (or\n"
    "over the probe volumes authored on glTF nodes as extras.afterglow.probeVolume = {\"size\":\n"
    "[x, y, z], \"spacing\": s}), refined on an octree where it holds or touches geometry, never\n"
    "inside geometry (a candidate whose rays see the backs of single-sided surfaces in over a\n"
    "quarter of directions, or inside a closed double-sided object, is moved to a free spot in\n"
    "its cell or dropped) and kept a margin off surfaces; then a Delaunay\n"
    "tetrahedralisation of the probes for interpolation. Writes, all or nothing:\n"
    "  PROBES.json   positions, kinds (grid, refined, moved, pinned), tetrahedra and their\n"
    "                neighbours, settings and summary (README: the light probes file)\n"
    "  PROBES.png    the probes over the scene from its first camera (or an overview), coloured\n"
    "                by kind: grid white, refined cyan, moved orange, pinned magenta\n"
    "and prints a summary: candidates, placed, rejected inside geometry, moved, refined (and\n"
    "added by --bake), reflection probes proposed (--reflection), time.\n"
    "SCENE is a .gltf or .glb file, or a built-in scene: builtin:cornell,\n"
    "builtin:cornell-metal (mirror and copper blocks, a reflection probe), builtin:furnace.\n"
    "\n"
    "Options:\n"
    "  -o, --output PROBES.json  output file; required\n"
    "  --spacing M               metres between grid probes (default: from the level's size,\n"
    "                            printed)\n"
    "  --levels N                finer octree levels near geometry (default 2)\n"
    "  --margin M                metres kept off surfaces (default: a tenth of the finest\n"
    "                            spacing)\n"
    "  --max-probes N            refuse more probes than this (default 100000)\n"
    "  --add FILE.json           the user's own probes ({\"positions\": [[x, y, z], ...],\n"
    "                            \"names\": [...]}), pinned, never moved; one inside geometry is\n"
    "                            warned about by name\n"
    "  --bake OUT/               then refine where a bake's light changes: each edge of the\n"
    "                            probes' tetrahedra whose ends' E/pi (the bake's probes\n"
    "                            interpolated there, over the six axis normals) differ by more\n"
    "                            than the threshold gets a probe at its midpoint (kind refined;\n"
    "                            not inside geometry nor within the margin of a surface), unless\n"
    "                            it is as short as the finest cells' diagonal already; within\n"
    "                            --max-probes, the largest differences first; one pass\n"
    "  --refine-threshold X      the difference that splits an edge (default 0.25), relative to\n"
    "                            the brighter end (or to 1% of the brightest E/pi, if more)\n"
    "  --reflection              also propose reflection probes, one per room-like region: a\n"
    "                            coarse grid of candidates each fits a box to the walls around it\n"
    "                            by ray distances; the best fitting boxes that do not overlap are\n"
    "                            kept, written to PROBES.json's \"reflectionProbes\" (name,\n"
    "                            position, size, blendDistance, importance, boxProjection,\n"
    "                            resolution) to review and edit, and drawn yellow in PROBES.png;\n"
    "                            afterglow bake --probes PROBES.json captures them\n"
    "  --max-reflection-probes N at most this many (default 32), the best fitting first\n"
    "  --unit-scale X            the level's metres per unit (0.01: centimetres, 0.001:\n"
    "                            millimetres): scales it first, as afterglow bake --unit-scale\n"
    "                            does; PROBES.json and --add's probes are in metres (default 1)\n"
    "  --width N, --height N     the picture's size (default 960 x 600)\n"
    "  --threads N               worker threads (default: every core); the output is identical\n"
    "                            for any count\n"
    "  --quiet                   no progress and no summary\n"
    "  -h, --help                this help\n"
    "\n"
    "probes sample: prints a bake's light probes interpolated at each --at point (tetrahedral\n"
    "interpolation, as the runtime's sampleProbeLighting gives an engine's dynamic object\n"
    "there): one line per point, x,y,z then E/pi (linear RGB, the lightmaps' unit: shade with\n"
    "albedo x value) for the six axis normals +X -X +Y -Y +Z -Z, or for each --normal given:\n"
    "the SH, with small light sources read as directions (docs/probes.md).\n"
    "OUT/transport.agt is solved as the bake solved it (from scratch, its bounce count from\n"
    "OUT/report.json), so a point on a probe gives that probe's SH in\n"
    "OUT/probes/light_probes_sh.bin (deringed alike). A folder afterglow relight wrote has no\n"
    "transport: its relit probes (probes/light_probes.json and light_probes_sh.bin) are\n"
    "interpolated as the runtime interpolates them. probes place --bake reads either.\n"
    "\n"
    "Options:\n"
    "  --at x,y,z                a point, metres in the scene's axes; repeatable; required\n"
    "  --normal x,y,z            a normal to evaluate instead of the six axes; repeatable\n"
    "  --json                    a JSON array instead, one object per point: position,\n"
    "                            tetrahedron (-1: none), inside (false: outside the probes' hull,\n"
    "                            projected onto its nearest face), probes and weights (the\n"
    "                            interpolation's; -1 and 0 where unused), sh (the radiance SH L2,\n"
    "                            27 floats as in light_probes_sh.bin: c0.r c0.g c0.b c1.r ...),\n"
    "                            irradiance ([{normal, value}], E/pi per normal)\n"
    "  -h, --help                this help\n";

namespace {

const Command kPlace = {"probes place", "probes", kProbesHelp};

// The job and the output from the command line: the usage error's exit code (printed) when
// they are wrong.
std::optional<int> parsePlacement(Args& args, probes::PlacementJob* job, std::string* output,
                                  int* threads) {
  if (!args.single("SCENE", &job->input)) return kPlace.usage(args.error());
  if (!args.has("output")) return kPlace.usage("missing -o PROBES.json");
  *output = args.get("output");
  if (!endsWith(*output, ".json"))
    return kPlace.usage("the output must end in .json, got '" + *output + "'");
  probes::PlacementOptions& options = job->placement;
  int maxProbes = int(options.maxProbes);
  int maxReflection = int(job->reflectionOptions.maxProbes);
  if (!args.getFloat("spacing", 0.0f, 0.0f, 1e6f, &options.spacing) ||
      !args.getInt("levels", options.levels, 0, 8, &options.levels) ||
      !args.getFloat("margin", 0.0f, -1e-30f, 1e6f, &options.margin) ||
      !args.getInt("max-probes", maxProbes, 1, 100000000, &maxProbes) ||
      !args.getInt("width", job->width, 16, 8192, &job->width) ||
      !args.getInt("height", job->height, 16, 8192, &job->height) ||
      !args.getInt("threads", 0, 0, 1024, threads) ||
      !args.getInt("max-reflection-probes", maxReflection, 1, 4096, &maxReflection) ||
      !args.getFloat("refine-threshold", job->refinement.threshold, 0.0f, 1e6f,
                     &job->refinement.threshold) ||
      !getUnitScale(args, &job->unitScale))
    return kPlace.usage(args.error());
  job->bake = args.get("bake");
  if (args.has("bake") && job->bake.empty())
    return kPlace.usage("--bake wants a bake folder OUT/");
  if (args.has("refine-threshold") && job->bake.empty())
    return kPlace.usage("--refine-threshold refines by a bake: give --bake OUT/ too");
  options.maxProbes = size_t(maxProbes);
  job->reflection = args.has("reflection");
  if (args.has("max-reflection-probes") && !job->reflection)
    return kPlace.usage(
        "--max-reflection-probes limits the proposals of --reflection: give it too");
  job->reflectionOptions.maxProbes = size_t(maxReflection);
  job->userProbesFile = args.get("add");
  return std::nullopt;
}

// --add's probes into the job, pinned; false with the error printed.
bool addUserProbes(probes::PlacementJob* job) {
  Result<probes::UserProbes> user = probes::readUserProbes(job->userProbesFile);
  if (!user) {
    printError(user.message());
    return false;
  }
  job->placement.userProbes = user->positions;
  job->placement.userNames = user->names;
  return true;
}

// --bake's light probes, solved as the bake solved them: the exit code to stop with on an
// error (printed) or a Ctrl-C.
std::optional<int> loadBake(probes::PlacementJob* job, std::optional<bakefiles::BakedProbes>* out) {
  const auto start = Clock::now();
  Result<bakefiles::BakedProbes> loaded = bakefiles::loadBakedProbes(job->bake);
  if (interrupted()) return interruptedExit();
  if (!loaded) {
    printError(loaded.message());
    return kExitBadInput;
  }
  *out = std::move(loaded.value());
  job->bakeLoadSeconds = secondsSince(start);
  return std::nullopt;
}

// PROBES.json and the picture beside it, both through temporaries, renamed only once both are
// written.
int writePlacement(const probes::PlacementJob& job, const probes::PlacedProbes& placed,
                   const std::string& output, const std::string& picturePath) {
  AtomicOutput files;
  Status st = files.write(output, placed.probesJson);
  if (st)
    st = preview::writeRenderPng(files.tempPath(picturePath), job.width, job.height,
                                 placed.picture, 0.0f);
  if (!st) {
    printError(st.message());
    return kExitOutput;
  }
  if (interrupted()) return interruptedExit();
  if (st = files.commit(); !st) {
    printError(st.message());
    return kExitOutput;
  }
  return kExitOk;
}

void printPlacement(const probes::PlacementJob& job, const probes::PlacedProbes& placed,
                    const scenes::Scene& scene, const std::string& output,
                    const std::string& picturePath) {
  const probes::Placement& placement = placed.placement;
  const probes::BakeRefinement& refinement = placed.refinement;
  const probes::ReflectionPlacement& reflections = placed.reflections;
  const bool baked = !job.bake.empty();
  std::printf("scene         %s\n", job.input.c_str());
  std::printf("spacing       %.3g m%s, %d finer levels, margin %.3g m\n",
              double(placement.spacing),
              job.placement.spacing > 0.0f ? "" : " (from the level's size)",
              job.placement.levels, double(placement.margin));
  std::printf("candidates    %zu\n", placement.candidates);
  std::printf("placed        %zu (%zu refined,%s %zu moved, %zu pinned)\n",
              placement.positions.size(), placement.refined,
              baked ? format(" %zu by the bake,", refinement.added).c_str() : "",
              placement.moved, placed.pinned);
  std::printf("rejected      %zu inside geometry\n", placement.rejected);
  if (baked)
    std::printf("bake          %zu probes added: %zu of %zu edges differ by more than %.3g in "
                "%s (%zu at the finest spacing already); %zu midpoints near geometry or on a "
                "probe, %zu over the budget\n",
                refinement.added, refinement.overThreshold, refinement.edges,
                double(job.refinement.threshold), job.bake.c_str(), refinement.shortEdges,
                refinement.rejected, refinement.overBudget);
  std::printf("tetrahedra    %zu\n", placed.mesh.tetrahedra.size());
  if (job.reflection)
    std::printf("reflection    %zu reflection probe%s proposed, from %zu candidates at %.3g m "
                "(%zu inside geometry, %zu open, %zu thin, %zu with the box's centre in "
                "geometry, %zu in a kept box, %zu over the budget)\n",
                reflections.probes.size(), reflections.probes.size() == 1 ? "" : "s",
                reflections.candidates, double(reflections.spacing), reflections.inside,
                reflections.open, reflections.thin, reflections.centreBlocked,
                reflections.overlapping, reflections.overBudget);
  std::printf("time          place %.2f s,%s%s tetrahedra %.2f s\n", placed.placeSeconds,
              baked ? format(" bake refinement %.2f s,", placed.bakeSeconds).c_str() : "",
              job.reflection
                  ? format(" reflection probes %.2f s,", placed.reflectionSeconds).c_str()
                  : "",
              placed.tetrahedraSeconds);
  for (const std::vector<std::string>* warnings :
       {&scene.warnings, &placement.warnings, &reflections.warnings})
    for (const std::string& w : *warnings) std::printf("warning       %s\n", w.c_str());
  std::printf("wrote         %s, %s\n", output.c_str(), picturePath.c_str());
}

int runPlace(int argc, char** argv, int first) {
  Args args;
  if (std::optional<int> stop = parseOrExit(
          args, argc, argv, first,
          {{"output", 'o'}, {"spacing"}, {"levels"}, {"margin"}, {"max-probes"}, {"add"},
           {"bake"}, {"refine-threshold"}, {"width"}, {"height"}, {"threads"},
           {"reflection", 0, false}, {"max-reflection-probes"}, kUnitScaleOption,
           {"quiet", 0, false},
           {"help", 'h', false}},
          kPlace))
    return *stop;
  probes::PlacementJob job;
  std::string output;
  int threads = 0;
  if (std::optional<int> stop = parsePlacement(args, &job, &output, &threads)) return *stop;
  const bool quiet = args.has("quiet");
  setThreadCount(threads);

  ConsoleProgress progress(stderr, quiet);
  InterruptGuard guard(progress);
  const auto start = Clock::now();
  if (args.has("add") && !addUserProbes(&job)) return kExitBadInput;
  int code = kExitOk;
  Result<scenes::Scene> loaded = loadSceneOrExit(job.input, false, &code);
  if (!loaded) return code;
  applyUnitScale(loaded.value(), job.unitScale, job.input);
  job.loadSeconds = secondsSince(start);
  // The bake first, so a wrong folder fails before the placement's work.
  std::optional<bakefiles::BakedProbes> baked;
  if (!job.bake.empty())
    if (std::optional<int> stop = loadBake(&job, &baked)) return *stop;
  // The bake's probes at the points in order, each walk starting from the last one's
  // tetrahedron: the same answer on any thread count (a point on a face shared by two
  // tetrahedra may round differently in each, so the walk's start must not depend on threads).
  const probes::BakeLight bakeLight = [&baked](const std::vector<glm::vec3>& points) {
    std::vector<runtime::ShL2> sh;
    int hint = 0;
    for (const glm::vec3& p : points) sh.push_back(baked->sample(p, &hint));
    return sh;
  };

  Result<probes::PlacedProbes> placed =
      probes::runPlacementJob(loaded.value(), job, baked ? &bakeLight : nullptr, progress);
  if (interrupted() || progress.cancelled()) return interruptedExit();
  if (!placed) {
    printError(placed.message());
    return kExitBadInput;
  }
  const fs::path outPath(output);
  const std::string picturePath = (outPath.parent_path() / outPath.stem()).string() + ".png";
  if ((code = writePlacement(job, placed.value(), output, picturePath)) != kExitOk) return code;
  if (!quiet) printPlacement(job, placed.value(), loaded.value(), output, picturePath);
  return kExitOk;
}

}  // namespace

int runProbes(int argc, char** argv, int first) {
  const std::string verb = first < argc ? argv[first] : "";
  if (verb == "place") return runPlace(argc, argv, first + 1);
  if (verb == "sample") return runProbesSample(argc, argv, first + 1);
  if (verb == "-h" || verb == "--help" || verb == "help") {
    printHelp(kProbesHelp);
    return kExitOk;
  }
  printError(verb.empty() ? "probes: missing a verb: place or sample (see afterglow probes --help)"
                          : "probes: unknown verb '" + verb +
                                "', there are place and sample (see afterglow probes --help)");
  return kExitUsage;
}

}  // namespace afterglow::cli
