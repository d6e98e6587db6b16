// `afterglow probes place`: light-probe placement (probes::placeProbes), refined where a bake's
// light changes with --bake (probes::refineByBake), their tetrahedra (probes::tetrahedralize),
// written as PROBES.json with a picture beside it; with --reflection, reflection probes proposed
// one per room-like region (probes::placeReflectionProbes) in the same file. `probes sample` is in cmd_probes_sample.cpp.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afterglow/trace/raytracer.h"
#include "afterglow/preview/render.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/parallel.h"
#include "afterglow/core/progress.h"
#include "afterglow/probes/bake_refinement.h"
#include "afterglow/probes/placement.h"
#include "afterglow/probes/placement_picture.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/probes/reflection_placement.h"
#include "afterglow/probes/tetrahedralize.h"
#include "args.h"
#include "afterglow/bakefiles/read.h"
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
    "inside geometry (a candidate whose rays mostly see the backs of single-sided surfaces is\n"
    "moved to a free spot in its cell or dropped) and kept a margin off surfaces; then a Delaunay\n"
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
    "  --width N, --height N     the picture's size (default 960 x 600)\n"
    "  --threads N               worker threads (default: every core); the output is identical\n"
    "                            for any count\n"
    "  --quiet                   no progress and no summary\n"
    "  -h, --help                this help\n"
    "\n"
    "probes sample: prints a bake's light probes interpolated at each --at point (tetrahedral\n"
    "interpolation, as the runtime's sampleProbes gives an engine's dynamic object there): one\n"
    "line per point, x,y,z then E/pi (linear RGB, the lightmaps' unit: shade with albedo x\n"
    "value) for the six axis normals +X -X +Y -Y +Z -Z, or for each --normal given.\n"
    "OUT/transport.agt is solved as the bake solved it (from scratch, its bounce count from\n"
    "OUT/report.json), so a point on a probe gives that probe's SH in\n"
    "OUT/probes/light_probes_sh.bin (deringed alike).\n"
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

int runPlace(int argc, char** argv, int first) {
  const Command command = {"probes place", "probes", kProbesHelp};
  auto usage = [&](const std::string& message) { return command.usage(message); };
  Args args;
  if (std::optional<int> stop = parseOrExit(
          args, argc, argv, first,
          {{"output", 'o'}, {"spacing"}, {"levels"}, {"margin"}, {"max-probes"}, {"add"},
           {"bake"}, {"refine-threshold"}, {"width"}, {"height"}, {"threads"},
           {"reflection", 0, false}, {"max-reflection-probes"}, {"quiet", 0, false},
           {"help", 'h', false}},
          command))
    return *stop;
  std::string input;
  if (!args.single("SCENE", &input)) return usage(args.error());
  if (!args.has("output")) return usage("missing -o PROBES.json");
  const std::string output = args.get("output");
  if (!endsWith(output, ".json"))
    return usage("the output must end in .json, got '" + output + "'");

  probes::PlacementOptions options;
  probes::BakeRefinementOptions refineOptions;
  probes::ReflectionPlacementOptions reflectionOptions;
  int threads = 0, width = 960, height = 600, maxProbes = int(options.maxProbes);
  int maxReflection = int(reflectionOptions.maxProbes);
  if (!args.getFloat("spacing", 0.0f, 0.0f, 1e6f, &options.spacing) ||
      !args.getInt("levels", options.levels, 0, 8, &options.levels) ||
      !args.getFloat("margin", 0.0f, -1e-30f, 1e6f, &options.margin) ||
      !args.getInt("max-probes", maxProbes, 1, 100000000, &maxProbes) ||
      !args.getInt("width", width, 16, 8192, &width) ||
      !args.getInt("height", height, 16, 8192, &height) ||
      !args.getInt("threads", 0, 0, 1024, &threads) ||
      !args.getInt("max-reflection-probes", maxReflection, 1, 4096, &maxReflection) ||
      !args.getFloat("refine-threshold", refineOptions.threshold, 0.0f, 1e6f,
                     &refineOptions.threshold))
    return usage(args.error());
  const std::string bakeDir = args.get("bake");
  if (args.has("bake") && bakeDir.empty()) return usage("--bake wants a bake folder OUT/");
  if (args.has("refine-threshold") && bakeDir.empty())
    return usage("--refine-threshold refines by a bake: give --bake OUT/ too");
  options.maxProbes = size_t(maxProbes);
  const bool reflection = args.has("reflection");
  if (args.has("max-reflection-probes") && !reflection)
    return usage("--max-reflection-probes limits the proposals of --reflection: give it too");
  reflectionOptions.maxProbes = size_t(maxReflection);
  const bool quiet = args.has("quiet");
  setThreadCount(threads);

  ConsoleProgress progress(stderr, quiet);
  InterruptGuard guard(progress);
  const auto start = Clock::now();

  std::vector<std::string> userNames;
  if (args.has("add")) {
    Result<probes::UserProbes> user = probes::readUserProbes(args.get("add"));
    if (!user) {
      printError(user.message());
      return kExitBadInput;
    }
    options.userProbes = user->positions;
    options.userNames = user->names;
  }

  int code = kExitOk;
  Result<scenes::Scene> loaded = loadSceneOrExit(input, false, &code);
  if (!loaded) return code;
  const scenes::Scene& scene = loaded.value();
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  if (!tracer) {
    printError(input + ": " + tracer.message());
    return kExitBadInput;
  }

  // The bake first, so a wrong folder fails before the placement's work.
  std::optional<bakefiles::BakedProbes> baked;
  double bakeSeconds = 0.0;
  if (!bakeDir.empty()) {
    const auto bakeStart = Clock::now();
    Result<bakefiles::BakedProbes> loadedBake = bakefiles::loadBakedProbes(bakeDir);
    if (interrupted()) return interruptedExit();
    if (!loadedBake) {
      printError(loadedBake.message());
      return kExitBadInput;
    }
    baked = std::move(loadedBake.value());
    bakeSeconds = secondsSince(bakeStart);
  }

  Result<probes::Placement> placed = probes::placeProbes(scene, *tracer.value(), options, progress);
  if (interrupted() || progress.cancelled()) return interruptedExit();
  if (!placed) {
    printError(input + ": " + placed.message());
    return kExitBadInput;
  }
  probes::Placement& placement = placed.value();
  const double placeSeconds = secondsSince(start) - bakeSeconds;  // loading included, as before

  auto tetrahedralize = [&]() -> Result<runtime::ProbeTetrahedra> {
    Result<runtime::ProbeTetrahedra> mesh = probes::tetrahedralize(placement.positions);
    if (!mesh) return Status::error(input + ": " + mesh.message());
    return mesh;
  };
  const auto tetStart = Clock::now();
  Result<runtime::ProbeTetrahedra> mesh = tetrahedralize();
  if (!mesh) {
    printError(mesh.message());
    return kExitBadInput;
  }
  double tetSeconds = secondsSince(tetStart);

  // --bake: split the edges across which the bake's light changes, then tetrahedralise again.
  probes::BakeRefinement refinement;
  if (baked) {
    const auto bakeStart = Clock::now();
    // In probe order, each walk starting from the last one's tetrahedron: the same answer on
    // any thread count (a point on a face shared by two tetrahedra may round differently in
    // each, so the walk's start must not depend on the threads).
    std::vector<probes::AxisIrradiance> irradiance(placement.positions.size());
    int hint = 0;
    for (size_t i = 0; i < placement.positions.size(); ++i) {
      const runtime::ShL2 sh = baked->sample(placement.positions[i], &hint);
      for (int k = 0; k < 6; ++k)
        irradiance[i][size_t(k)] = runtime::Runtime::evaluateIrradiance(sh, probes::axisNormal(k));
    }
    Result<probes::BakeRefinement> refined = probes::refineByBake(
        scene, *tracer.value(), options, mesh.value(), irradiance, refineOptions, placement);
    if (!refined) {
      printError(input + ": " + refined.message());
      return kExitBadInput;
    }
    refinement = refined.value();
    bakeSeconds += secondsSince(bakeStart);
    if (refinement.added > 0) {
      const auto again = Clock::now();
      mesh = tetrahedralize();
      if (!mesh) {
        printError(mesh.message());
        return kExitBadInput;
      }
      tetSeconds += secondsSince(again);
    }
  }

  probes::ReflectionPlacement reflections;
  double reflectionSeconds = 0.0;
  if (reflection) {
    const auto reflectionStart = Clock::now();
    Result<probes::ReflectionPlacement> proposed =
        probes::placeReflectionProbes(scene, *tracer.value(), reflectionOptions, progress);
    if (interrupted() || progress.cancelled()) return interruptedExit();
    if (!proposed) {
      printError(input + ": " + proposed.message());
      return kExitBadInput;
    }
    reflections = std::move(proposed.value());
    reflectionSeconds = secondsSince(reflectionStart);
  }

  // The user's probes are the pinned ones, in their file's order: they take its names.
  std::vector<std::string> names(placement.positions.size());
  for (size_t i = 0, u = 0; i < placement.positions.size() && u < options.userNames.size(); ++i)
    if (placement.kinds[i] == probes::ProbeKind::Pinned) names[i] = options.userNames[u++];

  trace::View view = scene.cameras.empty() ? trace::defaultView(scene, 0.9f)
                                           : trace::cameraView(scene.cameras.front());
  const std::vector<glm::vec3> picture =
      probes::placementPicture(scene, *tracer.value(), placement, options.levels, view,
                                 width, height, reflections.probes);

  size_t pinned = 0;
  for (probes::ProbeKind k : placement.kinds) pinned += k == probes::ProbeKind::Pinned;
  nlohmann::json settings = {{"input", input},
                             {"spacing", placement.spacing},
                             {"levels", options.levels},
                             {"margin", placement.margin},
                             {"maxProbes", options.maxProbes},
                             {"add", args.get("add")},
                             {"threads", threadCount()}};
  if (baked) {
    settings["bake"] = bakeDir;
    settings["refineThreshold"] = refineOptions.threshold;
  }
  if (reflection) {
    settings["reflection"] = true;
    settings["maxReflectionProbes"] = reflectionOptions.maxProbes;
    settings["reflectionSpacing"] = reflections.spacing;
  }
  nlohmann::json summary = {{"candidates", placement.candidates},
                            {"placed", placement.positions.size()},
                            {"rejectedInsideGeometry", placement.rejected},
                            {"moved", placement.moved},
                            {"refined", placement.refined},
                            {"pinned", pinned},
                            {"refinedByBake", refinement.added},
                            {"tetrahedra", mesh->tetrahedra.size()},
                            {"placeSeconds", placeSeconds},
                            {"tetrahedraSeconds", tetSeconds},
                            {"warnings", placement.warnings}};
  if (baked)
    summary["bakeRefinement"] = {{"edges", refinement.edges},
                                 {"shortEdges", refinement.shortEdges},
                                 {"overThreshold", refinement.overThreshold},
                                 {"rejected", refinement.rejected},
                                 {"overBudget", refinement.overBudget},
                                 {"floor", refinement.floor},
                                 {"seconds", bakeSeconds}};
  if (reflection)
    summary["reflection"] = {{"proposed", reflections.probes.size()},
                             {"candidates", reflections.candidates},
                             {"insideGeometry", reflections.inside},
                             {"open", reflections.open},
                             {"thin", reflections.thin},
                             {"centreBlocked", reflections.centreBlocked},
                             {"overlapping", reflections.overlapping},
                             {"overBudget", reflections.overBudget},
                             {"seconds", reflectionSeconds},
                             {"warnings", reflections.warnings}};
  const std::string text = probes::probesJson(placement, names, mesh.value(), settings.dump(),
                                              summary.dump(), "", reflections.probes);

  // Both files through temporaries, renamed only once both are written.
  const fs::path outPath(output);
  const std::string picturePath = (outPath.parent_path() / outPath.stem()).string() + ".png";
  AtomicOutput files;
  if (Status st = files.write(output, text); !st) {
    printError(st.message());
    return kExitOutput;
  }
  if (Status st = preview::writeRenderPng(files.tempPath(picturePath), width, height, picture, 0.0f);
      !st) {
    printError(st.message());
    return kExitOutput;
  }
  if (interrupted()) return interruptedExit();
  if (Status st = files.commit(); !st) {
    printError(st.message());
    return kExitOutput;
  }
  if (!quiet) {
    std::printf("scene         %s\n", input.c_str());
    std::printf("spacing       %.3g m%s, %d finer levels, margin %.3g m\n",
                double(placement.spacing), options.spacing > 0.0f ? "" : " (from the level's size)",
                options.levels, double(placement.margin));
    std::printf("candidates    %zu\n", placement.candidates);
    std::printf("placed        %zu (%zu refined,%s %zu moved, %zu pinned)\n",
                placement.positions.size(), placement.refined,
                baked ? format(" %zu by the bake,", refinement.added).c_str() : "",
                placement.moved, pinned);
    std::printf("rejected      %zu inside geometry\n", placement.rejected);
    if (baked)
      std::printf("bake          %zu probes added: %zu of %zu edges differ by more than %.3g in "
                  "%s (%zu at the finest spacing already); %zu midpoints near geometry or on a "
                  "probe, %zu over the budget\n",
                  refinement.added, refinement.overThreshold, refinement.edges,
                  double(refineOptions.threshold), bakeDir.c_str(), refinement.shortEdges,
                  refinement.rejected, refinement.overBudget);
    std::printf("tetrahedra    %zu\n", mesh->tetrahedra.size());
    if (reflection)
      std::printf("reflection    %zu reflection probe%s proposed, from %zu candidates at %.3g m "
                  "(%zu inside geometry, %zu open, %zu thin, %zu with the box's centre in "
                  "geometry, %zu in a kept box, %zu over the budget)\n",
                  reflections.probes.size(), reflections.probes.size() == 1 ? "" : "s",
                  reflections.candidates, double(reflections.spacing),
                  reflections.inside, reflections.open, reflections.thin,
                  reflections.centreBlocked, reflections.overlapping, reflections.overBudget);
    std::printf("time          place %.2f s,%s%s tetrahedra %.2f s\n", placeSeconds,
                baked ? format(" bake refinement %.2f s,", bakeSeconds).c_str() : "",
                reflection ? format(" reflection probes %.2f s,", reflectionSeconds).c_str() : "",
                tetSeconds);
    for (const std::string& w : scene.warnings) std::printf("warning       %s\n", w.c_str());
    for (const std::string& w : placement.warnings) std::printf("warning       %s\n", w.c_str());
    for (const std::string& w : reflections.warnings)
      std::printf("warning       %s\n", w.c_str());
    std::printf("wrote         %s, %s\n", output.c_str(), picturePath.c_str());
  }
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
