// The indirect grid (Unity's realtime lightmap UVs, Enlighten's output pixels at their own
// resolution): the lightmap's charts repacked at the indirect density, where bounced light is
// solved. A chart keeps its shape, scaled and turned as a whole, so a point's indirect UV is an
// affine image of its lightmap UV within its chart, and bilinear reads of the indirect atlas
// never mix two charts (they are padded apart). Bounced light then costs what the indirect
// density costs, whatever the lightmap's.
#pragma once

#include <cstddef>
#include <string>

#include "afterglow/core/status.h"
#include "afterglow/scenes/scene.h"
#include "afterglow/uv/pack.h"

namespace afterglow::uv {

struct IndirectLayout {
  float texelsPerUnit = 0.0f;  // the indirect density it was packed at
  int width = 0, height = 0;   // the indirect atlas (one)
  size_t charts = 0;
  size_t meshesDuplicated = 0; // static instances that shared a mesh get one of their own
};

// Gives every lightmapped static instance indirect UVs (Primitive::indirectUv) and its
// indirectLightmap: its uv1 charts (labelled as the metrics label them) scaled to
// texelsPerUnit × lightmapScale on average over the instance, and packed into one atlas with
// `pack`'s padding. Fails, naming the density, when they do not fit one atlas of
// pack.maxAtlasSize. Deterministic.
Result<IndirectLayout> packIndirect(scenes::Scene& scene, float texelsPerUnit,
                                    const PackOptions& pack = {});

// Forgets the indirect UVs: the bounced light is then solved at the lightmap's texels.
void clearIndirect(scenes::Scene& scene);

}  // namespace afterglow::uv
