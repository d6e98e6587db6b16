// Stage reflection capture: one ray per cubemap texel from each probe's capture
// position, and what it hit kept as a runtime::ReflectionHit (runtime/reflection_capture.h), so
// the bake and the runtime shade the cubemaps from the same records.
#pragma once

#include <vector>

#include "afterglow/baker/options.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::trace {
class RayTracer;
}  // namespace afterglow::trace

namespace afterglow::baker {

// The influence box of a probe authored without a size: fitted to the walls around its capture
// position by ray distances. Along each of the node's six axis directions it takes the 80th
// percentile (walls stand behind furniture) of the distances, measured along that axis, of the
// capture rays within 30° of it that hit something;
// a direction whose rays all miss reaches the scene's bounds instead. The projection box spans
// those six distances (so its centre may sit off the capture position); the influence box is it
// grown by blendDistance on every side, so the walls get the probe's full weight. The axes are
// the node's.
// `hits` and `directions` are the probe's capture, texel by texel.
runtime::ReflectionProbeBox fitReflectionProbeBox(const runtime::ReflectionProbeBox& nodeFrame,
                                                  const std::vector<runtime::ReflectionHit>& hits,
                                                  const std::vector<glm::vec3>& directions,
                                                  const scenes::Bounds& sceneBounds);

// Captures scene.reflectionProbes into transport.reflections (materials must be filled: a hit
// on glTF's default material appends it when absent). Deterministic; rays on the tracer's
// threads.
Status captureReflectionProbes(const scenes::Scene& scene, const trace::RayTracer& tracer,
                               const ReflectionOptions& options,
                               runtime::TransportData& transport, Progress& progress);

}  // namespace afterglow::baker
