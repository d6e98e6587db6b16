#include "bench_common.h"

#include "afterglow/bakefiles/pipeline.h"

namespace afterglow::bench {

const char* mark(bool ok) { return ok ? "ok" : "MISSED"; }

baker::Quality qualityNamed(const std::string& name) {
  return name == "draft" ? baker::Quality::Draft
         : name == "high" ? baker::Quality::High
                          : baker::Quality::Default;
}

void printErrors(const baker::ReferenceComparison& c) {
  auto line = [](const char* name, const baker::ErrorStats& e) {
    std::printf("%-12s relative RMSE %.4f  bias %+.4f  (reference noise %.4f)\n", name,
                e.relativeRmse, e.bias, e.referenceNoise);
  };
  line("direct", c.direct);
  line("indirect", c.indirect);
  line("total", c.total);
}

Result<float> unwrapForBench(scenes::Scene& scene, float texelsPerUnit, int atlasSize,
                             float indirectTexelsPerUnit) {
  bakefiles::BakeJob job;
  job.input = scene.sourcePath;
  job.texelsPerUnit = texelsPerUnit;
  job.atlasSize = atlasSize;
  job.indirectTexelsPerUnit = indirectTexelsPerUnit;
  Result<bakefiles::UnwrapStep> step = bakefiles::unwrapForBake(scene, job);
  if (!step) return step.status();
  return step->texelsPerUnit;
}

}  // namespace afterglow::bench
