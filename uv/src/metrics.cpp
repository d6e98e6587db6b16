// Lightmap-UV metrics from TEXCOORD_1 and the lightmap locations alone.
//
// Coverage is the conservative footprint (texel_raster.h, with a 1/500-texel tolerance so float
// round-off of stored UVs does not read as touching a neighbour). Stretch follows Sander et al.
// 2001 ("Texture mapping progressive meshes"): per triangle, L2 = sqrt((|Ss|² + |St|²) / 2)
// where Ss, St are the derivatives of the world position along the texel axes; each chart is
// first scaled so its texel area equals its world area, so 1 means isometric whatever the
// density. Triangles with zero UV area have no finite stretch and are left out of it.
#include "afterglow/uv/metrics.h"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "afterglow/core/parallel.h"
#include "scene_charts.h"

namespace afterglow::uv {
namespace {

struct ChartSums {
  double signedUvArea = 0.0;  // texels², signed
  double uvArea = 0.0;        // texels², absolute
  double worldArea = 0.0;     // m², all triangles
  double stretchWeight = 0.0; // m², triangles with non-zero UV area
  double stretchSum = 0.0;    // Σ L2² · world area, before the chart's area normalisation
};

// Texels of one chart with a texel of another chart within Chebyshev distance `padding`
// (or sharing the texel).
size_t countPaddingViolations(const detail::AtlasCoverage& cov, int padding) {
  const int W = cov.width, H = cov.height;
  std::vector<size_t> perRow(size_t(std::max(0, H)), 0);
  parallelFor(size_t(std::max(0, H)), [&](size_t yRow) {
    const int y = int(yRow);
    size_t count = 0;
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x;
      const int32_t own = cov.owner[i];
      if (own < 0) continue;
      bool bad = cov.shared[i] != 0;
      for (int yy = std::max(0, y - padding); yy <= std::min(H - 1, y + padding) && !bad; ++yy)
        for (int xx = std::max(0, x - padding); xx <= std::min(W - 1, x + padding); ++xx) {
          const size_t j = size_t(yy) * W + xx;
          if ((cov.owner[j] >= 0 && cov.owner[j] != own) || cov.shared[j]) {
            bad = true;
            break;
          }
        }
      count += bad;
    }
    perRow[yRow] = count;
  });
  size_t total = 0;
  for (size_t c : perRow) total += c;
  return total;
}

bool inUnitRange(glm::vec2 uv) {
  return uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f && uv.y <= 1.0f;  // false for NaN
}

}  // namespace

Metrics computeMetrics(const scenes::Scene& scene, int padding) {
  Metrics m;
  const detail::SceneCharts charts = detail::labelCharts(scene);
  m.chartCount = size_t(charts.chartCount);
  std::vector<ChartSums> sums(size_t(charts.chartCount));

  // Pass 1: per-chart sums; out-of-range and missing UVs.
  auto forEachTriangle = [&](auto&& visit) {
    for (const detail::InstanceCharts& ic : charts.instances) {
      const scenes::Instance& inst = scene.instances[ic.instance];
      const scenes::Mesh& mesh = scene.meshes[inst.mesh];
      const glm::dvec2 size(inst.lightmap.width, inst.lightmap.height);
      const glm::dmat4 xf(inst.transform);
      for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const scenes::Primitive& prim = mesh.primitives[p];
        for (size_t t = 0; t < ic.triangleChart[p].size(); ++t)
          visit(ic, inst, prim, t, ic.triangleChart[p][t], size, xf);
      }
    }
  };
  auto uvArea = [](const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
    const glm::dvec2 e1 = b - a, e2 = c - a;
    return 0.5 * (e1.x * e2.y - e1.y * e2.x);
  };
  forEachTriangle([&](const detail::InstanceCharts& ic, const scenes::Instance&,
                      const scenes::Primitive& prim, size_t t, int32_t chart,
                      const glm::dvec2& size, const glm::dmat4& xf) {
    ++m.triangleCount;
    if (chart < 0) {  // no usable TEXCOORD_1 at all
      ++m.outOfRangeTriangles;
      return;
    }
    const uint32_t i0 = prim.indices[3 * t], i1 = prim.indices[3 * t + 1],
                   i2 = prim.indices[3 * t + 2];
    if (!inUnitRange(prim.uv1[i0]) || !inUnitRange(prim.uv1[i1]) || !inUnitRange(prim.uv1[i2]))
      ++m.outOfRangeTriangles;
    const glm::dvec2 s1 = glm::dvec2(prim.uv1[i0]) * size, s2 = glm::dvec2(prim.uv1[i1]) * size,
                     s3 = glm::dvec2(prim.uv1[i2]) * size;
    const glm::dvec3 q1(xf * glm::dvec4(glm::dvec3(prim.positions[i0]), 1.0));
    const glm::dvec3 q2(xf * glm::dvec4(glm::dvec3(prim.positions[i1]), 1.0));
    const glm::dvec3 q3(xf * glm::dvec4(glm::dvec3(prim.positions[i2]), 1.0));
    ChartSums& cs = sums[size_t(ic.firstChart + chart)];
    const double a2 = uvArea(s1, s2, s3);
    const double a3 = 0.5 * glm::length(glm::cross(q2 - q1, q3 - q1));
    if (!std::isfinite(a2) || !std::isfinite(a3)) return;
    cs.signedUvArea += a2;
    cs.uvArea += std::abs(a2);
    cs.worldArea += a3;
    if (a2 != 0.0) {
      const glm::dvec3 ss = (q1 * (s2.y - s3.y) + q2 * (s3.y - s1.y) + q3 * (s1.y - s2.y)) / (2 * a2);
      const glm::dvec3 st = (q1 * (s3.x - s2.x) + q2 * (s1.x - s3.x) + q3 * (s2.x - s1.x)) / (2 * a2);
      const double l2sq = 0.5 * (glm::dot(ss, ss) + glm::dot(st, st));
      cs.stretchSum += l2sq * a3;
      cs.stretchWeight += a3;
    }
  });

  // Pass 2: triangles wound against their chart's area-weighted majority.
  forEachTriangle([&](const detail::InstanceCharts& ic, const scenes::Instance&,
                      const scenes::Primitive& prim, size_t t, int32_t chart,
                      const glm::dvec2& size, const glm::dmat4&) {
    if (chart < 0) return;
    const double total = sums[size_t(ic.firstChart + chart)].signedUvArea;
    const double a2 = uvArea(glm::dvec2(prim.uv1[prim.indices[3 * t]]) * size,
                             glm::dvec2(prim.uv1[prim.indices[3 * t + 1]]) * size,
                             glm::dvec2(prim.uv1[prim.indices[3 * t + 2]]) * size);
    if ((total > 0 && a2 < 0) || (total < 0 && a2 > 0)) ++m.flippedTriangles;
  });

  // Stretch and density per chart.
  double stretchNum = 0.0, stretchDen = 0.0;
  std::vector<double> densities;
  for (int c = 0; c < charts.chartCount; ++c) {
    const ChartSums& cs = sums[size_t(c)];
    if (cs.worldArea > 0.0 && cs.uvArea > 0.0 && cs.stretchWeight > 0.0) {
      const double chartL2sq = cs.stretchSum / cs.stretchWeight * (cs.uvArea / cs.worldArea);
      stretchNum += chartL2sq * cs.stretchWeight;
      stretchDen += cs.stretchWeight;
      m.stretchL2Max = std::max(m.stretchL2Max, std::sqrt(chartL2sq));
      const float scale = scene.instances[size_t(charts.chartInstance[size_t(c)])].lightmapScale;
      densities.push_back(std::sqrt(cs.uvArea / cs.worldArea) / (scale > 0.0f ? scale : 1.0f));
    }
  }
  m.stretchL2 = stretchDen > 0.0 ? std::sqrt(stretchNum / stretchDen) : 0.0;
  if (!densities.empty()) {
    double mean = 0.0, var = 0.0;
    m.densityMin = m.densityMax = densities[0];
    for (double d : densities) {
      mean += d;
      m.densityMin = std::min(m.densityMin, d);
      m.densityMax = std::max(m.densityMax, d);
    }
    mean /= double(densities.size());
    for (double d : densities) var += (d - mean) * (d - mean);
    var /= double(densities.size());
    m.densitySpread = mean > 0.0 ? std::sqrt(var) / mean : 0.0;
  }

  // Coverage, one atlas at a time to bound memory.
  size_t covered = 0, texels = 0;
  for (int a = 0; a < charts.atlasCount; ++a) {
    const detail::AtlasCoverage cov = detail::rasterizeAtlas(scene, charts, a);
    AtlasMetrics am;
    am.width = cov.width;
    am.height = cov.height;
    am.coveredTexels = cov.covered;
    const size_t area = size_t(std::max(0, cov.width)) * size_t(std::max(0, cov.height));
    am.utilization = area ? double(cov.covered) / double(area) : 0.0;
    m.overlappingTexels += cov.overlapping;
    m.paddingViolations += countPaddingViolations(cov, std::max(0, padding));
    covered += cov.covered;
    texels += area;
    m.atlases.push_back(am);
  }
  m.utilization = texels ? double(covered) / double(texels) : 0.0;
  return m;
}

std::string metricsToJson(const Metrics& m) {
  nlohmann::ordered_json j;
  j["chartCount"] = m.chartCount;
  j["triangleCount"] = m.triangleCount;
  j["utilization"] = m.utilization;
  j["overlappingTexels"] = m.overlappingTexels;
  j["paddingViolations"] = m.paddingViolations;
  j["outOfRangeTriangles"] = m.outOfRangeTriangles;
  j["flippedTriangles"] = m.flippedTriangles;
  j["stretchL2"] = m.stretchL2;
  j["stretchL2Max"] = m.stretchL2Max;
  j["densityMinTexelsPerMetre"] = m.densityMin;
  j["densityMaxTexelsPerMetre"] = m.densityMax;
  j["densitySpread"] = m.densitySpread;
  nlohmann::ordered_json atlases = nlohmann::ordered_json::array();
  for (size_t a = 0; a < m.atlases.size(); ++a) {
    const AtlasMetrics& am = m.atlases[a];
    atlases.push_back({{"index", a},
                       {"width", am.width},
                       {"height", am.height},
                       {"coveredTexels", am.coveredTexels},
                       {"utilization", am.utilization}});
  }
  j["atlases"] = atlases;
  return j.dump(2);
}

}  // namespace afterglow::uv
