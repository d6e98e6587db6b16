// Texels buried in geometry: inside a wall, or wedged in a gap narrower than the texel, where
// no one value can hold. They take no light of their own; the lightmap fills them from their
// neighbours (post/lightmap_post.h).
#pragma once

#include <cstdint>

#include "afterglow/baker/options.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/progress.h"

namespace afterglow::baker {

// Whether an emitter that shines on texel t covers its whole footprint within one texel edge:
// a ray along the normal from each of the footprint's four corners hits, nearer than the edge,
// emissive geometry whose side facing the texel emits (the back of a double-sided lamp panel
// just below a ceiling). Such a cavity is lit, not buried.
bool litCavity(const trace::RayTracer& tracer, const TexelSet& texels, uint32_t t);

// The gather's burial rule on a texel's `rays` cosine rays (gather.cpp isBuried, and the
// lightmap's texels below): inside a wall when more than maxBackfaceFraction of them met
// single-sided back faces; wedged in a gap when at least maxEnclosedFraction met geometry
// nearer than the texel's edge (unless a litCavity).
inline bool insideAWall(int backfaces, int rays, const LinkOptions& options) {
  return float(backfaces) > options.maxBackfaceFraction * float(rays);
}
inline bool wedgedInAGap(int close, int rays, const LinkOptions& options) {
  return float(close) >= options.maxEnclosedFraction * float(rays);
}

// Two resolutions: the gather finds the indirect grid's buried texels with its own rays; the
// lightmap's texels cast none, so every valid one casts kBurialRays cosine rays here and is
// judged by the gather's rule (LinkOptions::maxBackfaceFraction, maxEnclosedFraction). Not only
// those near other geometry: a texel inside a wall whose grid texels' samples lie outside it
// (Sponza's at 16 texels/m: up to all of its rays on back faces, not near geometry, its grid
// corners valid) would read their light. Marks them invalid in `lightmap`; returns how many.
constexpr int kBurialRays = 16;
size_t buryLightmapTexels(const trace::RayTracer& tracer, TexelSet& lightmap,
                          const LinkOptions& options, Progress& progress = nullProgress());

}  // namespace afterglow::baker
