#include "bench_common.h"

#include "afterglow/bakefiles/pipeline.h"

namespace afterglow::bench {

const char* mark(bool ok) { return ok ? "ok" : "MISSED"; }

Result<float> unwrapForBench(scenes::Scene& scene, float texelsPerUnit, int atlasSize) {
  bakefiles::BakeJob job;
  job.input = scene.sourcePath;
  job.texelsPerUnit = texelsPerUnit;
  job.atlasSize = atlasSize;
  Result<bakefiles::UnwrapStep> step = bakefiles::unwrapForBake(scene, job);
  if (!step) return step.status();
  return step->texelsPerUnit;
}

}  // namespace afterglow::bench
