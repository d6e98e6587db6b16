// Stage texels: the lightmap texels of every static instance, each with a world position, normal
// and footprint, placed on the surface and moved out of nearby geometry.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/options.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::trace {
class RayTracer;
}  // namespace afterglow::trace

namespace afterglow::baker {

using UvSet = scenes::LightmapUvSet;

// Texels as structure-of-arrays; index t is the runtime's texel index.
struct TexelSet {
  std::vector<runtime::AtlasLayout> atlases;  // pixel -> texel index
  std::vector<glm::vec3> position;   // world sample point (already pushed off the surface)
  std::vector<glm::vec3> normal;     // world shading normal (unit)
  std::vector<glm::vec3> geometricNormal;  // world face normal (unit), front side
  std::vector<float> area;           // world area the texel covers, m²
  std::vector<uint32_t> instance;    // index into Scene::instances
  std::vector<uint32_t> primitive;   // index into the instance's Mesh::primitives
  std::vector<uint32_t> triangle;    // triangle the sample lies on
  std::vector<glm::vec2> uv0;        // material UV at the sample (for albedo/emission lookups)
  std::vector<uint16_t> atlas;       // atlas index
  std::vector<glm::u16vec2> pixel;   // texel coordinate in its atlas
  std::vector<float> offset;         // metres: how far position sits off the surface
  std::vector<float> edge;           // metres: world length of a texel edge on its triangle
  std::vector<uint8_t> nearGeometry; // 1 when other geometry comes within 0.75 texels of the
                                     //   sample along the surface (a wall or object may cut
                                     //   through the texel's footprint)
  UvSet uvSet = UvSet::Lightmap;     // the UVs and atlases the texels were rasterised from
  std::vector<uint8_t> valid;        // 0 when the texel is buried in geometry (no light); set
                                     //   by gatherTexels, all 1 after computeTexels

  uint32_t size() const { return uint32_t(position.size()); }
  // The sample point on the other side of the surface (for the back of double-sided
  // geometry): as far behind the surface as position is in front of it.
  glm::vec3 backPosition(uint32_t t) const {
    return position[t] - geometricNormal[t] * (2.0f * offset[t]);
  }
};

// Rasterises every static instance's TEXCOORD_1 conservatively into its atlas and places one
// sample per covered texel. Deterministic whatever the thread count.
Result<TexelSet> computeTexels(const scenes::Scene& scene, const trace::RayTracer& tracer,
                               const TexelOptions& options = {},
                               Progress& progress = nullProgress(),
                               UvSet uvs = UvSet::Lightmap);

// The glTF material index of a texel's primitive (-1: the default material) and whether that
// material is double-sided.
// Up to 16 world points spread over texel t's footprint: a 4 × 4 grid over its atlas pixel
// mapped through its triangle (TEXCOORD_1 in pixels to world), those that fall inside the
// triangle, lifted off it like the sample. Returns how many (0 without lightmap UVs).
// Each point sits at its grid cell's centre, or with `jitter` at jitter[i], 16 points in the
// pixel's [0, 1)², row by row, point i in cell i (sampling::multiJittered16): a jittered grid is
// an unbiased estimate of a footprint mean, where cell centres are off by up to an eighth of a
// texel at every edge that lines up with the grid.
int footprintPoints(const scenes::Scene& scene, const TexelSet& texels, uint32_t t,
                    glm::vec3 out[16], const glm::vec2* jitter = nullptr);
int texelMaterial(const scenes::Scene& scene, const TexelSet& texels, uint32_t t);
bool texelDoubleSided(const scenes::Scene& scene, const TexelSet& texels, uint32_t t);

// The texel a surface point (given by its instance, primitive, triangle and barycentrics) maps
// to through TEXCOORD_1, or runtime::kNoTexel for dynamic instances and unbaked pixels.
uint32_t texelAt(const scenes::Scene& scene, const TexelSet& texels, uint32_t instance,
                 uint32_t primitive, uint32_t triangle, glm::vec2 barycentric);
// The same from the point's TEXCOORD_1 (RayTracer::uv(hit, 1) is cheaper than re-reading the
// mesh, which matters for tens of millions of gather hits).
uint32_t texelAtUv(const scenes::Scene& scene, const TexelSet& texels, uint32_t instance,
                   glm::vec2 uv1);

// Two resolutions (runtime/lightmap_layers.h): per lightmap texel, the 2×2 indirect texels
// around its point in the indirect atlas that its bounced light is read from, masked to those
// of its chart, not buried, and in sight of its sample. Invalid texels read none.
std::vector<runtime::IndirectCorners> indirectCorners(const scenes::Scene& scene,
                                                      const trace::RayTracer& tracer,
                                                      const TexelSet& lightmap,
                                                      const TexelSet& indirect,
                                                      Progress& progress = nullProgress());

}  // namespace afterglow::baker
