#include "afterglow/uv/indirect.h"

#include <cmath>
#include <map>

#include "scene_charts.h"

namespace afterglow::uv {

using scenes::Instance;
using scenes::Mesh;
using scenes::Primitive;
using scenes::Scene;

namespace {

// Each lightmapped instance needs a mesh of its own (its indirect UVs live on the primitives):
// instances sharing one get copies. Returns how many copies were made.
size_t ownMeshes(Scene& scene, const detail::SceneCharts& charts) {
  std::map<int, int> users;
  size_t copies = 0;
  for (const detail::InstanceCharts& ic : charts.instances) {
    Instance& inst = scene.instances[size_t(ic.instance)];
    if (users[inst.mesh]++ == 0) continue;
    const Mesh copy = scene.meshes[size_t(inst.mesh)];
    scene.meshes.push_back(copy);
    inst.mesh = int(scene.meshes.size()) - 1;
    ++copies;
  }
  return copies;
}

}  // namespace

void clearIndirect(Scene& scene) {
  for (Mesh& mesh : scene.meshes)
    for (Primitive& prim : mesh.primitives) prim.indirectUv.clear();
  for (Instance& inst : scene.instances) inst.indirectLightmap = {};
}

Result<IndirectLayout> packIndirect(Scene& scene, float texelsPerUnit, const PackOptions& pack) {
  if (!(texelsPerUnit > 0.0f) || !std::isfinite(texelsPerUnit))
    return Status::error(format("indirect density %g texels per unit: must be positive",
                                double(texelsPerUnit)));
  clearIndirect(scene);
  detail::SceneCharts charts = detail::labelCharts(scene);
  IndirectLayout out;
  out.texelsPerUnit = texelsPerUnit;
  out.meshesDuplicated = ownMeshes(scene, charts);

  // Per instance, the scale from lightmap texels to indirect texels: the density asked for over
  // the density its uv1 has on average (an authored layout's relative chart sizes stay).
  std::vector<PackChart> packs(size_t(charts.chartCount));
  std::vector<double> scaleOf(charts.instances.size(), 0.0);
  for (size_t k = 0; k < charts.instances.size(); ++k) {
    const detail::InstanceCharts& ic = charts.instances[k];
    const Instance& inst = scene.instances[size_t(ic.instance)];
    const Mesh& mesh = scene.meshes[size_t(inst.mesh)];
    const glm::dvec2 size(inst.lightmap.width, inst.lightmap.height);
    const glm::dmat3 linear(glm::mat3(inst.transform));
    double world = 0.0, texels = 0.0;
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const Primitive& prim = mesh.primitives[p];
      for (size_t t = 0; t < ic.triangleChart[p].size(); ++t) {
        if (ic.triangleChart[p][t] < 0) continue;
        const uint32_t* i = &prim.indices[3 * t];
        const glm::dvec3 e1 = linear * glm::dvec3(prim.positions[i[1]] - prim.positions[i[0]]);
        const glm::dvec3 e2 = linear * glm::dvec3(prim.positions[i[2]] - prim.positions[i[0]]);
        world += 0.5 * glm::length(glm::cross(e1, e2));
        const glm::dvec2 u1 = glm::dvec2(prim.uv1[i[1]] - prim.uv1[i[0]]) * size;
        const glm::dvec2 u2 = glm::dvec2(prim.uv1[i[2]] - prim.uv1[i[0]]) * size;
        texels += 0.5 * std::abs(u1.x * u2.y - u1.y * u2.x);
      }
    }
    const double density = double(texelsPerUnit) * double(inst.lightmapScale);
    scaleOf[k] = texels > 0.0 ? density * std::sqrt(world / texels) : 0.0;
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const Primitive& prim = mesh.primitives[p];
      for (size_t t = 0; t < ic.triangleChart[p].size(); ++t) {
        const int32_t c = ic.triangleChart[p][t];
        if (c < 0) continue;
        std::vector<glm::vec2>& tri = packs[size_t(ic.firstChart + c)].triangles;
        for (int j = 0; j < 3; ++j)
          tri.push_back(glm::vec2(glm::dvec2(prim.uv1[prim.indices[3 * t + size_t(j)]]) * size *
                                  scaleOf[k]));
      }
    }
  }
  out.charts = packs.size();
  if (packs.empty()) return out;

  const PackResult packed = packCharts(packs, pack);
  for (size_t c = 0; c < packed.placements.size(); ++c)
    if (packed.placements[c].atlas != 0) {
      const int instance = charts.chartInstance[c];
      return Status::error(format(
          "the indirect grid at %g texels per unit needs more than one %d texel atlas (instance "
          "'%s' does not fit); lower --indirect-texels-per-unit",
          double(texelsPerUnit), pack.maxAtlasSize,
          scene.instances[size_t(instance)].name.c_str()));
    }
  out.width = packed.atlasSizes[0].x;
  out.height = packed.atlasSizes[0].y;
  const glm::vec2 atlasSize(packed.atlasSizes[0]);

  // A vertex belongs to one chart (charts are unions of the triangles that share vertices).
  for (size_t k = 0; k < charts.instances.size(); ++k) {
    const detail::InstanceCharts& ic = charts.instances[k];
    Instance& inst = scene.instances[size_t(ic.instance)];
    Mesh& mesh = scene.meshes[size_t(inst.mesh)];
    const glm::dvec2 size(inst.lightmap.width, inst.lightmap.height);
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      Primitive& prim = mesh.primitives[p];
      if (ic.triangleChart[p].empty()) continue;
      prim.indirectUv.assign(prim.positions.size(), glm::vec2(0.0f));
      for (size_t t = 0; t < ic.triangleChart[p].size(); ++t) {
        const int32_t c = ic.triangleChart[p][t];
        if (c < 0) continue;
        const ChartPlacement& pl = packed.placements[size_t(ic.firstChart + c)];
        for (int j = 0; j < 3; ++j) {
          const uint32_t v = prim.indices[3 * t + size_t(j)];
          const glm::vec2 point(glm::dvec2(prim.uv1[v]) * size * scaleOf[k]);
          prim.indirectUv[v] = (pl.rotation * point + pl.offset) / atlasSize;
        }
      }
    }
    inst.indirectLightmap = {0, out.width, out.height};
  }
  return out;
}

}  // namespace afterglow::uv
