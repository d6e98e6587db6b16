// afterglow bake: UVs, the precompute and one solve, written as lightmaps + glTF + report.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afterglow/baker/bake.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/memory.h"
#include "afterglow/core/parallel.h"
#include "afterglow/uv/unwrap.h"
#include "afterglow/baker/bake_output.h"
#include "afterglow/baker/raytracer.h"
#include "afterglow/probes/placement.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/probe_sh_file.h"
#include "args.h"
#include "commands.h"
#include "common.h"

namespace fs = std::filesystem;

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
    "  --uv generate|keep       new lightmap UVs (default) or the authored TEXCOORD_1\n"
    "  --quality Q              draft | default | high: gather rays per texel, first and\n"
    "                           penumbra shadow rays, smoothing passes (32/8/64/3,\n"
    "                           64/16/128/2, 256/32/512/1)\n"
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
    "  --shared-far-span N      texels near other geometry within N texels on one surface pool\n"
    "                           their far-cluster rays into one shared row (default 4; 0: off)\n"
    "  --shared-far-points X    rays a shared far row keeps, in gather points' rays (default 2)\n"
    "  --dilation N             texels each chart is grown into its padding (default 2)\n"
    "  --single-sided-emission  double-sided emissive materials emit from their front only\n"
    "                           (default: both sides, as glTF says); written on the output's\n"
    "                           materials as extras.afterglow.singleSidedEmission\n"
    "  --probes auto|none|FILE  light probes: placed automatically (default, as afterglow\n"
    "                           probes place does), none, or a PROBES.json from probes place;\n"
    "                           a file's reflectionProbes (probes place --reflection) are\n"
    "                           captured too, except one named as a node's own\n"
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

// `--texels-per-unit auto`: about a 512² atlas's worth of texels, whatever the level's scale.
constexpr double kAutoTexels = 512.0 * 512.0;

const std::vector<OptionSpec> kBakeOptions = {
    {"output", 'o'},       {"texels-per-unit"}, {"atlas-size"}, {"uv"},
    {"penumbra-samples"},  {"filter-passes"},
    {"quality"},           {"texel-rays"},      {"cluster-rays"},
    {"light-samples"},     {"emissive-samples"}, {"bounces"},
    {"indirect-intensity"}, {"albedo-boost"},    {"sky"},
    {"sky-image"},         {"cluster-size"},    {"cluster-texels"},
    {"far-distance"},      {"shared-far-span"},  {"shared-far-points"}, {"dilation"},
    {"threads"},           {"settings"},        {"memory-budget"},
    {"reference", 0, false}, {"spp"},       {"single-sided-emission", 0, false},
    {"probes"},            {"probe-spacing"},   {"max-probes"},  {"probe-dering"},
    {"reflection-bounces"},
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
          key != "single-sided-emission") {
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

// An estimate of the bake's peak memory: decoded textures, texel and cluster records, their
// links (at most one per ray), per-source transfer, sky transfer, atlas images and the BVH.
// Sponza-sun at 4 texels/m: estimated 1.27 GB, measured peak 0.95 GB.
double estimateBytes(const scenes::Scene& scene, size_t texels, size_t atlasPixels,
                     float texelsPerUnit, const baker::BakeOptions& o) {
  size_t sources = scene.lights.size();
  for (const scenes::Material& m : scene.materials) sources += m.emissive() ? 1 : 0;
  double textureBytes = 0.0;
  for (const scenes::Texture& t : scene.textures)
    textureBytes += double(t.width) * double(t.height) * sizeof(glm::vec4);
  // Charts smaller than a cluster make clusters smaller than clusterSize: count half the ideal.
  double side = double(o.clusters.clusterSize) * double(texelsPerUnit);
  if (o.clusters.clusterTexels > 0.0f) side = std::min(side, double(o.clusters.clusterTexels));
  const double clusters = double(texels) / std::max(1.0, side * side * 0.5) + 1.0;
  const double perTexel = 96.0 + 36.0 + 12.0 + 8.0 * double(o.links.texelRays) +
                          4.0 * double(sources) * 2.0;
  const double perCluster = 96.0 + 36.0 + 8.0 * double(o.links.clusterRays);
  return textureBytes + double(texels) * perTexel + clusters * perCluster +
         double(atlasPixels) * 40.0 + double(scene.instancedTriangleCount()) * 160.0 +
         64.0 * 1024 * 1024;
}

// The light probes a bake uses, and how they came about.
struct ProbeSet {
  probes::ProbesFile file;
  float spacing = 0.0f;       // of an automatic placement (0 for a file)
  nlohmann::json summary = nlohmann::json::object();
};

Result<ProbeSet> placeBakeProbes(const scenes::Scene& scene, float spacing, size_t maxProbes,
                                 Progress& progress) {
  Result<std::unique_ptr<baker::RayTracer>> tracer = baker::RayTracer::build(scene);
  if (!tracer) return tracer.status();
  probes::PlacementOptions o;
  o.spacing = spacing;
  o.maxProbes = maxProbes;
  Result<probes::Placement> placed = probes::placeProbes(scene, *tracer.value(), o, progress);
  if (!placed) return Status::error(scene.sourcePath + ": " + placed.message());
  Result<runtime::ProbeTetrahedra> mesh = probes::tetrahedralize(placed->positions);
  if (!mesh) return Status::error(scene.sourcePath + ": " + mesh.message());
  ProbeSet out;
  out.file.positions = placed->positions;
  out.file.kinds = placed->kinds;
  out.file.names.assign(placed->positions.size(), "");
  out.file.mesh = std::move(mesh.value());
  out.spacing = placed->spacing;
  out.summary = {{"candidates", placed->candidates},
                 {"placed", placed->positions.size()},
                 {"rejectedInsideGeometry", placed->rejected},
                 {"moved", placed->moved},
                 {"refined", placed->refined},
                 {"tetrahedra", out.file.mesh.tetrahedra.size()},
                 {"warnings", placed->warnings}};
  return out;
}

Result<ProbeSet> readBakeProbes(const std::string& path) {
  Result<probes::ProbesFile> file = probes::readProbesFile(path);
  if (!file) return file.status();
  ProbeSet out;
  out.file = std::move(file.value());
  out.summary = {{"from", path},
                 {"placed", out.file.positions.size()},
                 {"tetrahedra", out.file.mesh.tetrahedra.size()}};
  return out;
}

// OUT/probes/light_probes.json (the placement's format, with the SH file named) and
// OUT/probes/light_probes_sh.bin, through the bake's atomic output.
Status writeProbeOutputs(const std::string& outDir, const ProbeSet& set,
                         const std::vector<runtime::ShL2>& sh, float dering,
                         const nlohmann::json& bakeSettings, AtomicOutput& files) {
  const fs::path dir = fs::path(outDir) / "probes";
  probes::Placement placement;
  placement.positions = set.file.positions;
  placement.kinds = set.file.kinds;
  nlohmann::json settings = {{"probes", bakeSettings.value("probes", "auto")},
                             {"spacing", set.spacing},
                             {"rays", bakeSettings.value("probeRays", 0)},
                             {"regions", bakeSettings.value("probeRegions", 0)},
                             {"emitterSamples", bakeSettings.value("probeEmitterSamples", 0)}};
  const nlohmann::json shInfo = {
      {"file", "light_probes_sh.bin"},
      {"format", "afterglow-light-probe-sh"},
      {"version", runtime::kProbeShVersion},
      {"basis", "real SH L2, bands 0-2, orthonormal (Y00 = 0.282095), world axes +Y up"},
      {"stores", "radiance SH L_i = integral of L(w) Y_i(w) dw, RGB; E/pi via the "
                 "clamped-cosine convolution (runtime/probe_sh.h)"},
      {"deringWindow", dering}};
  const std::string text = probes::probesJson(placement, set.file.names, set.file.mesh,
                                              settings.dump(), set.summary.dump(), shInfo.dump());
  runtime::ProbeShFile file;
  file.deringWindow = dering;
  file.sh = sh;
  if (dering > 0.0f)
    for (runtime::ShL2& s : file.sh) s = runtime::deringed(s, dering);
  const std::vector<uint8_t> bytes = runtime::serializeProbeSh(file);
  if (Status st = files.write((dir / "light_probes.json").string(), text); !st) return st;
  return files.write((dir / "light_probes_sh.bin").string(),
                     std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace

int runBake(int argc, char** argv, int first) {
  auto usage = [](const std::string& message) {
    printError("bake: " + message + " (see afterglow bake --help)");
    return int(kExitUsage);
  };
  Args args;
  if (!args.parse(argc, argv, first, kBakeOptions)) return usage(args.error());
  if (args.has("help")) {
    std::printf("%s\n%s", kBakeHelp, kExitCodesHelp);
    return kExitOk;
  }
  if (args.has("settings")) {
    std::vector<std::string> merged;
    std::string error;
    if (!settingsArguments(args.get("settings"), &merged, &error)) return usage(error);
    for (int i = first; i < argc; ++i) merged.push_back(argv[i]);
    std::vector<char*> mergedArgv;
    for (std::string& s : merged) mergedArgv.push_back(s.data());
    Args withSettings;
    if (!withSettings.parse(int(mergedArgv.size()), mergedArgv.data(), 0, kBakeOptions))
      return usage(withSettings.error() + " (in " + args.get("settings") + " or the command line)");
    args = withSettings;
  }
  std::string input;
  if (!args.single("SCENE", &input)) return usage(args.error());
  if (!args.has("output")) return usage("missing -o OUT/");
  const std::string outDir = args.get("output");

  uv::UnwrapOptions unwrapOptions;
  const std::string quality = args.get("quality", "default");
  baker::Quality preset;
  if (!qualityFor(quality, &preset))
    return usage("--quality wants draft, default or high, got '" + quality + "'");
  baker::BakeOptions options = baker::bakePreset(preset);
  int threads = 0, bounces = 0, atlasSize = 0;
  float budgetGb = 8.0f, texelsPerUnit = 0.0f, probeSpacing = 0.0f, probeDering = 0.0f;
  int maxProbes = 100000, reflectionBounces = 1;
  const std::string density = args.get("texels-per-unit", "auto");
  if (density != "auto" &&
      !args.getFloat("texels-per-unit", 0.0f, 1e-3f, 1e5f, &texelsPerUnit))
    return usage(args.error() + " (or 'auto')");
  if (!args.getInt("atlas-size", 0, 16, 16384, &atlasSize) ||
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
      !args.getInt("bounces", 0, 0, 100000, &bounces) ||
      !args.getFloat("indirect-intensity", 1.0f, -1e-30f, 1e6f, &options.indirectIntensity) ||
      !args.getFloat("albedo-boost", 1.0f, 0.0f, 1e3f, &options.albedoBoost) ||
      !args.getFloat("cluster-size", options.clusters.clusterSize, 0.0f, 1e6f,
                     &options.clusters.clusterSize) ||
      !args.getFloat("cluster-texels", options.clusters.clusterTexels, 0.0f, 1e6f,
                     &options.clusters.clusterTexels) ||
      !args.getFloat("far-distance", options.links.farDistance, 0.0f, 1e6f,
                     &options.links.farDistance) ||
      !args.getInt("shared-far-span", options.links.sharedFarSpan, 0, 1024,
                   &options.links.sharedFarSpan) ||
      !args.getFloat("shared-far-points", options.links.sharedFarPoints, 0.0f, 1e6f,
                     &options.links.sharedFarPoints) ||
      !args.getInt("dilation", 2, 0, 64, &options.dilation) ||
      !args.getInt("threads", 0, 0, 1024, &threads) ||
      !args.getInt("spp", 1024, 1, 1 << 24, &options.referenceOptions.samples) ||
      !args.getFloat("memory-budget", 8.0f, 0.0f, 1e6f, &budgetGb) ||
      !args.getFloat("probe-spacing", 0.0f, 0.0f, 1e6f, &probeSpacing) ||
      !args.getInt("max-probes", 100000, 1, 100000000, &maxProbes) ||
      !args.getFloat("probe-dering", 0.0f, 0.0f, 1e6f, &probeDering) ||
      !args.getInt("reflection-bounces", 1, 0, 64, &reflectionBounces))
    return usage(args.error());
  options.reflections.bounces = uint32_t(reflectionBounces);
  const std::string probesMode = args.get("probes", "auto");
  if (atlasSize > 0 && texelsPerUnit > 0.0f)
    return usage("give --texels-per-unit or --atlas-size, not both");
  options.solve.maxBounces = bounces;
  options.reference = args.has("reference");
  if (args.has("sky") && !parseVec3(args.get("sky"), &options.skyColor))
    return usage("--sky wants r,g,b, got '" + args.get("sky") + "'");
  options.skyImage = args.get("sky-image");
  const std::string mode = args.get("uv", "generate");
  if (mode == "keep") unwrapOptions.mode = uv::UvMode::Keep;
  else if (mode != "generate") return usage("--uv wants generate or keep, got '" + mode + "'");
  const bool quiet = args.has("quiet");
  setThreadCount(threads);

  ConsoleProgress progress(stderr, quiet);
  InterruptGuard guard(progress);
  baker::BakeReportInfo info;
  info.version = AFTERGLOW_VERSION;
  info.input = input;

  auto t0 = Clock::now();
  bool badArgument = false;
  Result<scenes::Scene> loaded = loadSceneArgument(input, true, &badArgument);
  info.extraStages.push_back({"load", secondsSince(t0)});
  if (interrupted()) return interruptedExit();
  if (!loaded) {
    printError(loaded.message());
    return badArgument ? kExitUsage : kExitBadInput;
  }
  scenes::Scene& scene = loaded.value();
  info.warnings = scene.warnings;
  const bool singleSidedEmission = args.has("single-sided-emission");
  if (singleSidedEmission)
    for (scenes::Material& m : scene.materials) m.singleSidedEmission = true;

  t0 = Clock::now();
  // Texel density: given, fitted to one atlas, or (by default) about kAutoTexels texels.
  if (atlasSize > 0) {
    Result<float> fitted = uv::fitTexelsPerUnit(scene, unwrapOptions, atlasSize, progress);
    if (interrupted() || progress.cancelled()) return interruptedExit();
    if (!fitted) {
      printError(input + ": " + fitted.message());
      return kExitBadInput;
    }
    texelsPerUnit = fitted.value();
    unwrapOptions.pack.maxAtlasSize = atlasSize;
  } else if (!(texelsPerUnit > 0.0f)) {
    texelsPerUnit = uv::texelsPerUnitFor(scene, kAutoTexels);
    if (!(texelsPerUnit > 0.0f)) {
      printError(input + ": nothing to bake: no static instance has triangles");
      return kExitBadInput;
    }
    // Two significant digits, so the report shows a number a person would pick.
    const float magnitude = std::pow(10.0f, std::floor(std::log10(texelsPerUnit)) - 1.0f);
    texelsPerUnit = std::round(texelsPerUnit / magnitude) * magnitude;
  }
  unwrapOptions.pack.texelsPerUnit = texelsPerUnit;
  Result<uv::UnwrapResult> unwrapped = uv::unwrap(scene, unwrapOptions, progress);
  info.extraStages.push_back({"uv", secondsSince(t0)});
  if (interrupted() || progress.cancelled()) return interruptedExit();
  if (!unwrapped) {
    printError(unwrapped.message());
    return kExitBadInput;
  }
  info.warnings.insert(info.warnings.end(), unwrapped->warnings.begin(),
                       unwrapped->warnings.end());

  size_t texels = 0, atlasPixels = 0;
  for (const uv::AtlasMetrics& a : unwrapped->metrics.atlases) {
    texels += a.coveredTexels;
    atlasPixels += size_t(a.width) * size_t(a.height);
  }
  const double estimateGb = estimateBytes(scene, texels, atlasPixels, unwrapOptions.pack.texelsPerUnit, options) / 1e9;
  if (!quiet)
    std::printf("texels        %zu in %zu atlases at %.3g texels/m; estimated memory %.2f GB "
                "(budget %.2f GB)\n",
                texels, unwrapped->metrics.atlases.size(), double(texelsPerUnit), estimateGb,
                double(budgetGb));
  std::fflush(stdout);
  if (estimateGb > double(budgetGb) && !args.has("yes")) {
    printError(format("bake: the estimated memory (%.2f GB for %zu texels) is over the budget of "
                      "%.2f GB; lower --texels-per-unit (is the scene in metres?), raise "
                      "--memory-budget GB, or pass --yes to bake anyway. Nothing written.",
                      estimateGb, texels, double(budgetGb)));
    return kExitBadInput;
  }

  // Light probes: placed (as `probes place` does) or read, before the bake so that a bad probes
  // file or too many probes stops it before minutes of precompute.
  ProbeSet probeSet;
  if (!options.reference && probesMode != "none") {
    const auto probeStart = Clock::now();
    Result<ProbeSet> got = probesMode == "auto"
                               ? placeBakeProbes(scene, probeSpacing, size_t(maxProbes), progress)
                               : readBakeProbes(probesMode);
    if (interrupted() || progress.cancelled()) return interruptedExit();
    if (!got) {
      printError(got.message());
      return kExitBadInput;
    }
    probeSet = std::move(got.value());
    options.probes = probeSet.file.mesh;
    // The file's reflection probes (probes place --reflection) join the scene's, except where a
    // node of the scene authors one of the same name: the level's own probe wins over a proposal.
    size_t reflectionAdded = 0, reflectionAuthored = 0;
    for (const probes::ReflectionProbeEntry& r : probeSet.file.reflectionProbes) {
      const bool authored =
          std::any_of(scene.reflectionProbes.begin(), scene.reflectionProbes.end(),
                      [&](const scenes::ReflectionProbe& p) { return p.name == r.name; });
      if (authored) {
        ++reflectionAuthored;
        continue;
      }
      scene.reflectionProbes.push_back(probes::toSceneReflectionProbe(r));
      ++reflectionAdded;
    }
    if (reflectionAuthored > 0)
      info.warnings.push_back(format(
          "%s: %zu of its reflection probes left out: the scene's nodes author probes of those "
          "names",
          probesMode.c_str(), reflectionAuthored));
    info.extraStages.push_back({"probe placement", secondsSince(probeStart)});
    if (!quiet) {
      std::printf("probes        %zu (%s), %zu tetrahedra\n", probeSet.file.positions.size(),
                  probesMode == "auto" ? format("placed, spacing %.3g m", double(probeSet.spacing)).c_str()
                                       : probesMode.c_str(),
                  probeSet.file.mesh.tetrahedra.size());
      if (!probeSet.file.reflectionProbes.empty())
        std::printf("reflection    %zu reflection probe%s from %s (%zu named as the scene's "
                    "own, left out)\n",
                    reflectionAdded, reflectionAdded == 1 ? "" : "s", probesMode.c_str(),
                    reflectionAuthored);
    }
    std::fflush(stdout);
  }

  Result<baker::BakeResult> baked = baker::bake(scene, options, progress);
  if (interrupted() || progress.cancelled()) return interruptedExit();
  if (!baked) {
    printError(baked.message());
    return kExitBadInput;
  }

  nlohmann::json settings = {{"texelsPerUnit", unwrapOptions.pack.texelsPerUnit},
                             {"atlasSize", atlasSize},
                             {"uv", mode},
                             {"quality", quality},
                             {"texelRays", options.links.texelRays},
                             {"clusterRays", options.links.clusterRays},
                             {"lightSamples", options.direct.lightSamples},
                             {"emissiveSamples", options.direct.emissiveSamples},
                             {"penumbraSamples", options.direct.penumbraSamples},
                             {"filterPasses", options.links.filterPasses},
                             {"bounces", bounces},
                             {"indirectIntensity", options.indirectIntensity},
                             {"albedoBoost", options.albedoBoost},
                             {"sky", {options.skyColor.r, options.skyColor.g, options.skyColor.b}},
                             // Absolute, so `render --reference` finds it from anywhere.
                             {"skyImage", options.skyImage.empty()
                                              ? std::string()
                                              : fs::absolute(options.skyImage).string()},
                             {"clusterSize", options.clusters.clusterSize},
                             {"clusterTexels", options.clusters.clusterTexels},
                             {"dilation", options.dilation},
                             {"singleSidedEmission", singleSidedEmission},
                             {"threads", threadCount()},
                             {"reference", options.reference},
                             {"referenceSpp", options.referenceOptions.samples},
                             {"memoryBudgetGb", budgetGb},
                             {"estimatedMemoryGb", estimateGb},
                             {"probes", probesMode},
                             {"probeSpacing", probeSet.spacing},
                             {"probeDering", probeDering},
                             {"probeRays", options.probeOptions.raysSide * options.probeOptions.raysSide},
                             {"probeRegions", options.probeOptions.binsSide * options.probeOptions.binsSide},
                             {"probeEmitterSamples", options.probeOptions.emitterSamples},
                             {"reflectionBounces", reflectionBounces}};
  info.settingsJson = settings.dump();

  AtomicOutput files;
  t0 = Clock::now();
  Result<std::vector<std::string>> written =
      baker::writeBakeOutputs(scene, baked.value(), outDir, info, files);
  if (!written) {
    printError(written.message());
    return kExitOutput;
  }
  if (!baked->probeSh.empty()) {
    if (Status st = writeProbeOutputs(outDir, probeSet, baked->probeSh, probeDering, settings, files);
        !st) {
      printError(st.message());
      return kExitOutput;
    }
    written->push_back((fs::path(outDir) / "probes" / "light_probes.json").string());
    written->push_back((fs::path(outDir) / "probes" / "light_probes_sh.bin").string());
  }
  if (interrupted()) return interruptedExit();
  if (Status st = files.commit(); !st) {
    printError(st.message());
    return kExitOutput;
  }
  if (!quiet) {
    const baker::BakeResult& r = baked.value();
    size_t valid = 0;
    for (uint8_t v : r.texels.valid) valid += v ? 1 : 0;
    std::printf("texels        %u (%zu valid), gather points %u, clusters %u, links %zu\n",
                r.texels.size(), valid, r.transport.gatherPointCount, r.clusters.size(),
                r.transport.linkCount());
    std::printf("rays          %llu\n", static_cast<unsigned long long>(r.raysTraced));
    std::printf("time         ");
    for (const baker::StageTime& s : info.extraStages) std::printf(" %s %.2f s,", s.name.c_str(), s.seconds);
    for (const baker::StageTime& s : r.stages) std::printf(" %s %.2f s,", s.name.c_str(), s.seconds);
    std::printf(" write %.2f s\n", secondsSince(t0));
    std::printf("peak memory   %.2f GB\n", double(peakMemoryBytes()) / 1e9);
    for (const std::string& w : info.warnings) std::printf("warning       %s\n", w.c_str());
    for (const std::string& w : r.warnings) std::printf("warning       %s\n", w.c_str());
    std::printf("wrote         %s (%zu files)\n", outDir.c_str(), written->size());
  }
  return kExitOk;
}

}  // namespace afterglow::cli
