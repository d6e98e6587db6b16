// Emissive surfaces as area lights: every emissive material's world-space triangles, sampled by
// area for shadow rays, and their unoccluded transfer in closed form (Lambert's polygon
// formula) so direct light from an untextured emitter is exact wherever it is fully visible.
// Shared by the precompute (direct.cpp) and the reference path tracer.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

// One world-space triangle of an emissive material.
struct EmitterTriangle {
  glm::vec3 p0, e1, e2;     // p0 + u·e1 + v·e2
  glm::vec3 normal;         // unit, front side (glTF winding, flipped for mirroring transforms)
  float area = 0.0f;        // m²
  glm::vec2 uv0, uv1, uv2;  // the emissive texture's UV set at the three corners
  uint32_t triangle = 0;    // its index in its primitive
};

// All emissive triangles of one material, over every instance.
struct Emitter {
  uint32_t material = 0;
  bool doubleSided = false;  // emits from both sides (Material::emitsFromBack)
  bool textured = false;     // emissiveTexture set: the closed form does not apply
  std::vector<EmitterTriangle> triangles;
  std::vector<float> cdf;    // cumulative area, last entry = totalArea
  float totalArea = 0.0f;    // m²
};

// Emitters sorted by material index; materials with no usable triangle are left out.
std::vector<Emitter> collectEmitters(const scenes::Scene& scene);
// Appends a primitive's world triangles of positive area, placed by its instance, to e (and
// its area and CDF), with `uvs` (the primitive's UV set, or empty) at their corners: how
// emitters, and the glass the sky shines through (glass_sky.h), gather their triangles.
void addTriangles(const scenes::Instance& inst, const scenes::Primitive& prim,
                  const std::vector<glm::vec2>& uvs, Emitter& e);

// The emissive texture's modulation at a UV as one scalar: a Source scales by the material's
// emission() colour, so a coloured texture can only enter as its mean ratio over the lit
// channels (an untextured material gives exactly 1).
float emissionModulation(const scenes::Scene& scene, const scenes::Material& m, glm::vec2 uv);

// A point on an emitter chosen by area from a uniform (or stratified) u in [0,1)²; the
// stratification of u survives the mapping (the CDF picks the triangle along u.x and the
// remainder of u.x places the point inside it).
struct EmitterSample {
  glm::vec3 point;
  glm::vec3 normal;   // the triangle's front normal
  glm::vec2 uv;       // emissive texture UV at the point
  float pdfArea = 0;  // 1 / totalArea
};
// A point of a triangle, uniform by area for a uniform u in [0,1)² (square to triangle, area
// preserving: b1 = 1 − √u.x, b2 = u.y·√u.x), with its UV; pdfArea left 0.
inline EmitterSample pointOnTriangle(const EmitterTriangle& tri, glm::vec2 u) {
  const float s = std::sqrt(u.x);
  const float b1 = 1.0f - s, b2 = u.y * s;
  EmitterSample out;
  out.point = tri.p0 + b1 * tri.e1 + b2 * tri.e2;
  out.normal = tri.normal;
  out.uv = (1.0f - b1 - b2) * tri.uv0 + b1 * tri.uv1 + b2 * tri.uv2;
  return out;
}
// Inline: direct light draws one for every shadow ray.
inline EmitterSample sampleEmitter(const Emitter& e, glm::vec2 u) {
  const float pick = std::min(u.x, 0.99999994f) * e.totalArea;
  size_t k = size_t(std::upper_bound(e.cdf.begin(), e.cdf.end(), pick) - e.cdf.begin());
  k = std::min(k, e.triangles.size() - 1);
  const EmitterTriangle& tri = e.triangles[k];
  const float lo = k > 0 ? e.cdf[k - 1] : 0.0f;
  // What is left of u.x inside the chosen triangle's slice, back in [0, 1).
  const float ux = std::clamp((pick - lo) / tri.area, 0.0f, 0.99999994f);
  EmitterSample out = pointOnTriangle(tri, {ux, u.y});
  out.pdfArea = 1.0f / e.totalArea;
  return out;
}

// Unoccluded E/π at point p with unit normal n from a uniform emitter of unit radiance covering
// the triangle: (1/2π) Σ_edges θ_i (n · γ_i) over the triangle clipped to the hemisphere above
// n (Lambert). Zero when p sees only the back of a single-sided triangle.
float triangleTransfer(const EmitterTriangle& tri, bool doubleSided, glm::vec3 p, glm::vec3 n);

}  // namespace afterglow::baker
