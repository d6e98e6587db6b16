#include "afterglow/probes/placement_job.h"

#include <memory>

#include <nlohmann/json.hpp>

#include "afterglow/core/parallel.h"
#include "afterglow/core/timer.h"
#include "afterglow/probes/placement_picture.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/trace/camera.h"
#include "afterglow/trace/raytracer.h"

using nlohmann::json;

namespace afterglow::probes {

namespace {

// An error of the job's, naming the level.
Status named(const PlacementJob& job, const Status& status) {
  return Status::error(job.input + ": " + status.message());
}

// The placement's tetrahedra, again after probes were added.
Status tetrahedralizeInto(const PlacementJob& job, PlacedProbes& out) {
  const auto start = Clock::now();
  Result<runtime::ProbeTetrahedra> mesh = tetrahedralize(out.placement.positions);
  if (!mesh) return named(job, mesh.status());
  out.mesh = std::move(mesh.value());
  out.tetrahedraSeconds += secondsSince(start);
  return Status::ok();
}

// Splits the edges across which the bake's light changes, then tetrahedralises again.
Status refineByLight(const scenes::Scene& scene, const trace::RayTracer& tracer,
                     const PlacementJob& job, const BakeLight& bakeLight, PlacedProbes& out) {
  const auto start = Clock::now();
  const std::vector<runtime::ShL2> sh = bakeLight(out.placement.positions);
  std::vector<AxisIrradiance> irradiance(sh.size());
  for (size_t i = 0; i < sh.size(); ++i)
    for (int k = 0; k < 6; ++k)
      irradiance[i][size_t(k)] = runtime::Runtime::evaluateIrradiance(sh[i], axisNormal(k));
  Result<BakeRefinement> refined = refineByBake(scene, tracer, job.placement, out.mesh, irradiance,
                                                job.refinement, out.placement);
  if (!refined) return named(job, refined.status());
  out.refinement = refined.value();
  out.bakeSeconds = job.bakeLoadSeconds + secondsSince(start);
  return out.refinement.added > 0 ? tetrahedralizeInto(job, out) : Status::ok();
}

Status proposeReflectionProbes(const scenes::Scene& scene, const trace::RayTracer& tracer,
                               const PlacementJob& job, Progress& progress, PlacedProbes& out) {
  const auto start = Clock::now();
  Result<ReflectionPlacement> proposed =
      placeReflectionProbes(scene, tracer, job.reflectionOptions, progress);
  if (progress.cancelled()) return Status::error("cancelled");
  if (!proposed) return named(job, proposed.status());
  out.reflections = std::move(proposed.value());
  out.reflectionSeconds = secondsSince(start);
  return Status::ok();
}

// The user's probes are the pinned ones, in their file's order: they take its names.
void namePinnedProbes(const PlacementJob& job, PlacedProbes& out) {
  const Placement& placement = out.placement;
  const std::vector<std::string>& userNames = job.placement.userNames;
  out.names.assign(placement.positions.size(), "");
  for (size_t i = 0, u = 0; i < placement.positions.size() && u < userNames.size(); ++i)
    if (placement.kinds[i] == ProbeKind::Pinned) out.names[i] = userNames[u++];
  for (ProbeKind k : placement.kinds) out.pinned += k == ProbeKind::Pinned;
}

// PROBES.json's "settings": the job's effective options.
json settingsJson(const PlacementJob& job, const PlacedProbes& out, bool refined) {
  json settings = {{"input", job.input},
                   {"spacing", out.placement.spacing},
                   {"levels", job.placement.levels},
                   {"margin", out.placement.margin},
                   {"maxProbes", job.placement.maxProbes},
                   {"add", job.userProbesFile},
                   {"threads", threadCount()}};
  // Only when scaled, as the options below: a placement of a level in metres reads as before.
  if (job.unitScale != 1.0f) settings["unitScale"] = job.unitScale;
  if (refined) {
    settings["bake"] = job.bake;
    settings["refineThreshold"] = job.refinement.threshold;
  }
  if (job.reflection) {
    settings["reflection"] = true;
    settings["maxReflectionProbes"] = job.reflectionOptions.maxProbes;
    settings["reflectionSpacing"] = out.reflections.spacing;
  }
  return settings;
}

// PROBES.json's "summary": the counts `probes place` prints, and the times.
json summaryJson(const PlacementJob& job, const PlacedProbes& out, bool refined) {
  const Placement& placement = out.placement;
  json summary = {{"candidates", placement.candidates},
                  {"placed", placement.positions.size()},
                  {"rejectedInsideGeometry", placement.rejected},
                  {"moved", placement.moved},
                  {"refined", placement.refined},
                  {"pinned", out.pinned},
                  {"refinedByBake", out.refinement.added},
                  {"tetrahedra", out.mesh.tetrahedra.size()},
                  {"placeSeconds", out.placeSeconds},
                  {"tetrahedraSeconds", out.tetrahedraSeconds},
                  {"warnings", placement.warnings}};
  const BakeRefinement& r = out.refinement;
  if (refined)
    summary["bakeRefinement"] = {{"edges", r.edges},
                                 {"shortEdges", r.shortEdges},
                                 {"overThreshold", r.overThreshold},
                                 {"rejected", r.rejected},
                                 {"overBudget", r.overBudget},
                                 {"floor", r.floor},
                                 {"seconds", out.bakeSeconds}};
  const ReflectionPlacement& p = out.reflections;
  if (job.reflection)
    summary["reflection"] = {{"proposed", p.probes.size()},
                             {"candidates", p.candidates},
                             {"insideGeometry", p.inside},
                             {"open", p.open},
                             {"thin", p.thin},
                             {"centreBlocked", p.centreBlocked},
                             {"overlapping", p.overlapping},
                             {"overBudget", p.overBudget},
                             {"seconds", out.reflectionSeconds},
                             {"warnings", p.warnings}};
  return summary;
}

}  // namespace

Result<PlacedProbes> runPlacementJob(const scenes::Scene& scene, const PlacementJob& job,
                                     const BakeLight* bakeLight, Progress& progress) {
  const auto start = Clock::now();
  Result<std::unique_ptr<trace::RayTracer>> built = trace::RayTracer::build(scene);
  if (!built) return named(job, built.status());
  const trace::RayTracer& tracer = *built.value();
  PlacedProbes out;
  Result<Placement> placed = placeProbes(scene, tracer, job.placement, progress);
  if (progress.cancelled()) return Status::error("cancelled");
  if (!placed) return named(job, placed.status());
  out.placement = std::move(placed.value());
  out.placeSeconds = job.loadSeconds + secondsSince(start);
  if (Status s = tetrahedralizeInto(job, out); !s) return s;
  if (bakeLight)
    if (Status s = refineByLight(scene, tracer, job, *bakeLight, out); !s) return s;
  if (job.reflection)
    if (Status s = proposeReflectionProbes(scene, tracer, job, progress, out); !s) return s;
  namePinnedProbes(job, out);

  const trace::View view = scene.cameras.empty() ? trace::defaultView(scene, 0.9f)
                                                 : trace::cameraView(scene.cameras.front());
  out.picture = placementPicture(scene, tracer, out.placement, job.placement.levels, view,
                                 job.width, job.height, out.reflections.probes);
  const bool refined = bakeLight != nullptr;
  out.probesJson =
      probesJson(out.placement, out.names, out.mesh, settingsJson(job, out, refined).dump(),
                 summaryJson(job, out, refined).dump(), "", out.reflections.probes);
  return out;
}

}  // namespace afterglow::probes
