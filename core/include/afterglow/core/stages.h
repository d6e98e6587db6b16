// The stages of a bake, in the order they run: the one list that the progress bar, report.json's
// "stages" and "stageRays", and the CLI's summary take their names from. The first three and the
// last are the pipeline's (bakefiles/pipeline.h), the rest the precompute's (baker/bake.h), each a
// function of its own stage header that can be run again on its own. In core because every
// library that reports progress on a bake (uv, probes, baker, bakefiles) names its steps by it.
#pragma once

#include <string>

namespace afterglow {

enum class Stage {
  Load,               // the scene read (scenes::loadGltf)
  Uv,                 // lightmap UVs (uv::unwrap)
  ProbePlacement,     // light probes placed or read (probes::placeProbes)
  RayTracer,          // the BVH (trace::RayTracer::build)
  Texels,             // texel samples (texels.h)
  Reference,          // --reference: every texel path-traced, instead of gather to solve
  Gather,             // the gather points' rays (gather.h)
  Clusters,           // clusters and far clusters (clusters.h)
  Direct,             // unit direct light per source (direct.h)
  Refine,             // more rays where bounced light is uncertain (gather.h)
  Links,              // form factors and smoothing (links.h)
  Probes,             // the light probes' transfer (probe_transfer.h)
  Solve,              // one solve with the authored lights (runtime::Solver)
  Dilate,             // lightmaps resolved and dilated into their padding
  ReflectionCapture,  // reflection probes' capture rays (reflection_capture.h)
  ReflectionPasses,   // their passes and GGX mips (runtime::solveReflectionProbes)
  Write,              // the bake folder written (bakefiles/write.h)
};
constexpr int kStageCount = int(Stage::Write) + 1;

// The stage's name in report.json and the progress bar ("gather", "reflection capture").
const char* stageName(Stage stage);
// A step of a stage for the progress bar: "gather: near geometry".
std::string stageStep(Stage stage, const char* step);

}  // namespace afterglow
