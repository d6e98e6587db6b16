// afterglow bake: UVs, the precompute and one solve, written as lightmaps + glTF + report.
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afterglow/bakefiles/pipeline.h"
#include "afterglow/baker/bake.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/memory.h"
#include "afterglow/core/parallel.h"
#include "args.h"
#include "commands.h"
#include "common.h"

namespace afterglow::cli {

const char kBakeHelp[] =
    "Usage: afterglow bake SCENE -o OUT/ [options]\n"
    "\n"
    "Bakes physically based lightmaps for every static instance of SCENE: lightmap UVs, texels,\n"
    "clusters, form factors, direct light, then a multi-bounce solve. Writes:\n"
    "  OUT/lightmaps/lightmap<i>.exr   linear half-float RGB (E/pi: shade as albedo x lightmap)\n"
    "  OUT/lightmaps/lightmap<i>.png   tone-mapped sRGB preview\n"
    "  OUT/scene.gltf (+ scene.bin)     the scene with TEXCOORD_1 and MOZ_lightmap materials\n"
    "  OUT/report.json                  counts, rays, time per stage, peak memory, warnings\n"
    "  OUT/transport.agt                the transport, for the runtime and afterglow relight\n"
    "  OUT/probes/light_probes.json     light probes: positions, kinds, tetrahedra, settings\n"
    "  OUT/probes/light_probes_sh.bin   their radiance SH L2, float32 (README: light probes)\n"
    "  OUT/probes/reflection_*.exr      reflection probes (nodes with extras.afterglow.\n"
    "                                   reflectionProbe, and the sky): OpenEXR cube maps with\n"
    "                                   GGX mips; reflection_probes.json, dfg.exr beside them\n"
    "Before baking it prints the texel count and a memory estimate, and refuses a bake above\n"
    "the memory budget unless --yes is given. Nothing is written when anything fails or the run\n"
    "is interrupted.\n"
    "SCENE is a .gltf or .glb file, or a built-in scene: builtin:cornell,\n"
    "builtin:cornell-metal (mirror and copper blocks, a reflection probe), builtin:furnace.\n"
    "\n"
    "Options (later ones win: preset < settings file < command line):\n"
    "  -o, --output OUT/        output folder; required\n"
    "  --texels-per-unit N|auto lightmap texels per metre (times each node's lightmapScale);\n"
    "                           auto (the default) picks about 262,000 texels for the level\n"
    "  --atlas-size N           instead: the most texels per metre that fit one N x N atlas\n"
    "  --indirect-texels-per-unit N|auto\n"
    "                           texels per metre where bounced light is solved (Unity's\n"
    "                           indirect resolution); each light's direct light stays at the\n"
    "                           lightmap's. auto (the default): a grid of about 131,000\n"
    "                           texels when that is at most half the lightmap's density,\n"
    "                           else the lightmap's own texels; at or above the lightmap's\n"
    "                           density: one resolution\n"
    "  --uv generate|keep       new lightmap UVs (default) or the authored TEXCOORD_1\n"
    "  --quality Q              draft | default | high: gather rays per gather point, first\n"
    "                           and penumbra shadow rays, smoothing passes (64/8/64/3,\n"
    "                           128/16/128/2, 512/32/512/1)\n"
    "  --texel-rays N           gather (form-factor) rays per texel\n"
    "  --cluster-rays N         rays per back-side cluster of double-sided surfaces\n"
    "  --light-samples N        first shadow rays per texel per light with a size\n"
    "  --emissive-samples N     first shadow rays per texel per emissive surface\n"
    "  --penumbra-samples N     shadow rays where the first ones disagree (the penumbra)\n"
    "  --filter-passes N        smoothing passes over bounced light (0: none)\n"
    "  --bounces N              bounce passes (default 0: until the change is below 0.1%)\n"
    "  --indirect-intensity X   scales all indirect light (default 1)\n"
    "  --albedo-boost X         >= 1 pushes albedo toward white for bounces (default 1)\n"
    "  --sky r,g,b              constant sky radiance, linear (default 0,0,0)\n"
    "  --sky-image FILE         equirectangular HDR sky (overrides --sky)\n"
    "  --cluster-size M         largest cluster edge in metres (default 0.5)\n"
    "  --cluster-texels N       largest cluster edge in texels (default 4; 0: no limit)\n"
    "  --far-distance X         rays hitting a far cluster (4x a cluster's size) from beyond X\n"
    "                           of its radii link to it, not their cluster (default 2; 0: off)\n"
    "  --far-levels N           far cluster levels, each 4x wider than the last (default 1)\n"
    "  --shared-far-span N      texels near other geometry within N texels on one surface pool\n"
    "                           their far-cluster rays into one shared row (default 4; 0: off)\n"
    "  --shared-far-points X    rays a shared far row keeps, in gather points' rays (default 3)\n"
    "  --dilation N             texels each chart is grown into its padding (default 2)\n"
    "  --unit-scale X           the level's metres per unit (0.01: centimetres, 0.001:\n"
    "                           millimetres): scales the whole level first, as a root node\n"
    "                           scale would (lights' positions and ranges, cameras, probe\n"
    "                           volumes and reflection probes too); the outputs are in metres\n"
    "                           (default 1; the bake warns when the level looks like it is not\n"
    "                           in metres)\n"
    "  --no-directional         no directional lightmaps (default: lightmaps/*_dx.exr, _dy,\n"
    "                           _dz hold the bounced light's change with the shading normal,\n"
    "                           for normal maps; extras.afterglow.directional says how to read\n"
    "                           them)\n"
    "  --single-sided-emission  double-sided emissive materials emit from their front only\n"
    "                           (default: both sides, as glTF says); written on the output's\n"
    "                           materials as extras.afterglow.singleSidedEmission\n"
    "  --probes auto|none|FILE  light probes: placed automatically (default, as afterglow\n"
    "                           probes place does), none, or a PROBES.json from probes place;\n"
    "                           a file's reflectionProbes (probes place --reflection) are\n"
    "                           captured too, except one named as a node's own\n"
    "  --reflection-probes auto|none\n"
    "                           auto (default): the scene's own reflection probes, or, when it\n"
    "                           has none and --probes is auto, one proposed per room as probes\n"
    "                           place --reflection does; none: no reflection probes\n"
    "  --probe-spacing M        metres between grid probes for auto (default: from the level)\n"
    "  --max-probes N           refuse an auto placement of more probes (default 100000)\n"
    "  --probe-dering W         write the probes' SH deringed with this Hanning window (e.g.\n"
    "                           4; default 0: as baked)\n"
    "  --reflection-bounces N   reflection probes' passes after the diffuse one: how many times\n"
    "                           facing mirrors show each other (default 1, as Unity's)\n"
    "  --reference              compute every texel with the reference path tracer instead\n"
    "                           (slow; for validating bakes: same outputs, no clusters)\n"
    "  --spp N                  paths per texel for --reference (default 1024)\n"
    "  --threads N              worker threads (default: every core)\n"
    "  --settings FILE.json     settings as a JSON object with the option names above as keys,\n"
    "                           e.g. {\"quality\": \"high\", \"sky\": [0.2, 0.3, 0.5]}\n"
    "  --memory-budget GB       refuse bakes estimated above this (default 8)\n"
    "  -y, --yes                bake even above the memory budget\n"
    "  --quiet                  no progress bar and no summary\n"
    "  -h, --help               this help\n";

namespace {

const std::vector<OptionSpec> kBakeOptions = {
    {"output", 'o'},       {"texels-per-unit"}, {"atlas-size"},  {"uv"},
    {"indirect-texels-per-unit"},
    {"penumbra-samples"},  {"filter-passes"},
    {"quality"},           {"texel-rays"},      {"cluster-rays"},
    {"light-samples"},     {"emissive-samples"}, {"bounces"},
    {"indirect-intensity"}, {"albedo-boost"},    {"sky"},
    {"sky-image"},         {"cluster-size"},    {"cluster-texels"},
    {"far-distance"},      {"far-levels"},      {"shared-far-span"},  {"shared-far-points"}, {"dilation"},
    {"threads"},           {"settings"},        {"memory-budget"},
    {"reference", 0, false}, {"spp"},       {"single-sided-emission", 0, false},
    {"no-directional", 0, false},
    {"probes"},            {"probe-spacing"},   {"max-probes"},  {"probe-dering"},
    {"reflection-bounces"}, {"reflection-probes"}, kUnitScaleOption,
    {"yes", 'y', false},   {"quiet", 0, false}, {"help", 'h', false}};

// The settings file as `--name=value` arguments, placed before the command line's own so that
// the command line wins.
bool settingsArguments(const std::string& path, std::vector<std::string>* out,
                       std::string* error) {
  Result<std::string> text = readFile(path);
  if (!text) {
    *error = text.message();
    return false;
  }
  const nlohmann::json j = nlohmann::json::parse(text.value(), nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    *error = path + ": not a JSON object";
    return false;
  }
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    if (key == "settings" || key == "output" || key == "help") {
      *error = path + ": '" + key + "' cannot be set in a settings file";
      return false;
    }
    const nlohmann::json& v = it.value();
    std::string value;
    if (v.is_boolean()) {
      if (key != "yes" && key != "quiet" && key != "reference" &&
          key != "single-sided-emission" && key != "no-directional") {
        *error = path + ": '" + key + "' is not a flag";
        return false;
      }
      if (v.get<bool>()) out->push_back("--" + key);
      continue;
    }
    if (v.is_string()) {
      value = v.get<std::string>();
    } else if (v.is_number()) {
      value = v.dump();
    } else if (v.is_array()) {
      for (const nlohmann::json& e : v) {
        if (!e.is_number()) {
          *error = path + ": '" + key + "' wants numbers";
          return false;
        }
        value += (value.empty() ? "" : ",") + e.dump();
      }
    } else {
      *error = path + ": '" + key + "' has an unusable value";
      return false;
    }
    out->push_back("--" + key + "=" + value);
  }
  return true;
}

bool qualityFor(const std::string& name, baker::Quality* q) {
  if (name == "draft") *q = baker::Quality::Draft;
  else if (name == "default") *q = baker::Quality::Default;
  else if (name == "high") *q = baker::Quality::High;
  else return false;
  return true;
}

// The pipeline's steps as the bake prints them before the work starts.
class PrintSteps : public bakefiles::PipelineEvents {
 public:
  explicit PrintSteps(bool quiet) : quiet_(quiet) {}
  void unwrapped(const bakefiles::BakeJob& job, const bakefiles::UnwrapStep& step) override {
    if (quiet_) return;
    std::printf("texels        %zu in %zu atlases at %.3g texels/m; estimated memory %.2f GB "
                "(budget %.2f GB)\n",
                step.texels, step.atlases, double(step.texelsPerUnit), step.estimatedGb,
                double(job.memoryBudgetGb));
    if (step.indirectTexelsPerUnit > 0.0f)
      std::printf("indirect      %.3g texels/m (%s), a %dx%d atlas: bounced light solved there\n",
                  double(step.indirectTexelsPerUnit), step.indirectChoice.c_str(),
                  step.indirectWidth, step.indirectHeight);
    else
      std::printf("indirect      at the lightmap's texels (%s)\n", step.indirectChoice.c_str());
    std::fflush(stdout);
  }
  void probesReady(const bakefiles::BakeJob& job, const bakefiles::ProbeStep& step) override {
    if (!quiet_) {
      const bakefiles::ProbeSet& set = *step.probes;
      std::printf("probes        %zu (%s), %zu tetrahedra\n", set.file.positions.size(),
                  job.probes == "auto"
                      ? format("placed, spacing %.3g m", double(set.spacing)).c_str()
                      : job.probes.c_str(),
                  set.file.mesh.tetrahedra.size());
      if (step.proposed)
        std::printf("reflection    %zu reflection probe%s proposed, one per room (as probes "
                    "place --reflection; --reflection-probes none for none)\n",
                    step.reflectionAdded, step.reflectionAdded == 1 ? "" : "s");
      else if (!set.file.reflectionProbes.empty())
        std::printf("reflection    %zu reflection probe%s from %s (%zu named as the scene's "
                    "own, left out)\n",
                    step.reflectionAdded, step.reflectionAdded == 1 ? "" : "s",
                    job.probes.c_str(), step.reflectionAuthored);
    }
    std::fflush(stdout);
  }

 private:
  bool quiet_;
};

// What the bake made and how long each stage took.
void printSummary(const bakefiles::BakedLevel& level, double writeSeconds,
                  const std::string& outDir, size_t files) {
  const baker::BakeResult& r = level.result;
  size_t valid = 0;
  for (uint8_t v : r.texels.valid) valid += v ? 1 : 0;
  std::printf("texels        %u (%zu valid), gather points %u, clusters %u, links %zu\n",
              r.texels.size(), valid, r.transport.gatherPointCount, r.clusters.size(),
              r.transport.linkCount());
  std::printf("rays          %llu\n", static_cast<unsigned long long>(r.raysTraced));
  std::printf("time         ");
  for (const std::vector<baker::StageTime>* list : {&level.report.extraStages, &r.stages})
    for (const baker::StageTime& s : *list)
      std::printf(" %s %.2f s,", stageName(s.stage), s.seconds);
  std::printf(" %s %.2f s\n", stageName(Stage::Write), writeSeconds);
  std::printf("peak memory   %.2f GB\n", double(peakMemoryBytes()) / 1e9);
  for (const std::string& w : level.report.warnings) std::printf("warning       %s\n", w.c_str());
  for (const std::string& w : r.warnings) std::printf("warning       %s\n", w.c_str());
  std::printf("wrote         %s (%zu files)\n", outDir.c_str(), files);
}

}  // namespace

int runBake(int argc, char** argv, int first) {
  const Command command = {"bake", "bake", kBakeHelp};
  Args args;
  if (std::optional<int> stop = parseOrExit(args, argc, argv, first, kBakeOptions, command))
    return *stop;
  if (args.has("settings")) {
    std::vector<std::string> merged;
    std::string error;
    if (!settingsArguments(args.get("settings"), &merged, &error)) return command.usage(error);
    for (int i = first; i < argc; ++i) merged.push_back(argv[i]);
    std::vector<char*> mergedArgv;
    for (std::string& s : merged) mergedArgv.push_back(s.data());
    Args withSettings;
    if (!withSettings.parse(int(mergedArgv.size()), mergedArgv.data(), 0, kBakeOptions))
      return command.usage(withSettings.error() + " (in " + args.get("settings") +
                           " or the command line)");
    args = withSettings;
  }
  std::string input;
  if (!args.single("SCENE", &input)) return command.usage(args.error());
  if (!args.has("output")) return command.usage("missing -o OUT/");
  const std::string outDir = args.get("output");

  bakefiles::BakeJob job;
  job.input = input;
  job.version = AFTERGLOW_VERSION;
  job.quality = args.get("quality", "default");
  baker::Quality preset;
  if (!qualityFor(job.quality, &preset))
    return command.usage("--quality wants draft, default or high, got '" + job.quality + "'");
  baker::BakeOptions& options = job.bake;
  options = baker::bakePreset(preset);
  int threads = 0, maxProbes = int(job.maxProbes), reflectionBounces = 1;
  const std::string density = args.get("texels-per-unit", "auto");
  if (density != "auto" &&
      !args.getFloat("texels-per-unit", 0.0f, 1e-3f, 1e5f, &job.texelsPerUnit))
    return command.usage(args.error() + " (or 'auto')");
  const std::string indirect = args.get("indirect-texels-per-unit", "auto");
  if (indirect != "auto" && !args.getFloat("indirect-texels-per-unit", 0.0f, 1e-3f, 1e5f,
                                           &job.indirectTexelsPerUnit))
    return command.usage(args.error() + " (or 'auto')");
  if (!args.getInt("atlas-size", 0, 16, 16384, &job.atlasSize) ||
      !args.getInt("texel-rays", options.links.texelRays, 1, 1 << 20, &options.links.texelRays) ||
      !args.getInt("cluster-rays", options.links.clusterRays, 1, 1 << 20,
                   &options.links.clusterRays) ||
      !args.getInt("light-samples", options.direct.lightSamples, 1, 1 << 20,
                   &options.direct.lightSamples) ||
      !args.getInt("emissive-samples", options.direct.emissiveSamples, 1, 1 << 20,
                   &options.direct.emissiveSamples) ||
      !args.getInt("penumbra-samples", options.direct.penumbraSamples, 0, 1 << 20,
                   &options.direct.penumbraSamples) ||
      !args.getInt("filter-passes", options.links.filterPasses, 0, 64,
                   &options.links.filterPasses) ||
      !args.getInt("bounces", 0, 0, 100000, &options.solve.maxBounces) ||
      !args.getFloat("indirect-intensity", 1.0f, -1e-30f, 1e6f, &options.indirectIntensity) ||
      !args.getFloat("albedo-boost", 1.0f, 0.0f, 1e3f, &options.albedoBoost) ||
      !args.getFloat("cluster-size", options.clusters.clusterSize, 0.0f, 1e6f,
                     &options.clusters.clusterSize) ||
      !args.getFloat("cluster-texels", options.clusters.clusterTexels, 0.0f, 1e6f,
                     &options.clusters.clusterTexels) ||
      !args.getFloat("far-distance", options.links.farDistance, 0.0f, 1e6f,
                     &options.links.farDistance) ||
      !args.getInt("far-levels", options.clusters.farLevels, 0, 8, &options.clusters.farLevels) ||
      !args.getInt("shared-far-span", options.links.sharedFarSpan, 0, 1024,
                   &options.links.sharedFarSpan) ||
      !args.getFloat("shared-far-points", options.links.sharedFarPoints, 0.0f, 1e6f,
                     &options.links.sharedFarPoints) ||
      !args.getInt("dilation", 2, 0, 64, &options.dilation) ||
      !args.getInt("threads", 0, 0, 1024, &threads) ||
      !args.getInt("spp", 1024, 1, 1 << 24, &options.referenceOptions.samples) ||
      !args.getFloat("memory-budget", 8.0f, 0.0f, 1e6f, &job.memoryBudgetGb) ||
      !args.getFloat("probe-spacing", 0.0f, 0.0f, 1e6f, &job.probeSpacing) ||
      !args.getInt("max-probes", maxProbes, 1, 100000000, &maxProbes) ||
      !args.getFloat("probe-dering", 0.0f, 0.0f, 1e6f, &job.probeDering) ||
      !args.getInt("reflection-bounces", 1, 0, 64, &reflectionBounces) ||
      !getUnitScale(args, &job.unitScale))
    return command.usage(args.error());
  options.reflections.bounces = uint32_t(reflectionBounces);
  job.maxProbes = size_t(maxProbes);
  job.probes = args.get("probes", "auto");
  job.reflectionProbes = args.get("reflection-probes", "auto");
  if (job.reflectionProbes != "auto" && job.reflectionProbes != "none")
    return command.usage("--reflection-probes wants auto or none, got '" + job.reflectionProbes +
                         "'");
  if (job.atlasSize > 0 && job.texelsPerUnit > 0.0f)
    return command.usage("give --texels-per-unit or --atlas-size, not both");
  options.reference = args.has("reference");
  if (args.has("sky") && !parseVec3(args.get("sky"), &options.skyColor))
    return command.usage("--sky wants r,g,b, got '" + args.get("sky") + "'");
  options.skyImage = args.get("sky-image");
  const std::string mode = args.get("uv", "generate");
  if (mode == "keep") job.unwrap.mode = uv::UvMode::Keep;
  else if (mode != "generate")
    return command.usage("--uv wants generate or keep, got '" + mode + "'");
  job.overBudget = args.has("yes");
  job.singleSidedEmission = args.has("single-sided-emission");
  options.directional = !args.has("no-directional");
  const bool quiet = args.has("quiet");
  setThreadCount(threads);

  ConsoleProgress progress(stderr, quiet);
  InterruptGuard guard(progress);
  auto t0 = Clock::now();
  int code = kExitOk;
  Result<scenes::Scene> loaded = loadSceneOrExit(input, true, &code);
  const double loadSeconds = secondsSince(t0);
  if (!loaded) return code;
  scenes::Scene& scene = loaded.value();
  applyUnitScale(scene, job.unitScale, input);
  if (job.singleSidedEmission)
    for (scenes::Material& m : scene.materials) m.singleSidedEmission = true;

  PrintSteps print(quiet);
  Result<bakefiles::BakedLevel> baked = bakefiles::bakeLevel(scene, job, progress, &print);
  if (interrupted() || progress.cancelled()) return interruptedExit();
  if (!baked) {
    printError(baked.message());
    return kExitBadInput;
  }
  bakefiles::BakedLevel& level = baked.value();
  level.report.extraStages.insert(level.report.extraStages.begin(),
                                  {Stage::Load, loadSeconds});

  AtomicOutput files;
  t0 = Clock::now();
  Result<std::vector<std::string>> written =
      bakefiles::writeBakeFolder(scene, level, outDir, files);
  if (!written) {
    printError(written.message());
    return kExitOutput;
  }
  if (interrupted()) return interruptedExit();
  if (Status st = files.commit(); !st) {
    printError(st.message());
    return kExitOutput;
  }
  if (!quiet) printSummary(level, secondsSince(t0), outDir, written->size());
  return kExitOk;
}

}  // namespace afterglow::cli
