#include "afterglow/bakefiles/pipeline.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>

#include "afterglow/core/parallel.h"
#include "afterglow/core/timer.h"
#include "afterglow/probes/placement.h"
#include "afterglow/probes/reflection_placement.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/uv/indirect.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::bakefiles {

namespace {

// Placed as `probes place` places them, with its reflection probe proposals when `reflection`.
Result<ProbeSet> placeBakeProbes(const scenes::Scene& scene, float spacing, size_t maxProbes,
                                 bool reflection, Progress& progress) {
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
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
  if (reflection) {
    Result<probes::ReflectionPlacement> proposed =
        probes::placeReflectionProbes(scene, *tracer.value(), {}, progress);
    if (!proposed) return Status::error(scene.sourcePath + ": " + proposed.message());
    out.file.reflectionProbes = std::move(proposed->probes);
    out.summary["reflectionProbes"] = out.file.reflectionProbes.size();
  }
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

// Whether the job bakes light probes at all (a reference bake has no transport for them).
bool bakesProbes(const BakeJob& job) { return !job.bake.reference && job.probes != "none"; }

}  // namespace

double estimateBakeBytes(const scenes::Scene& scene, size_t texels, size_t atlasPixels,
                         float texelsPerUnit, const baker::BakeOptions& o,
                         float indirectTexelsPerUnit) {
  // Sponza-sun at 4 texels/m: estimated 1.27 GB, measured peak 0.95 GB.
  size_t sources = scene.lights.size();
  for (const scenes::Material& m : scene.materials) sources += m.emissive() ? 1 : 0;
  double textureBytes = 0.0;
  for (const scenes::Texture& t : scene.textures)
    textureBytes += double(t.width) * double(t.height) * sizeof(glm::vec4);
  // The texels that gather, and their density: the grid's, or the lightmap's.
  const bool grid = indirectTexelsPerUnit > 0.0f && indirectTexelsPerUnit < texelsPerUnit;
  const double density = grid ? double(indirectTexelsPerUnit) : double(texelsPerUnit);
  const double ratio = density / double(texelsPerUnit);
  const double gathering = double(texels) * ratio * ratio;
  // Charts smaller than a cluster make clusters smaller than clusterSize: count half the ideal.
  double side = double(o.clusters.clusterSize) * density;
  if (o.clusters.clusterTexels > 0.0f) side = std::min(side, double(o.clusters.clusterTexels));
  const double clusters = gathering / std::max(1.0, side * side * 0.5) + 1.0;
  const double perTexel = 96.0 + 36.0 + 12.0 + 4.0 * double(sources) * 2.0;
  // A lightmap texel of a grid: its direct light as floats, then halves, and its corners.
  const double perLightmapTexel = grid ? 6.0 * double(sources) + 8.0 : 0.0;
  const double perGatherTexel = 8.0 * double(o.links.texelRays);
  const double perCluster = 96.0 + 36.0 + 8.0 * double(o.links.clusterRays);
  return textureBytes + double(texels) * (perTexel + perLightmapTexel) +
         gathering * (perGatherTexel + (grid ? perTexel : 0.0)) + clusters * perCluster +
         double(atlasPixels) * 40.0 + double(scene.instancedTriangleCount()) * 160.0 +
         64.0 * 1024 * 1024;
}

namespace {

// Two significant digits, so the report shows a number a person would pick.
float roundDensity(float texelsPerUnit) {
  const float magnitude = std::pow(10.0f, std::floor(std::log10(texelsPerUnit)) - 1.0f);
  return std::round(texelsPerUnit / magnitude) * magnitude;
}

// The indirect grid: given or auto; packed when coarser than the lightmap.
Status chooseIndirect(scenes::Scene& scene, const BakeJob& job, UnwrapStep& step) {
  float density = job.indirectTexelsPerUnit;
  if (density > 0.0f) {
    step.indirectChoice = "given";
  } else {
    density = roundDensity(uv::texelsPerUnitFor(scene, kAutoIndirectTexels));
    if (!(2.0f * density <= step.texelsPerUnit)) {
      step.indirectChoice = format("auto: the lightmap is not twice as dense as a grid of about "
                                   "%.0fk texels would be, bounced light at its texels",
                                   kAutoIndirectTexels / 1000.0);
      uv::clearIndirect(scene);
      return Status::ok();
    }
    step.indirectChoice = format("auto: about %.0fk texels", kAutoIndirectTexels / 1000.0);
  }
  if (!(density < step.texelsPerUnit)) {
    step.indirectChoice += ", not coarser than the lightmap: bounced light at its texels";
    uv::clearIndirect(scene);
    return Status::ok();
  }
  uv::PackOptions pack = job.unwrap.pack;
  pack.texelsPerUnit = density;
  Result<uv::IndirectLayout> packed = uv::packIndirect(scene, density, pack);
  if (!packed) return Status::error(job.input + ": " + packed.message());
  step.indirectTexelsPerUnit = density;
  step.indirectWidth = packed->width;
  step.indirectHeight = packed->height;
  return Status::ok();
}

}  // namespace

Result<UnwrapStep> unwrapForBake(scenes::Scene& scene, BakeJob& job, Progress& progress) {
  UnwrapStep step;
  float texelsPerUnit = job.texelsPerUnit;
  // Texel density: given, fitted to one atlas, or (by default) about kAutoTexels texels.
  if (job.atlasSize > 0) {
    Result<float> fitted = uv::fitTexelsPerUnit(scene, job.unwrap, job.atlasSize, progress);
    if (progress.cancelled()) return Status::error("cancelled");
    if (!fitted) return Status::error(job.input + ": " + fitted.message());
    texelsPerUnit = fitted.value();
    job.unwrap.pack.maxAtlasSize = job.atlasSize;
  } else if (!(texelsPerUnit > 0.0f)) {
    texelsPerUnit = uv::texelsPerUnitFor(scene, kAutoTexels);
    if (!(texelsPerUnit > 0.0f))
      return Status::error(job.input + ": nothing to bake: no static instance has triangles");
    texelsPerUnit = roundDensity(texelsPerUnit);
  }
  job.unwrap.pack.texelsPerUnit = texelsPerUnit;
  Result<uv::UnwrapResult> unwrapped = uv::unwrap(scene, job.unwrap, progress);
  if (progress.cancelled()) return Status::error("cancelled");
  // An instance larger than one atlas at the density asked for (Sponza's walls at 32 texels/m)
  // gets atlases of up to kLargeAtlas instead of a refusal, unless the atlas size was given.
  // Packing fails before it changes the scene, so the second try starts from the same one.
  if (!unwrapped && job.atlasSize == 0 && job.unwrap.mode == uv::UvMode::Generate &&
      job.unwrap.pack.maxAtlasSize < kLargeAtlas) {
    const std::string first = unwrapped.message();
    job.unwrap.pack.maxAtlasSize = kLargeAtlas;
    unwrapped = uv::unwrap(scene, job.unwrap, progress);
    if (progress.cancelled()) return Status::error("cancelled");
    if (unwrapped)
      unwrapped->warnings.push_back(format("%s; atlases of up to %d texels used instead",
                                           first.c_str(), kLargeAtlas));
  }
  if (!unwrapped) return unwrapped.status();
  step.texelsPerUnit = texelsPerUnit;
  step.warnings = unwrapped->warnings;
  for (const uv::AtlasMetrics& a : unwrapped->metrics.atlases) {
    step.texels += a.coveredTexels;
    step.atlasPixels += size_t(a.width) * size_t(a.height);
  }
  step.atlases = unwrapped->metrics.atlases.size();
  if (Status st = chooseIndirect(scene, job, step); !st) return st;
  step.estimatedGb = estimateBakeBytes(scene, step.texels, step.atlasPixels, texelsPerUnit,
                                       job.bake, step.indirectTexelsPerUnit) /
                     1e9;
  return step;
}

Result<ProbeSet> prepareProbes(scenes::Scene& scene, BakeJob& job, ProbeStep* step,
                               Progress& progress) {
  ProbeSet set;
  if (job.reflectionProbes == "none") scene.reflectionProbes.clear();
  if (!bakesProbes(job)) return set;
  step->proposed = job.probes == "auto" && job.reflectionProbes == "auto" &&
                   scene.reflectionProbes.empty();
  Result<ProbeSet> got = job.probes == "auto"
                             ? placeBakeProbes(scene, job.probeSpacing, job.maxProbes,
                                               step->proposed, progress)
                             : readBakeProbes(job.probes);
  if (progress.cancelled()) return Status::error("cancelled");
  if (!got) return got.status();
  set = std::move(got.value());
  if (job.reflectionProbes == "none") set.file.reflectionProbes.clear();
  job.bake.probes = set.file.mesh;
  for (const probes::ReflectionProbeEntry& r : set.file.reflectionProbes) {
    const bool authored =
        std::any_of(scene.reflectionProbes.begin(), scene.reflectionProbes.end(),
                    [&](const scenes::ReflectionProbe& p) { return p.name == r.name; });
    if (authored) {
      ++step->reflectionAuthored;
      continue;
    }
    scene.reflectionProbes.push_back(probes::toSceneReflectionProbe(r));
    ++step->reflectionAdded;
  }
  return set;
}

json bakeSettings(const BakeJob& job, const UnwrapStep& unwrapped, const ProbeSet& probes) {
  const baker::BakeOptions& o = job.bake;
  return {{"texelsPerUnit", job.unwrap.pack.texelsPerUnit},
          {"indirectTexelsPerUnit", unwrapped.indirectTexelsPerUnit},
          {"indirectChoice", unwrapped.indirectChoice},
          {"atlasSize", job.atlasSize},
          {"uv", job.unwrap.mode == uv::UvMode::Keep ? "keep" : "generate"},
          {"quality", job.quality},
          {"texelRays", o.links.texelRays},
          {"clusterRays", o.links.clusterRays},
          {"lightSamples", o.direct.lightSamples},
          {"emissiveSamples", o.direct.emissiveSamples},
          {"penumbraSamples", o.direct.penumbraSamples},
          {"filterPasses", o.links.filterPasses},
          {"bounces", o.solve.maxBounces},
          {"indirectIntensity", o.indirectIntensity},
          {"albedoBoost", o.albedoBoost},
          {"sky", {o.skyColor.r, o.skyColor.g, o.skyColor.b}},
          // Absolute, so `render --reference` finds it from anywhere.
          {"skyImage", o.skyImage.empty() ? std::string() : fs::absolute(o.skyImage).string()},
          {"clusterSize", o.clusters.clusterSize},
          {"clusterTexels", o.clusters.clusterTexels},
          {"dilation", o.dilation},
          {"singleSidedEmission", job.singleSidedEmission},
          {"unitScale", job.unitScale},
          {"threads", threadCount()},
          {"reference", o.reference},
          {"referenceSpp", o.referenceOptions.samples},
          {"memoryBudgetGb", job.memoryBudgetGb},
          {"estimatedMemoryGb", unwrapped.estimatedGb},
          {"probes", job.probes},
          {"reflectionProbes", job.reflectionProbes},
          {"probeSpacing", probes.spacing},
          {"probeDering", job.probeDering},
          {"probeRays", o.probeOptions.raysSide * o.probeOptions.raysSide},
          {"probeRegions", o.probeOptions.binsSide * o.probeOptions.binsSide},
          {"probeEmitterSamples", o.probeOptions.emitterSamples},
          {"reflectionBounces", o.reflections.bounces}};
}

Result<BakedLevel> bakeLevel(scenes::Scene& scene, BakeJob& job, Progress& progress,
                             PipelineEvents* events) {
  PipelineEvents none;
  if (!events) events = &none;
  BakedLevel level;
  BakeReportInfo& report = level.report;
  report.version = job.version;
  report.input = job.input;
  report.warnings = scene.warnings;

  Clock::time_point t0 = Clock::now();
  Result<UnwrapStep> unwrapped = unwrapForBake(scene, job, progress);
  report.extraStages.push_back({Stage::Uv, secondsSince(t0)});
  if (!unwrapped) return unwrapped.status();
  report.warnings.insert(report.warnings.end(), unwrapped->warnings.begin(),
                         unwrapped->warnings.end());
  events->unwrapped(job, unwrapped.value());
  if (unwrapped->estimatedGb > double(job.memoryBudgetGb) && !job.overBudget)
    return Status::error(format(
        "bake: the estimated memory (%.2f GB for %zu texels) is over the budget of %.2f GB; "
        "lower --texels-per-unit (is the scene in metres?), raise --memory-budget GB, or pass "
        "--yes to bake anyway. Nothing written.",
        unwrapped->estimatedGb, unwrapped->texels, double(job.memoryBudgetGb)));

  // Before the bake, so that a bad probes file or too many probes stops it before minutes of
  // precompute.
  t0 = Clock::now();
  ProbeStep step;
  Result<ProbeSet> probes = prepareProbes(scene, job, &step, progress);
  if (!probes) return probes.status();
  level.probes = std::move(probes.value());
  if (bakesProbes(job)) {
    if (step.reflectionAuthored > 0)
      report.warnings.push_back(format(
          "%s: %zu of its reflection probes left out: the scene's nodes author probes of those "
          "names",
          job.probes.c_str(), step.reflectionAuthored));
    report.extraStages.push_back({Stage::ProbePlacement, secondsSince(t0)});
    step.probes = &level.probes;
    events->probesReady(job, step);
  }

  Result<baker::BakeResult> baked = baker::bake(scene, job.bake, progress);
  if (!baked) return baked.status();
  level.result = std::move(baked.value());
  level.probeDering = job.probeDering;
  report.settings = bakeSettings(job, unwrapped.value(), level.probes);
  return level;
}

Result<std::vector<std::string>> writeBakeFolder(const scenes::Scene& scene,
                                                 const BakedLevel& level,
                                                 const std::string& outDir, AtomicOutput& out) {
  Result<std::vector<std::string>> written =
      writeBakeOutputs(scene, level.result, outDir, level.report, out);
  if (!written) return written;
  if (!level.result.probeSh.empty())
    if (Status st = writeLightProbes(outDir, level.probes, level.result.probeSh,
                                     runtime::probeLights(level.result.transport,
                                                          runtime::directScales(level.result.transport)),
                                     level.result.transport.probes.depth,
                                     level.probeDering, level.report.settings, out,
                                     written.value());
        !st)
      return st;
  if (!level.result.probeOcclusion.empty()) {
    nlohmann::json channels = nlohmann::json::object();
    for (size_t i = 0; i < level.result.shadowmaskChannel.size() && i < scene.lights.size(); ++i)
      if (level.result.shadowmaskChannel[i] >= 0)
        channels[scene.lights[i].name] = level.result.shadowmaskChannel[i];
    if (Status st = writeProbeOcclusion(outDir, level.result.probeOcclusion, channels, out,
                                        written.value());
        !st)
      return st;
  }
  return written;
}

}  // namespace afterglow::bakefiles
