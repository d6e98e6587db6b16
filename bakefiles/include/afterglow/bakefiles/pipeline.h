// The whole `afterglow bake` job on a loaded level, in stages.h's order: lightmap UVs at a
// density chosen from the level (or given), a memory estimate held against a budget, light
// probes placed or read (their file's reflection probes joining the scene's), the precompute and
// solve (baker::bake), then the bake folder written. The CLI, the benchmarks and the tests run
// it; each step is a function of its own too.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afterglow/bakefiles/write.h"
#include "afterglow/baker/bake.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/scenes/scene.h"
#include "afterglow/uv/unwrap.h"

namespace afterglow::bakefiles {

// `--texels-per-unit auto`: about a 512² atlas's worth of texels, whatever the level's scale.
constexpr double kAutoTexels = 512.0 * 512.0;
// Atlases grow to this size when an instance does not fit the usual 4,096 (engines take
// 8,192² textures; OpenEXR and the runtime do not mind).
constexpr int kLargeAtlas = 8192;
// `--indirect-texels-per-unit auto`: bounced light on an indirect grid of about
// kAutoIndirectTexels texels (uv/indirect.h) when that is at most half the lightmap's density
// (a quarter of its texels), else at the lightmap's own texels (so the default density,
// kAutoTexels, keeps one resolution). A relight's bounce costs about 25 ns an indirect texel on
// one core, so the grid keeps a bounce near 3 ms whatever the lightmap's density (Unity solves
// indirect light at 2 texels per unit beside 40 for its lightmaps). The grid carries the sky as
// well, so sky light through a window is as soft as the grid is coarse.
constexpr double kAutoIndirectTexels = 128.0 * 1024.0;

// Everything a bake is asked to do.
struct BakeJob {
  std::string input;               // the SCENE argument, for messages and the report
  std::string version;             // afterglow's, for the report
  uv::UnwrapOptions unwrap;        // its pack.texelsPerUnit is chosen from the two below
  float texelsPerUnit = 0.0f;      // texels per metre; 0: auto (about kAutoTexels texels)
  // Indirect texels per metre (Unity's indirect resolution); 0: auto (kAutoIndirectTexels);
  // at or above the lightmap's density: bounced light at the lightmap's texels, one resolution.
  float indirectTexelsPerUnit = 0.0f;
  int atlasSize = 0;               // instead: the most texels per metre fitting one such atlas
  std::string quality = "default"; // the preset bake's options came from (for the report)
  baker::BakeOptions bake;         // its probes are filled from the probes below
  std::string probes = "auto";     // auto | none | a PROBES.json (probes place)
  // auto: the scene's authored reflection probes, or (without any, and with probes auto) one
  // proposed per room as `probes place --reflection` proposes them; none: no reflection probes.
  std::string reflectionProbes = "auto";
  float probeSpacing = 0.0f;       // metres between automatic grid probes (0: from the level)
  size_t maxProbes = 100000;       // refuse an automatic placement of more
  float probeDering = 0.0f;        // the SH file's Hanning window (0: as baked)
  bool singleSidedEmission = false;  // recorded: the scene's materials are already set
  float unitScale = 1.0f;          // recorded: metres per unit the scene was already scaled by
  float memoryBudgetGb = 8.0f;     // refuse bakes estimated above this ...
  bool overBudget = false;         // ... unless this is set
};

// After the UVs: the density, what it gives and what it will cost.
struct UnwrapStep {
  float texelsPerUnit = 0.0f;
  size_t texels = 0;           // covered texels
  size_t atlases = 0;
  size_t atlasPixels = 0;
  float indirectTexelsPerUnit = 0.0f;  // the indirect grid's density; 0: one resolution
  std::string indirectChoice;          // how it was chosen, for people
  int indirectWidth = 0, indirectHeight = 0;  // its atlas
  double estimatedGb = 0.0;    // estimateBakeBytes
  std::vector<std::string> warnings;
};

// After the probes: how many, and the reflection probes their file (or the proposals) added to
// the scene.
struct ProbeStep {
  const ProbeSet* probes = nullptr;
  bool proposed = false;          // the reflection probes are proposals, not a file's
  size_t reflectionAdded = 0;     // reflection probes joining the scene's
  size_t reflectionAuthored = 0;  // left out: a node of the scene authors one of that name
};

// What the pipeline tells its caller as it goes (the CLI prints it); every method may be left
// out.
class PipelineEvents {
 public:
  virtual ~PipelineEvents() = default;
  virtual void unwrapped(const BakeJob& job, const UnwrapStep& step) {}
  virtual void probesReady(const BakeJob& job, const ProbeStep& step) {}
};

// A baked level, ready to write.
struct BakedLevel {
  baker::BakeResult result;
  ProbeSet probes;
  float probeDering = 0.0f;  // the light probes' SH file's window (BakeJob::probeDering)
  BakeReportInfo report;     // stages, settings and warnings around the bake
};

// Gives the level lightmap UVs at the job's density (given, fitted to one atlas, or auto:
// kAutoTexels rounded to two significant digits), into job.unwrap.pack; refuses a bake over
// the memory budget.
Result<UnwrapStep> unwrapForBake(scenes::Scene& scene, BakeJob& job,
                                 Progress& progress = nullProgress());

// An estimate of a bake's peak memory: decoded textures, texel and cluster records, their links
// (at most one per ray), per-source transfer, sky transfer, atlas images and the BVH. With an
// indirect grid (indirectTexelsPerUnit > 0) the gather, clusters and links are the grid's.
double estimateBakeBytes(const scenes::Scene& scene, size_t texels, size_t atlasPixels,
                         float texelsPerUnit, const baker::BakeOptions& options,
                         float indirectTexelsPerUnit = 0.0f);

// The light probes of job.probes: placed (as `probes place` does), read from a file, or none;
// fills job.bake.probes. A file's reflection probes, or with probes auto and none authored the
// proposals of `probes place --reflection`, join the scene's, except where a node of the scene
// authors one of the same name (the level's own wins over a proposal); with
// job.reflectionProbes none the scene keeps none.
Result<ProbeSet> prepareProbes(scenes::Scene& scene, BakeJob& job, ProbeStep* step,
                               Progress& progress = nullProgress());

// The report's "settings": the job's effective options.
nlohmann::json bakeSettings(const BakeJob& job, const UnwrapStep& unwrapped,
                            const ProbeSet& probes);

// Every step but writing: UVs, probes, bake. Stops at the first error (or cancellation).
Result<BakedLevel> bakeLevel(scenes::Scene& scene, BakeJob& job,
                             Progress& progress = nullProgress(),
                             PipelineEvents* events = nullptr);

// Writes the bake folder (layout.h) into `out` (not committed); returns the final paths.
Result<std::vector<std::string>> writeBakeFolder(const scenes::Scene& scene,
                                                 const BakedLevel& level,
                                                 const std::string& outDir, AtomicOutput& out);

}  // namespace afterglow::bakefiles
