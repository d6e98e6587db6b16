// afterglow_bench accuracy --breakdown (bench_accuracy_breakdown.cpp).
#pragma once

#include "afterglow/baker/bake.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::bench {

// Prints the bake's indirect error against `ref` by class of texel, and the error of four
// one-bounce final gathers of the bake's solution, each with `rays` rays per texel.
void printIndirectBreakdown(const scenes::Scene& scene, const trace::RayTracer& tracer,
                            const baker::BakeResult& b, const baker::ReferenceTexels& ref,
                            int rays);

}  // namespace afterglow::bench
