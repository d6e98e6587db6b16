#include "precompute/probe_directions.h"

#include <algorithm>
#include <cmath>

#include "afterglow/runtime/probe_sh.h"
#include "shading/sampling.h"

namespace afterglow::baker {

using runtime::kShCount;

glm::vec3 equalAreaOctahedral(glm::vec2 p) {
  const float u = std::clamp(p.x, -1.0f, 1.0f), v = std::clamp(p.y, -1.0f, 1.0f);
  const float up = std::abs(u), vp = std::abs(v);
  const float signedDistance = 1.0f - (up + vp);
  const float d = std::abs(signedDistance);
  const float r = 1.0f - d;
  const float phi = (r == 0.0f ? 1.0f : (vp - up) / r + 1.0f) * (kPi / 4.0f);
  const float z = std::copysign(1.0f - r * r, signedDistance);
  const float s = r * std::sqrt(std::max(0.0f, 2.0f - r * r));
  const float cosPhi = std::copysign(std::cos(phi), u), sinPhi = std::copysign(std::sin(phi), v);
  return glm::normalize(glm::vec3(cosPhi * s, sinPhi * s, z));
}

// The probes' rays point at the centres of the cells, the same directions for every probe: a
// quadrature that integrates smooth radiance far better than a random ray per cell (a probe in
// a furnace sees its emission within 0.3% for every normal, against 2% jittered), with every
// probe's errors alike, so interpolation between probes shows no noise. The grid is turned by
// a fixed, generic rotation so that no ray runs exactly along an axis or a diagonal, where a
// level's walls meet (a probe on a room's diagonal would send rays exactly into its corners).
glm::vec3 probeDirection(glm::vec2 square) {
  static const glm::mat3 turn = [] {
    const glm::vec3 a = glm::normalize(glm::vec3(0.5773f, 0.8264f, 0.2341f));
    const float angle = 0.4187f, c = std::cos(angle), s = std::sin(angle);
    const glm::mat3 k(0.0f, a.z, -a.y, -a.z, 0.0f, a.x, a.y, -a.x, 0.0f);  // cross(a, ·)
    return glm::mat3(1.0f) + s * k + (1.0f - c) * (k * k);
  }();
  return glm::normalize(turn * equalAreaOctahedral(square));
}

namespace {

// The region weights that recover SH L2 from the regions' means: Σ_b ∫_b Y_i · W_b alone
// projects a piecewise constant radiance, which blurs it (band 1 loses about a tenth, band 2
// a third with 16 regions: a probe beside a lit wall would see it dimmer and the dark side
// brighter). The least-squares L2 radiance whose region means are W instead is
// M⁻¹ Σ_b ∫_b Y · W_b, with M_ij = Σ_b ∫_b Y_i ∫_b Y_j / Ω_b: exact for radiance within L2,
// and folded into the weights, so the runtime does the same work.
std::vector<float> leastSquaresRegionSh(const std::vector<float>& integrals,
                                        const std::vector<double>& solidAngle) {
  const uint32_t bins = uint32_t(solidAngle.size());
  double m[kShCount][2 * kShCount] = {};
  for (int i = 0; i < kShCount; ++i) {
    for (int j = 0; j < kShCount; ++j)
      for (uint32_t b = 0; b < bins; ++b)
        m[i][j] += double(integrals[b * kShCount + size_t(i)]) *
                   double(integrals[b * kShCount + size_t(j)]) / solidAngle[b];
    m[i][kShCount + i] = 1.0;
  }
  // Gauss-Jordan with partial pivoting (M is symmetric positive definite for enough regions).
  for (int c = 0; c < kShCount; ++c) {
    int pivot = c;
    for (int r = c + 1; r < kShCount; ++r)
      if (std::abs(m[r][c]) > std::abs(m[pivot][c])) pivot = r;
    for (int k = 0; k < 2 * kShCount; ++k) std::swap(m[c][k], m[pivot][k]);
    const double d = m[c][c];
    if (std::abs(d) < 1e-12) return integrals;  // too few regions to resolve L2: keep the plain ones
    for (int k = 0; k < 2 * kShCount; ++k) m[c][k] /= d;
    for (int r = 0; r < kShCount; ++r) {
      if (r == c) continue;
      const double f = m[r][c];
      for (int k = 0; k < 2 * kShCount; ++k) m[r][k] -= f * m[c][k];
    }
  }
  std::vector<float> out(integrals.size());
  for (uint32_t b = 0; b < bins; ++b)
    for (int i = 0; i < kShCount; ++i) {
      double v = 0.0;
      for (int j = 0; j < kShCount; ++j) v += m[i][kShCount + j] * double(integrals[b * kShCount + size_t(j)]);
      out[b * kShCount + size_t(i)] = float(v);
    }
  return out;
}

}  // namespace

ProbeDirections::ProbeDirections(uint32_t side, uint32_t regionsSide)
    : rays(side * side), regions(regionsSide * regionsSide),
      omega(4.0f * kPi / float(side * side)) {
  // Cell (x, y) of the square lies in region (x · R / side, y · R / side): square blocks when R
  // divides side, else blocks whose sides differ by a cell. Rays go region by region.
  std::vector<uint32_t> order(rays), regionOfCell(rays);
  for (uint32_t y = 0; y < side; ++y)
    for (uint32_t x = 0; x < side; ++x)
      regionOfCell[y * side + x] = (y * regionsSide / side) * regionsSide + x * regionsSide / side;
  for (uint32_t c = 0; c < rays; ++c) order[c] = c;
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return regionOfCell[a] < regionOfCell[b]; });
  direction.resize(rays);
  region.resize(rays);
  raysOfRegion.assign(regions, 0);
  basis.resize(size_t(rays) * kShCount);
  products.resize(size_t(rays) * runtime::kProbeSkyCount);
  // ∫_b Y_i dω per region, by the midpoint rule on 16² points a cell (each cell's solid angle
  // is exact; the error is Y's variation inside a cell, far below a half float's precision).
  constexpr uint32_t kFine = 16;
  std::vector<float> integrals(size_t(regions) * kShCount, 0.0f);
  std::vector<double> solidAngle(regions, 0.0), sums(size_t(regions) * kShCount, 0.0);
  for (uint32_t k = 0; k < rays; ++k) {
    const uint32_t c = order[k], x = c % side, y = c / side;
    const glm::vec2 q(-1.0f + 2.0f * (float(x) + 0.5f) / float(side),
                      -1.0f + 2.0f * (float(y) + 0.5f) / float(side));
    direction[k] = probeDirection(q);
    region[k] = regionOfCell[c];
    ++raysOfRegion[region[k]];
    float* yk = &basis[size_t(k) * kShCount];
    runtime::shBasis(direction[k], yk);
    for (int i = 0; i < kShCount; ++i)
      for (int j = i; j < kShCount; ++j) {
        const int at = runtime::probeSkyIndex(i, j);
        products[size_t(k) * runtime::kProbeSkyCount + size_t(at)] = omega * yk[i] * yk[j];
        allProducts[at] += double(omega) * double(yk[i]) * double(yk[j]);
      }
    solidAngle[region[k]] += double(omega);
    for (uint32_t j = 0; j < kFine; ++j)
      for (uint32_t i = 0; i < kFine; ++i) {
        const glm::vec2 f(-1.0f + 2.0f * (float(x * kFine + i) + 0.5f) / float(side * kFine),
                          -1.0f + 2.0f * (float(y * kFine + j) + 0.5f) / float(side * kFine));
        float yf[kShCount];
        runtime::shBasis(probeDirection(f), yf);
        for (int n = 0; n < kShCount; ++n)
          sums[size_t(region[k]) * kShCount + size_t(n)] += double(yf[n]) * double(omega) / (kFine * kFine);
      }
  }
  for (size_t i = 0; i < integrals.size(); ++i) integrals[i] = float(sums[i]);
  regionSh = leastSquaresRegionSh(integrals, solidAngle);
}

}  // namespace afterglow::baker
