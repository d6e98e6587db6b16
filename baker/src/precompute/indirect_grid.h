// Two resolutions: where a lightmap texel sits in the indirect grid (uv/indirect.h).
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "afterglow/baker/texels.h"

namespace afterglow::baker {

// The indirect atlas pixel coordinate of lightmap texel t's pixel centre: the affine map from
// its triangle's lightmap pixels to its indirect pixels (exact within a chart, which moves as a
// whole), so a centre just outside its triangle (conservative rasterisation) maps as well.
// False without indirect UVs.
bool indirectPoint(const scenes::Scene& scene, const TexelSet& lightmap, uint32_t t,
                   glm::dvec2& out);

// How far (indirect pixels) t's point may map through another triangle of its chart: the
// similarity maps of one chart agree up to rounding.
constexpr double kSameChart = 0.25;

// The indirect texel at pixel (x, y) of lightmap texel t's indirect atlas when it is a valid
// texel of t's chart (`point`: t's indirectPoint), else kNoTexel.
uint32_t gridTexel(const scenes::Scene& scene, const TexelSet& lightmap, uint32_t t,
                   glm::dvec2 point, const TexelSet& indirect, int x, int y);

}  // namespace afterglow::baker
