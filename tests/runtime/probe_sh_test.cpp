// The light probes' SH L2 math: radiance SH → E/π, the deringing window, and the Unity exports
// (SphericalHarmonicsL2's 27 floats and the 7 shader constants).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "afterglow/core/math.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/solver.h"
#include "test_rng.h"

namespace afterglow::runtime {
namespace {



// A unit vector perpendicular to d.
glm::vec3 perpendicular(glm::vec3 d) {
  const glm::vec3 a = std::abs(d.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(d, a));
}

// One directional light of irradiance E0 (at normal incidence) from d, as radiance SH: a delta
// of radiance projects to L_i = E0 · Y_i(d).
ShL2 directionalLight(glm::vec3 d, glm::vec3 e0) {
  ShL2 sh;
  projectRadiance(d, e0, 1.0f, sh);
  return sh;
}

TEST(ProbeSh, ConstantSkyGivesItsRadianceForEveryNormal) {
  const glm::vec3 L(0.7f, 1.3f, 2.9f);
  ShL2 sh;
  constantSkySh(L, sh.c);
  test::Rng rng{42};
  for (int k = 0; k < 1000; ++k) {
    const glm::vec3 n = randomDirection(rng);
    const glm::vec3 e = irradianceOverPi(sh, n);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(e[c], L[c], 2e-6f * L[c]) << "normal " << k;
  }
}

// The SH L2 approximation of one directional light's E/π, worked out independently of the
// Â_l constants. E(n) = E0 · h(n·d) with h(t) = max(0, t); as a zonal function of n its
// Legendre series is h(t) = Σ_l (2l+1)/2 · h_l · P_l(t), h_l = ∫_{-1}^{1} h(t) P_l(t) dt, and SH
// L2 keeps l ≤ 2. (Exactly h_0 = 1/2, h_1 = 1/3, h_2 = 1/8, so the truncation is
// 1/4 + t/2 + (5/16) P_2(t), which is 1/4 + 1/2 + 5/16 = 1.0625 at t = 1. The SH side computes
// E0 Σ_l (Â_l/π)·(2l+1)/(4π)·P_l(t) by the addition theorem: the two agree iff Â_l = 2π h_l,
// i.e. Â = (π, 2π/3, π/4).)
double legendre(int l, double t) {
  return l == 0 ? 1.0 : l == 1 ? t : 0.5 * (3.0 * t * t - 1.0);
}
double clampedCosineL2(double t) {
  static const std::array<double, 3> h = [] {
    std::array<double, 3> r{};
    const int steps = 200000;  // midpoint rule over [-1, 1]
    for (int s = 0; s < steps; ++s) {
      const double x = -1.0 + (s + 0.5) * (2.0 / steps);
      for (int l = 0; l < 3; ++l) r[size_t(l)] += std::max(0.0, x) * legendre(l, x) * (2.0 / steps);
    }
    return r;
  }();
  double sum = 0;
  for (int l = 0; l < 3; ++l) sum += (2 * l + 1) / 2.0 * h[size_t(l)] * legendre(l, t);
  return sum;
}

TEST(ProbeSh, DirectionalLightMatchesTheClampedCosinesL2Series) {
  const glm::vec3 d = glm::normalize(glm::vec3(0.3f, 0.8f, -0.5f));
  const float e0 = 2.5f;
  const ShL2 sh = directionalLight(d, glm::vec3(e0));
  test::Rng rng{7};
  double maxError = 0;
  for (int k = 0; k < 4000; ++k) {
    const glm::vec3 n = randomDirection(rng);
    const double t = glm::dot(n, d);
    const double expected = e0 / kPiDouble * clampedCosineL2(t);
    const float got = irradianceOverPi(sh, n).x;
    ASSERT_NEAR(got, expected, 2e-6 * e0) << "n·d = " << t;
    maxError = std::max(maxError, std::abs(got - e0 / kPiDouble * std::max(0.0, t)));
  }
  // Facing the light: 1/4 + 1/2 + 5/16 = 17/16 of the exact E0/π.
  EXPECT_NEAR(irradianceOverPi(sh, d).x, e0 / kPiDouble * 1.0625, 2e-6 * e0);
  // The truncation's error against the exact clamped cosine, g(t) = 3/32 + t/2 + 15t²/32 −
  // max(0, t), peaks at grazing (t = 0): 3/32 · E0/π, about 9% of the peak.
  EXPECT_LE(maxError, 3.0 / 32.0 * e0 / kPiDouble + 1e-5);
  EXPECT_GE(maxError, 0.9 * 3.0 / 32.0 * e0 / kPiDouble);
  EXPECT_NEAR(irradianceOverPi(sh, perpendicular(d)).x, 3.0 / 32.0 * e0 / kPiDouble, 2e-6 * e0);
}

// L(ω) = a + b·(ω·y): E(n) = aπ + b ∫ (ω·y) max(0, ω·n) dω = aπ + b (n·y) · 2π/3 (only the
// component of y along n survives the symmetric integral, ∫_{ω·n>0} (ω·n)² dω = 2π/3), so
// E/π = a + (2/3) b n.y — exactly, the field being band 0 and 1 only.
TEST(ProbeSh, MonteCarloProjectionOfASkyGradientGivesItsIrradiance) {
  const glm::vec3 a(1.0f, 0.6f, 0.3f), b(0.5f, -0.4f, 0.9f);
  const int count = 200000;
  ShL2 sh;
  test::Rng rng{2024};
  for (int k = 0; k < count; ++k) {
    const glm::vec3 w = randomDirection(rng);
    projectRadiance(w, a + b * w.y, 4.0f * kPi / float(count), sh);
  }
  for (int k = 0; k < 500; ++k) {
    const glm::vec3 n = randomDirection(rng);
    const glm::vec3 expected = a + (2.0f / 3.0f) * b * n.y;
    const glm::vec3 got = irradianceOverPi(sh, n);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(got[c], expected[c], 0.015f * (a[c] + std::abs(b[c]))) << "normal " << k;
  }
}

ShL2 randomSh(test::Rng& rng) {
  ShL2 sh;
  for (glm::vec3& c : sh.c) c = glm::vec3(rng.unit(), rng.unit(), rng.unit()) * 2.0f - 1.0f;
  return sh;
}

TEST(ProbeSh, ShaderConstantsEvaluateToIrradianceOverPi) {
  test::Rng rng{99};
  for (UnityAxes axes : {UnityAxes::NegateX, UnityAxes::NegateZ, UnityAxes::AsIs}) {
    for (int k = 0; k < 200; ++k) {
      const ShL2 sh = randomSh(rng);
      const ShaderConstants constants = toShaderConstants(sh, axes);
      EXPECT_EQ(constants[6].w, 1.0f);
      const UnitySh unity = toUnitySH(sh, axes);
      for (int j = 0; j < 10; ++j) {
        const glm::vec3 n = randomDirection(rng);
        const glm::vec3 un = toUnityDirection(n, axes);
        const glm::vec3 expected = irradianceOverPi(sh, n);
        const glm::vec3 shader = evalShaderConstants(constants, un);
        const glm::vec3 evaluate = evalUnitySH(unity, un);
        for (int c = 0; c < 3; ++c) {
          // Relative to the size of the terms (the sum itself may cancel to near 0).
          const float scale = 1.0f + std::abs(expected[c]);
          EXPECT_NEAR(shader[c], expected[c], 1e-5f * scale);
          EXPECT_NEAR(evaluate[c], expected[c], 1e-5f * scale);
        }
      }
    }
  }
}

TEST(ProbeSh, ToUnityDirectionFlipsOneAxis) {
  const glm::vec3 d(0.2f, 0.3f, 0.9f);
  EXPECT_EQ(toUnityDirection(d), glm::vec3(-0.2f, 0.3f, 0.9f));  // UnityGLTF's default
  EXPECT_EQ(toUnityDirection(d, UnityAxes::NegateZ), glm::vec3(0.2f, 0.3f, -0.9f));
  EXPECT_EQ(toUnityDirection(d, UnityAxes::AsIs), d);
}

// Known cases, analytically: a constant L has U[0] = L (SphericalHarmonicsL2.AddAmbientLight);
// the gradient L = a + b·y has L00 = 2√π a, L1-1 = b · k1 · 4π/3 (∫ y² dω = 4π/3), so
// U[1] = k1 · (2/3) · L1-1 = b · k1² · 8π/9 = (2/3) b (k1² = 3/(4π)): ShadeSH9 = a + (2/3) b n.y,
// whichever horizontal axis is negated. A gradient along x lands in U[3], negated by NegateX.
TEST(ProbeSh, UnityCoefficientsOfKnownSkies) {
  const float k1 = 0.488602511902920f;
  const glm::vec3 a(1.0f, 2.0f, 3.0f), b(0.3f, -0.6f, 0.9f);
  ShL2 y;
  constantSkySh(a, y.c);
  y.c[1] = b * (k1 * 4.0f * kPi / 3.0f);
  ShL2 x;
  x.c[3] = b * (k1 * 4.0f * kPi / 3.0f);
  for (UnityAxes axes : {UnityAxes::NegateX, UnityAxes::NegateZ, UnityAxes::AsIs}) {
    const UnitySh u = toUnitySH(y, axes);
    const UnitySh ux = toUnitySH(x, axes);
    const float xSign = axes == UnityAxes::NegateX ? -1.0f : 1.0f;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(u[size_t(c * 9 + 0)], a[c], 1e-6f * a[c]);
      EXPECT_NEAR(u[size_t(c * 9 + 1)], 2.0f / 3.0f * b[c], 1e-6f);
      for (int i = 2; i < 9; ++i) EXPECT_EQ(u[size_t(c * 9 + i)], 0.0f) << i;
      EXPECT_NEAR(ux[size_t(c * 9 + 3)], xSign * 2.0f / 3.0f * b[c], 1e-6f);
    }
  }
}

TEST(ProbeSh, UnityRoundTrip) {
  test::Rng rng{5};
  for (UnityAxes axes : {UnityAxes::NegateX, UnityAxes::NegateZ, UnityAxes::AsIs}) {
    const ShL2 sh = randomSh(rng);
    const ShL2 back = fromUnitySH(toUnitySH(sh, axes), axes);
    for (int i = 0; i < kShCount; ++i)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(back.c[i][c], sh.c[i][c], 1e-6f) << i;
  }
}

// Min over the sphere of a single light's E/π and radiance reconstruction (both zonal about d:
// sampled over n·d = t in [-1, 1]).
struct Minima {
  float irradiance = 1e30f, radiance = 1e30f;
};
Minima minima(const ShL2& sh, glm::vec3 d) {
  const glm::vec3 p = perpendicular(d);
  Minima m;
  for (int s = 0; s <= 4000; ++s) {
    const float t = -1.0f + float(s) / 2000.0f;
    const glm::vec3 n = t * d + std::sqrt(std::max(0.0f, 1.0f - t * t)) * p;
    m.irradiance = std::min(m.irradiance, irradianceOverPi(sh, n).x);
    m.radiance = std::min(m.radiance, evalRadiance(sh, n).x);
  }
  return m;
}

TEST(ProbeSh, DeringingWindowZeroIsTheIdentity) {
  test::Rng rng{11};
  const ShL2 sh = randomSh(rng);
  for (float w : {0.0f, -1.0f}) {
    const ShL2 out = deringed(sh, w);
    for (int i = 0; i < kShCount; ++i) EXPECT_EQ(out.c[i], sh.c[i]);
  }
  // Any window leaves band 0 (a constant sky) alone.
  EXPECT_EQ(deringed(sh, 4.0f).c[0], sh.c[0]);
}

TEST(ProbeSh, DeringingLiftsADirectionalLightsNegativeLobe) {
  const glm::vec3 d = glm::normalize(glm::vec3(-0.4f, 0.7f, 0.2f));
  const float e0 = 1.0f;
  const ShL2 sh = directionalLight(d, glm::vec3(e0));
  const Minima plain = minima(sh, d);
  // Unwindowed: E/π's minimum is 3/32 − 2/15 = −19/480 (at n·d = −8/15); the radiance's is
  // (1 − 0.6 − 2.2)/(4π) = −1.8/(4π) (at n·d = −1/5).
  EXPECT_NEAR(plain.irradiance, -19.0f / 480.0f * e0 / kPi, 1e-5f);
  EXPECT_NEAR(plain.radiance, -1.8f / (4.0f * kPi) * e0, 1e-4f);
  for (float w : {4.0f, 5.0f, 6.0f, 8.0f}) {
    const Minima m = minima(deringed(sh, w), d);
    EXPECT_GT(m.irradiance, 0.75f * plain.irradiance) << "window " << w;
    EXPECT_LE(m.irradiance, 0.0f) << "window " << w;
    EXPECT_GT(m.radiance, 0.85f * plain.radiance) << "window " << w;
  }
  // The documented caveat: w = 3 over-damps band 2 and deepens E/π opposite the light to
  // 1/4 − 3/8 + 5/64 = −3/64 (while the radiance still improves).
  const ShL2 w3 = deringed(sh, 3.0f);
  EXPECT_NEAR(irradianceOverPi(w3, -d).x, -3.0f / 64.0f * e0 / kPi, 1e-6f);
  EXPECT_GT(minima(w3, d).radiance, plain.radiance);
}

}  // namespace
}  // namespace afterglow::runtime
