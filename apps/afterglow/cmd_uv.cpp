// afterglow uv: lightmap UVs for a scene, written as glTF plus atlas pictures and a JSON report.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <system_error>

#include <nlohmann/json.hpp>

#include "afterglow/core/atomic_file.h"
#include "afterglow/core/parallel.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/uv/atlas_image.h"
#include "afterglow/uv/unwrap.h"
#include "args.h"
#include "commands.h"
#include "common.h"

namespace fs = std::filesystem;

namespace afterglow::cli {

const char kUvHelp[] =
    "Usage: afterglow uv SCENE -o OUT.gltf [options]\n"
    "\n"
    "Gives every static instance of SCENE lightmap UVs (TEXCOORD_1) packed into atlases, and\n"
    "writes:\n"
    "  OUT.gltf (+ its .bin)  the scene with TEXCOORD_1; every lightmapped node records\n"
    "                         extras.afterglow.lightmap = {atlas, width, height}\n"
    "  OUT_atlas<i>.png       a picture of each atlas, one colour per chart\n"
    "  OUT_uv.json            the quality report: metrics, timings, options\n"
    "Nothing is written when anything fails or the run is interrupted.\n"
    "SCENE is a .gltf or .glb file, or a built-in scene: builtin:cornell,\n"
    "builtin:cornell-metal (mirror and copper blocks, a reflection probe), builtin:furnace.\n"
    "\n"
    "Options:\n"
    "  -o, --output OUT.gltf   output glTF (.gltf or .glb); required\n"
    "  --texels-per-unit N     lightmap texels per metre (default 16), times each node's\n"
    "                          extras.afterglow.lightmapScale\n"
    "  --padding N             empty texels between charts (default 2)\n"
    "  --max-atlas-size N      largest atlas side in texels (default 4096); charts spill into\n"
    "                          more atlases past it\n"
    "  --uv generate|keep      make new UVs (default), or keep the authored TEXCOORD_1 when it\n"
    "                          is valid (inside [0,1], no overlaps): a layout recorded in\n"
    "                          extras.afterglow.lightmap is kept, otherwise each static\n"
    "                          instance gets an atlas of its own\n"
    "  --threads N             worker threads (default: every core)\n"
    "  --quiet                 no progress bar and no summary\n"
    "  -h, --help              this help\n";

namespace {

// "2 × 4096x4096, 512x512": atlas sizes grouped, in order of first appearance.
std::string atlasSummary(const std::vector<uv::AtlasMetrics>& atlases) {
  std::vector<std::pair<std::pair<int, int>, int>> groups;
  for (const uv::AtlasMetrics& a : atlases) {
    bool found = false;
    for (auto& g : groups)
      if (g.first == std::make_pair(a.width, a.height)) {
        ++g.second;
        found = true;
      }
    if (!found) groups.push_back({{a.width, a.height}, 1});
  }
  std::string out;
  for (const auto& g : groups) {
    if (!out.empty()) out += ", ";
    if (g.second > 1) out += format("%d x ", g.second);
    out += format("%dx%d", g.first.first, g.first.second);
  }
  return out;
}

struct Timings {
  double load = 0, pictures = 0, gltf = 0;
  uv::UnwrapTimings unwrap;
};

std::string reportJson(const std::string& input, const std::string& output,
                       const uv::UnwrapOptions& options, int threads, const scenes::Scene& scene,
                       const uv::UnwrapResult& result, const Timings& t,
                       const std::vector<std::string>& pictures, Status* status) {
  nlohmann::json metrics = nlohmann::json::parse(uv::metricsToJson(result.metrics), nullptr, false);
  if (metrics.is_discarded()) {
    *status = Status::error("internal error: metricsToJson produced invalid JSON");
    return {};
  }
  nlohmann::json j;
  j["afterglowVersion"] = AFTERGLOW_VERSION;
  j["input"] = input;
  j["output"] = output;
  j["options"] = {{"uv", options.mode == uv::UvMode::Keep ? "keep" : "generate"},
                  {"texelsPerUnit", options.pack.texelsPerUnit},
                  {"padding", options.pack.padding},
                  {"maxAtlasSize", options.pack.maxAtlasSize},
                  {"threads", threads}};
  size_t statics = 0, lightmapped = 0;
  for (const scenes::Instance& inst : scene.instances) {
    statics += inst.isStatic ? 1 : 0;
    lightmapped += inst.lightmap.atlas >= 0 ? 1 : 0;
  }
  j["instances"] = {{"total", scene.instances.size()},
                    {"static", statics},
                    {"lightmapped", lightmapped}};
  j["timings"] = {{"load", t.load},
                  {"charts", t.unwrap.charts},
                  {"pack", t.unwrap.pack},
                  {"apply", t.unwrap.apply},
                  {"metrics", t.unwrap.metrics},
                  {"pictures", t.pictures}};
  nlohmann::json pics = nlohmann::json::array();
  for (const std::string& p : pictures) pics.push_back(fs::path(p).filename().string());
  j["pictures"] = pics;
  j["metrics"] = metrics;
  nlohmann::json warnings = nlohmann::json::array();
  for (const std::string& w : scene.warnings) warnings.push_back(w);
  for (const std::string& w : result.warnings) warnings.push_back(w);
  j["warnings"] = warnings;
  *status = Status::ok();
  return j.dump(2) + "\n";
}

void printSummary(const std::string& output, const scenes::Scene& scene,
                  const uv::UnwrapResult& result, const Timings& t, int padding,
                  const std::vector<std::string>& written) {
  const uv::Metrics& m = result.metrics;
  size_t statics = 0, lightmapped = 0;
  for (const scenes::Instance& inst : scene.instances) {
    statics += inst.isStatic ? 1 : 0;
    lightmapped += inst.lightmap.atlas >= 0 ? 1 : 0;
  }
  std::printf("instances     %zu lightmapped (%zu static, %zu in all), %zu triangles\n",
              lightmapped, statics, scene.instances.size(), m.triangleCount);
  std::printf("charts        %zu\n", m.chartCount);
  std::printf("atlases       %zu: %s\n", m.atlases.size(), atlasSummary(m.atlases).c_str());
  std::printf("utilisation   %.3f\n", m.utilization);
  std::printf("overlaps      %zu texels; padding (%d texels) violations %zu; outside [0,1] %zu\n",
              m.overlappingTexels, padding, m.paddingViolations, m.outOfRangeTriangles);
  std::printf("stretch       L2 %.3f (worst chart %.3f); flipped triangles %zu\n", m.stretchL2,
              m.stretchL2Max, m.flippedTriangles);
  std::printf("density       spread %.3f; %.2f to %.2f texels/m\n", m.densitySpread,
              m.densityMin, m.densityMax);
  std::printf("time          load %.2f s, charts %.2f s, pack %.2f s, apply %.2f s, metrics %.2f s, "
              "write %.2f s\n",
              t.load, t.unwrap.charts, t.unwrap.pack, t.unwrap.apply, t.unwrap.metrics,
              t.pictures + t.gltf);
  for (const std::string& w : scene.warnings) std::printf("warning       %s\n", w.c_str());
  for (const std::string& w : result.warnings) std::printf("warning       %s\n", w.c_str());
  std::printf("wrote         %s", output.c_str());
  for (const std::string& w : written) std::printf(", %s", fs::path(w).filename().c_str());
  std::printf("\n");
}

}  // namespace

int runUv(int argc, char** argv, int first) {
  const Command command = {"uv", "uv", kUvHelp};
  Args args;
  if (std::optional<int> stop = parseOrExit(args, argc, argv, first,
                                            {{"output", 'o'},
                                             {"texels-per-unit"},
                                             {"padding"},
                                             {"max-atlas-size"},
                                             {"uv"},
                                             {"threads"},
                                             {"quiet", 0, false},
                                             {"help", 'h', false}},
                                            command))
    return *stop;
  std::string input;
  if (!args.single("SCENE", &input)) return command.usage(args.error());
  if (!args.has("output")) return command.usage("missing -o OUT.gltf");
  const std::string output = args.get("output");
  if (!endsWith(output, ".gltf") && !endsWith(output, ".glb"))
    return command.usage("the output must end in .gltf or .glb, got '" + output + "'");

  uv::UnwrapOptions options;
  int threads = 0;
  if (!args.getFloat("texels-per-unit", 16.0f, 0.0f, 1e6f, &options.pack.texelsPerUnit) ||
      !args.getInt("padding", 2, 0, 64, &options.pack.padding) ||
      !args.getInt("max-atlas-size", 4096, 16, 65536, &options.pack.maxAtlasSize) ||
      !args.getInt("threads", 0, 0, 1024, &threads))
    return command.usage(args.error());
  const std::string mode = args.get("uv", "generate");
  if (mode == "keep")
    options.mode = uv::UvMode::Keep;
  else if (mode != "generate")
    return command.usage("--uv wants generate or keep, got '" + mode + "'");
  const bool quiet = args.has("quiet");
  setThreadCount(threads);

  ConsoleProgress progress(stderr, quiet);
  InterruptGuard guard(progress);
  Timings timings;

  // Texture images are not needed for UVs; the export keeps their URIs.
  auto t0 = Clock::now();
  int code = kExitOk;
  Result<scenes::Scene> loaded = loadSceneOrExit(input, false, &code);
  timings.load = secondsSince(t0);
  if (!loaded) return code;
  scenes::Scene& scene = loaded.value();

  Result<uv::UnwrapResult> unwrapped = uv::unwrap(scene, options, progress);
  if (interrupted() || progress.cancelled()) return interruptedExit();
  if (!unwrapped) {
    printError(unwrapped.message());
    return kExitBadInput;
  }
  const uv::UnwrapResult& result = unwrapped.value();

  // Pictures and report go to temporary files first; the glTF is saved last (saveGltf is atomic
  // on its own) and only then are the others moved into place, so a failure anywhere leaves
  // nothing behind.
  const fs::path outPath(output);
  const std::string stem = (outPath.parent_path() / outPath.stem()).string();
  AtomicOutput files;
  t0 = Clock::now();
  Result<std::vector<std::string>> pictures =
      uv::writeAtlasPictures(scene, stem + "_atlas", files);
  timings.pictures = secondsSince(t0);
  if (!pictures) {
    printError(pictures.message());
    return kExitOutput;
  }
  timings.unwrap = result.timings;
  Status status;
  std::string report = reportJson(input, output, options, threadCount(), scene, result, timings,
                                  pictures.value(), &status);
  if (!status) {
    printError(status.message());
    return kExitOutput;
  }
  const std::string reportPath = stem + "_uv.json";
  if (Status st = files.write(reportPath, report); !st) {
    printError(st.message());
    return kExitOutput;
  }
  if (interrupted()) return interruptedExit();
  t0 = Clock::now();
  if (Status st = scenes::saveGltf(scene, output); !st) {
    printError(st.message());
    return kExitOutput;
  }
  timings.gltf = secondsSince(t0);
  if (Status st = files.commit(); !st) {
    // Undo the glTF so that the run leaves nothing half-done.
    std::error_code ec;
    fs::remove(output, ec);
    if (endsWith(output, ".gltf")) fs::remove(stem + ".bin", ec);
    printError(st.message());
    return kExitOutput;
  }
  if (!quiet) {
    std::vector<std::string> written;
    if (endsWith(output, ".gltf")) written.push_back(stem + ".bin");
    written.insert(written.end(), pictures.value().begin(), pictures.value().end());
    written.push_back(reportPath);
    printSummary(output, scene, result, timings, options.pack.padding, written);
  }
  return kExitOk;
}

}  // namespace afterglow::cli
