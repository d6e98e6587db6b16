// A picture of the placed probes over the scene, so a person can check the placement at a glance:
// the scene shaded plainly (base colour under a headlight, no bake needed), each probe a dot
// coloured by its kind (grid white, refined cyan, moved orange, pinned magenta), drawn only
// where the camera sees it, smaller with distance; and the proposed reflection probes' boxes as
// yellow wireframes (dim where a surface hides them) with a yellow dot at each capture position.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "afterglow/trace/camera.h"
#include "afterglow/probes/placement.h"
#include "afterglow/probes/reflection_placement.h"

namespace afterglow::probes {

// Linear RGB, row 0 at the top (preview::writeRenderPng writes it). Deterministic.
// `levels` is the placement's refinement depth (the dots' size follows the finest spacing).
// Written with preview::writeRenderPng at exposure 0 stops, the dots show probeKindColour.
std::vector<glm::vec3> placementPicture(const scenes::Scene& scene,
                                        const trace::RayTracer& tracer, const Placement& placement,
                                        int levels, const trace::View& view, int width,
                                        int height,
                                        const std::vector<ReflectionProbeEntry>& reflections = {});

// The colour a kind is shown in, as the PNG's values.
glm::vec3 probeKindColour(ProbeKind kind);
// The colour of the reflection probes' boxes, as the PNG's values.
glm::vec3 reflectionBoxColour();

}  // namespace afterglow::probes
