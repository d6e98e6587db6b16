#include "afterglow/runtime/probe_sh.h"

#include <cmath>

#include "afterglow/core/math.h"

namespace afterglow::runtime {

namespace {

// The basis functions' constants k_i (shBasis without the polynomials).
constexpr float kBasisConstant[kShCount] = {
    0.282094791773878f, 0.488602511902920f, 0.488602511902920f,
    0.488602511902920f, 1.092548430592079f, 1.092548430592079f,
    0.315391565252520f, 1.092548430592079f, 0.546274215296040f};

constexpr int kBand[kShCount] = {0, 1, 1, 1, 2, 2, 2, 2, 2};

// +1 or −1 per coefficient: the sign the axis change puts on it (odd in the negated axis).
float axisSign(UnityAxes axes, int i) {
  switch (axes) {
    case UnityAxes::NegateX: return (i == 3 || i == 4 || i == 7) ? -1.0f : 1.0f;
    case UnityAxes::NegateZ: return (i == 2 || i == 5 || i == 7) ? -1.0f : 1.0f;
    case UnityAxes::AsIs: break;
  }
  return 1.0f;
}

}  // namespace

void projectRadiance(glm::vec3 dir, glm::vec3 radiance, float weight, ShL2& sh) {
  float y[kShCount];
  shBasis(dir, y);
  for (int i = 0; i < kShCount; ++i) sh.c[i] += radiance * (weight * y[i]);
}

glm::vec3 evalRadiance(const ShL2& radianceSh, glm::vec3 dir) {
  float y[kShCount];
  shBasis(dir, y);
  glm::vec3 sum(0.0f);
  for (int i = 0; i < kShCount; ++i) sum += radianceSh.c[i] * y[i];
  return sum;
}

glm::vec3 irradianceOverPi(const ShL2& radianceSh, glm::vec3 normal) {
  float y[kShCount];
  shBasis(normal, y);
  glm::vec3 sum(0.0f);
  for (int i = 0; i < kShCount; ++i) sum += radianceSh.c[i] * (kCosineOverPi[i] * y[i]);
  return sum;
}

ShL2 deringed(const ShL2& radianceSh, float window) {
  if (!(window > 0.0f)) return radianceSh;
  ShL2 out = radianceSh;
  for (int i = 1; i < kShCount; ++i) {
    const float l = float(kBand[i]);
    const float sigma = l > window ? 0.0f : 0.5f * (1.0f + std::cos(kPi * l / window));
    out.c[i] *= sigma;
  }
  return out;
}

glm::vec3 toUnityDirection(glm::vec3 dir, UnityAxes axes) {
  switch (axes) {
    case UnityAxes::NegateX: return {-dir.x, dir.y, dir.z};
    case UnityAxes::NegateZ: return {dir.x, dir.y, -dir.z};
    case UnityAxes::AsIs: break;
  }
  return dir;
}

UnitySh toUnitySH(const ShL2& radianceSh, UnityAxes axes) {
  UnitySh u{};
  for (int i = 0; i < kShCount; ++i) {
    const float scale = axisSign(axes, i) * kBasisConstant[i] * kCosineOverPi[i];
    for (int c = 0; c < 3; ++c) u[size_t(c * kShCount + i)] = radianceSh.c[i][c] * scale;
  }
  return u;
}

ShL2 fromUnitySH(const UnitySh& unity, UnityAxes axes) {
  ShL2 sh;
  for (int i = 0; i < kShCount; ++i) {
    const float scale = axisSign(axes, i) / (kBasisConstant[i] * kCosineOverPi[i]);
    for (int c = 0; c < 3; ++c) sh.c[i][c] = unity[size_t(c * kShCount + i)] * scale;
  }
  return sh;
}

glm::vec3 evalUnitySH(const UnitySh& unity, glm::vec3 n) {
  const float p[kShCount] = {1.0f,      n.y,       n.z,
                             n.x,       n.x * n.y, n.y * n.z,
                             3.0f * n.z * n.z - 1.0f, n.x * n.z, n.x * n.x - n.y * n.y};
  glm::vec3 sum(0.0f);
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < kShCount; ++i) sum[c] += unity[size_t(c * kShCount + i)] * p[i];
  return sum;
}

ShaderConstants toShaderConstants(const ShL2& radianceSh, UnityAxes axes) {
  const UnitySh u = toUnitySH(radianceSh, axes);
  auto U = [&u](int c, int i) { return u[size_t(c * kShCount + i)]; };
  ShaderConstants k;
  for (int c = 0; c < 3; ++c) {
    k[size_t(c)] = glm::vec4(U(c, 3), U(c, 1), U(c, 2), U(c, 0) - U(c, 6));
    k[size_t(3 + c)] = glm::vec4(U(c, 4), U(c, 5), 3.0f * U(c, 6), U(c, 7));
  }
  k[6] = glm::vec4(U(0, 8), U(1, 8), U(2, 8), 1.0f);
  return k;
}

glm::vec3 evalShaderConstants(const ShaderConstants& k, glm::vec3 n) {
  const glm::vec4 n1(n, 1.0f);
  const glm::vec4 vB(n.x * n.y, n.y * n.z, n.z * n.z, n.z * n.x);  // n.xyzz * n.yzzx
  const float vC = n.x * n.x - n.y * n.y;
  glm::vec3 out;
  for (int c = 0; c < 3; ++c)
    out[c] = glm::dot(k[size_t(c)], n1) + glm::dot(k[size_t(3 + c)], vB) + k[6][c] * vC;
  return out;
}

ShL2 mixProbes(const ProbeLocation& where, const std::vector<ShL2>& probeSh) {
  ShL2 out;
  for (int k = 0; k < 4; ++k) {
    if (where.probes[k] < 0 || where.weights[k] == 0.0f) continue;
    const ShL2& sh = probeSh[size_t(where.probes[k])];
    for (int i = 0; i < kShCount; ++i) out.c[i] += where.weights[k] * sh.c[i];
  }
  return out;
}

}  // namespace afterglow::runtime
