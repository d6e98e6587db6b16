// Emissive surfaces as area lights: every emissive material's world-space triangles, sampled by
// area for shadow rays, and their unoccluded transfer in closed form (Lambert's polygon
// formula) so direct light from an untextured emitter is exact wherever it is fully visible.
// Shared by the precompute (direct.cpp) and the reference path tracer.
#pragma once

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
};

// All emissive triangles of one material, over every instance.
struct Emitter {
  uint32_t material = 0;
  bool doubleSided = false;  // emits from both sides (Material::doubleSidedEmission)
  bool textured = false;     // emissiveTexture set: the closed form does not apply
  std::vector<EmitterTriangle> triangles;
  std::vector<float> cdf;    // cumulative area, last entry = totalArea
  float totalArea = 0.0f;    // m²
};

// Emitters sorted by material index; materials with no usable triangle are left out.
std::vector<Emitter> collectEmitters(const scenes::Scene& scene);

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
EmitterSample sampleEmitter(const Emitter& e, glm::vec2 u);

// Unoccluded E/π at point p with unit normal n from a uniform emitter of unit radiance covering
// the triangle: (1/2π) Σ_edges θ_i (n · γ_i) over the triangle clipped to the hemisphere above
// n (Lambert). Zero when p sees only the back of a single-sided triangle.
float triangleTransfer(const EmitterTriangle& tri, bool doubleSided, glm::vec3 p, glm::vec3 n);

}  // namespace afterglow::baker
