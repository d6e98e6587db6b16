#include "scene_charts.h"

#include <algorithm>
#include <cstring>
#include <numeric>

#include "afterglow/core/union_find.h"
#include "afterglow/uv/texel_raster.h"

namespace afterglow::uv::detail {
namespace {

bool usableUv(const scenes::Primitive& prim) {
  return !prim.uv1.empty() && prim.uv1.size() == prim.positions.size();
}

}  // namespace

SceneCharts labelCharts(const scenes::Scene& scene) {
  SceneCharts out;
  for (int ii = 0; ii < int(scene.instances.size()); ++ii) {
    const scenes::Instance& inst = scene.instances[ii];
    if (inst.lightmap.atlas < 0 || inst.mesh < 0 || inst.mesh >= int(scene.meshes.size()))
      continue;
    const scenes::Mesh& mesh = scene.meshes[inst.mesh];
    out.atlasCount = std::max(out.atlasCount, inst.lightmap.atlas + 1);
    InstanceCharts ic;
    ic.instance = ii;
    ic.firstChart = out.chartCount;
    std::vector<uint32_t> base(mesh.primitives.size() + 1, 0);
    for (size_t p = 0; p < mesh.primitives.size(); ++p)
      base[p + 1] = base[p] + uint32_t(mesh.primitives[p].positions.size());
    UnionFind uf(base.back());
    // Weld vertices with identical uv1 and position, across primitives too.
    struct Key {
      float v[5];
      uint32_t id;
    };
    std::vector<Key> keys;
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const scenes::Primitive& prim = mesh.primitives[p];
      if (!usableUv(prim)) continue;
      for (size_t v = 0; v < prim.positions.size(); ++v)
        keys.push_back({{prim.uv1[v].x, prim.uv1[v].y, prim.positions[v].x, prim.positions[v].y,
                         prim.positions[v].z},
                        base[p] + uint32_t(v)});
    }
    auto less = [](const Key& a, const Key& b) {
      const int c = std::memcmp(a.v, b.v, sizeof a.v);
      return c < 0 || (c == 0 && a.id < b.id);
    };
    std::sort(keys.begin(), keys.end(), less);
    for (size_t k = 1; k < keys.size(); ++k)
      if (std::memcmp(keys[k].v, keys[k - 1].v, sizeof keys[k].v) == 0)
        uf.unite(keys[k].id, keys[k - 1].id);
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const scenes::Primitive& prim = mesh.primitives[p];
      if (!usableUv(prim)) continue;
      const uint32_t nv = uint32_t(prim.positions.size());
      for (size_t t = 0; t + 2 < prim.indices.size(); t += 3) {
        const uint32_t a = prim.indices[t], b = prim.indices[t + 1], c = prim.indices[t + 2];
        if (a >= nv || b >= nv || c >= nv) continue;
        uf.unite(base[p] + a, base[p] + b);
        uf.unite(base[p] + a, base[p] + c);
      }
    }
    // Number charts in order of first use by a triangle.
    std::vector<int32_t> rootChart(base.back(), -1);
    ic.triangleChart.resize(mesh.primitives.size());
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const scenes::Primitive& prim = mesh.primitives[p];
      std::vector<int32_t>& tc = ic.triangleChart[p];
      tc.assign(prim.triangleCount(), -1);
      if (!usableUv(prim)) continue;
      const uint32_t nv = uint32_t(prim.positions.size());
      for (size_t t = 0; t < tc.size(); ++t) {
        const uint32_t a = prim.indices[3 * t];
        if (a >= nv || prim.indices[3 * t + 1] >= nv || prim.indices[3 * t + 2] >= nv) continue;
        int32_t& chart = rootChart[uf.find(base[p] + a)];
        if (chart < 0) {
          chart = ic.chartCount++;
          out.chartInstance.push_back(ii);
          out.chartLocal.push_back(chart);
        }
        tc[t] = chart;
      }
    }
    out.chartCount += ic.chartCount;
    out.instances.push_back(std::move(ic));
  }
  return out;
}

AtlasCoverage rasterizeAtlas(const scenes::Scene& scene, const SceneCharts& charts, int atlas) {
  AtlasCoverage cov;
  for (const InstanceCharts& ic : charts.instances) {
    const scenes::LightmapLocation& lm = scene.instances[ic.instance].lightmap;
    if (lm.atlas != atlas) continue;
    cov.width = std::max(cov.width, lm.width);
    cov.height = std::max(cov.height, lm.height);
  }
  if (cov.width <= 0 || cov.height <= 0) return cov;
  const size_t texels = size_t(cov.width) * size_t(cov.height);
  cov.owner.assign(texels, -1);
  cov.shared.assign(texels, 0);
  const glm::dvec2 size(cov.width, cov.height);
  for (const InstanceCharts& ic : charts.instances) {
    const scenes::Instance& inst = scene.instances[ic.instance];
    if (inst.lightmap.atlas != atlas) continue;
    const scenes::Mesh& mesh = scene.meshes[inst.mesh];
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const scenes::Primitive& prim = mesh.primitives[p];
      const std::vector<int32_t>& tc = ic.triangleChart[p];
      for (size_t t = 0; t < tc.size(); ++t) {
        if (tc[t] < 0) continue;
        const int32_t id = ic.firstChart + tc[t];
        const glm::dvec2 a = glm::dvec2(prim.uv1[prim.indices[3 * t]]) * size;
        const glm::dvec2 b = glm::dvec2(prim.uv1[prim.indices[3 * t + 1]]) * size;
        const glm::dvec2 c = glm::dvec2(prim.uv1[prim.indices[3 * t + 2]]) * size;
        rasterizeTriangle(a, b, c, kMetricsGrow, cov.width, cov.height, [&](int x, int y) {
          const size_t i = size_t(y) * size_t(cov.width) + size_t(x);
          if (cov.owner[i] < 0) {
            cov.owner[i] = id;
            ++cov.covered;
          } else if (cov.owner[i] != id && !cov.shared[i]) {
            cov.shared[i] = 1;
            ++cov.overlapping;
          }
        });
      }
    }
  }
  return cov;
}

}  // namespace afterglow::uv::detail
