// Which texel's light a gather ray's hit takes (TexelOfHit): the texel under the hit point
// unless a wall stands between the hit point and that texel's sample, or the two are lit
// unlike each other. GatherBatch::trace resolves a batch's hits with it.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/texels.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/trace/raytracer.h"
#include "precompute/light_visibility.h"
#include "precompute/sight_lines.h"
#include "precompute/texel_lookup.h"

namespace afterglow::baker {

// The texel whose light a ray hit receives: t, the texel under the hit point, unless a
// wall or object cuts through that texel's footprint and stands between the hit point and the
// texel's sample, as for a floor texel half under a box: a ray from inside the box that lands
// on the hidden half must not collect the light of the sample outside. Then the nearest texel
// of the same chart that the hit point does see stands in; with none, the ray is absorbed.
// Only texels near other geometry (TexelLookup::kNear) are checked. In two steps, so that a
// batch's sight lines are traced together: sightLine() gives the line from the hit point to
// its texel's sample, and when that line is blocked standInCandidates() are searched, a
// batch's searches together (SightSearch). The hit point is the ray's origin + t × direction:
// within micrometres of the surface, which the lift off it (texel t's offset, millimetres or
// more) dwarfs, and without the triangle's vertices to fetch.
struct TexelOfHit {
  // The hit point lifted off its surface by texel t's offset, on the side the ray arrived at:
  // where sight lines and the light check start.
  static glm::vec3 lightOrigin(const TexelSet& texels, uint32_t t, const trace::Hit& hit,
                               glm::vec3 hitPoint) {
    const glm::vec3 side = hit.frontFace ? hit.geometricNormal : -hit.geometricNormal;
    return hitPoint + side * texels.offset[t];
  }

  // The line from the hit point (lifted off the surface by texel t's offset) to the sample of
  // texel `target` on the side the ray arrived at; false when the two coincide (nothing can
  // stand between them).
  static bool sightLine(const TexelSet& texels, uint32_t t, const trace::Hit& hit, glm::vec3 hitPoint,
                        uint32_t target, trace::Ray& ray) {
    return segment(lightOrigin(texels, t, hit, hitPoint),
                   hit.frontFace ? texels.position[target] : texels.backPosition(target), ray);
  }

  // The stand-in search's candidates, visit(n, distance, kind): every valid neighbour of t in
  // its chart (kind 0), of which the nearest the hit point sees stands in (kNoTexel: none).
  template <class Visit>
  static void standInCandidates(const TexelSet& texels, uint32_t t, const trace::Hit& hit,
                                glm::vec3 hitPoint, Visit&& visit) {
    const glm::vec3 origin = lightOrigin(texels, t, hit, hitPoint);
    forChartNeighbours(texels, t, 1, [&](uint32_t n) {
      visit(n, glm::length(texels.position[n] - origin), 0);
    });
  }

  // A hit nearer its ray's origin than this many of its texel's edges is checked for light
  // (the light match below): there the hit point and its texel's sample may lie on either
  // side of a shadow the ray's own surface casts, and the hit covers a wide solid angle.
  // Farther hits each cover little, and their errors average out over the rays. (On
  // Sponza-sun 1, 2 and 4 edges give the same figures; on the contact test 4 does best, for
  // 10% more bake time.)
  static constexpr float kLightCheckEdges = 4.0f;

  // Texel t, or the texel whose light a hit should take instead: when the lights that reach
  // the hit point (lifted off its surface like t's sample) are not those that reach t's
  // sample, or are but t's footprint is lit unevenly (its cluster reflects the footprint's
  // mean, LightVisibility::kUneven), the nearest valid texel of t's chart within two texels
  // that is lit like the hit point, evenly if one is, and that the hit point sees. With none:
  // t when its sample is lit like the hit point; kNoTexel (absorbed) when a light reaches t's
  // sample but not the hit point, for a sunlit sample must not light a shadowed contact, whose
  // own light is the little that bounced into it; else t.
  // `want`: the lights that reach the hit point lifted off its surface. In two steps, so that
  // a batch's searches trace their sight lines together: whether a search is needed
  // (needsLightMatch), its candidates (lightMatchCandidates: kind 0 lit evenly, 1 unevenly),
  // and the choice once the nearest of each kind in sight is known (lightMatchChoice).
  static bool needsLightMatch(const TexelLookup& lookup, uint32_t t, uint32_t want) {
    return want != lookup.reached()[t];  // else lit alike, evenly: t
  }
  template <class Visit>
  static void lightMatchCandidates(const TexelSet& texels, const TexelLookup& lookup, uint32_t t,
                                   const trace::Hit& hit, glm::vec3 hitPoint, uint32_t want,
                                   Visit&& visit) {
    constexpr uint32_t kUneven = LightVisibility::kUneven;
    const glm::vec3 origin = lightOrigin(texels, t, hit, hitPoint);
    const std::vector<uint32_t>& reached = lookup.reached();
    forChartNeighbours(texels, t, 2, [&](uint32_t n) {
      if ((reached[n] & ~kUneven) != want) return;
      visit(n, glm::length(texels.position[n] - origin), (reached[n] & kUneven) ? 1 : 0);
    });
  }
  static uint32_t lightMatchChoice(const TexelLookup& lookup, uint32_t t, uint32_t want,
                                   uint32_t nearestEven, uint32_t nearestUneven) {
    const uint32_t own = lookup.reached()[t] & ~LightVisibility::kUneven;
    if (nearestEven != runtime::kNoTexel) return nearestEven;
    if (want == own) return t;
    if (nearestUneven != runtime::kNoTexel) return nearestUneven;
    return (own & ~want) ? runtime::kNoTexel : t;
  }

 private:
  // Calls visit(n) for every valid texel n of t's instance within `radius` atlas pixels of t
  // (t excluded), row by row.
  template <class Visit>
  static void forChartNeighbours(const TexelSet& texels, uint32_t t, int radius, Visit&& visit) {
    const runtime::AtlasLayout& layout = texels.atlases[texels.atlas[t]];
    const int x = texels.pixel[t].x, y = texels.pixel[t].y;
    for (int dy = -radius; dy <= radius; ++dy)
      for (int dx = -radius; dx <= radius; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= layout.width || ny >= layout.height)
          continue;
        const uint32_t n = layout.texelOfPixel[size_t(ny) * size_t(layout.width) + size_t(nx)];
        if (n != runtime::kNoTexel && texels.valid[n] && texels.instance[n] == texels.instance[t])
          visit(n);
      }
  }
};

}  // namespace afterglow::baker
