// Light probes' SH L2 irradiance math (GLM only: engines shade with it).
//
// Basis. Real spherical harmonics, bands 0..2, over a unit direction d = (x, y, z) in the
// project's world axes (glTF: right-handed, +Y up, +Z toward the viewer), in the usual order
//   0 Y00 = 0.282095            1 Y1-1 = 0.488603 y     2 Y10 = 0.488603 z
//   3 Y11 = 0.488603 x          4 Y2-2 = 1.092548 xy    5 Y2-1 = 1.092548 yz
//   6 Y20 = 0.315392 (3z² − 1)  7 Y21 = 1.092548 xz     8 Y22 = 0.546274 (x² − y²)
// orthonormal over the sphere (∫ Y_i Y_j dω = δ_ij). shBasis below is the one definition: the
// baker's sky transfer (sampling::shBasis) is this function.
//
// What a probe stores: its *radiance* SH, L_i = ∫ L(ω) Y_i(ω) dω (RGB), the projection of the
// radiance arriving at the probe from every direction, exactly like TransportData::skySh (a
// constant radiance L projects to L·2√π on Y00: constantSkySh(L, sh.c)). Radiance SH add, scale
// and interpolate linearly (tetrahedral weights), and the convolution to irradiance is applied
// at lookup: irradianceOverPi gives E(n)/π, the lightmaps' unit (the outgoing radiance of a
// white Lambertian surface with normal n: shade with albedo × value).
#pragma once

#include <array>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

// The basis above at direction d (unit). Inline and bit-for-bit the baker's former
// sampling::shBasis (same float constants, same arithmetic order), so bakes do not change.
inline void shBasis(glm::vec3 d, float out[kShCount]) {
  out[0] = 0.282094791773878f;
  out[1] = 0.488602511902920f * d.y;
  out[2] = 0.488602511902920f * d.z;
  out[3] = 0.488602511902920f * d.x;
  out[4] = 1.092548430592079f * d.x * d.y;
  out[5] = 1.092548430592079f * d.y * d.z;
  out[6] = 0.315391565252520f * (3.0f * d.z * d.z - 1.0f);
  out[7] = 1.092548430592079f * d.x * d.z;
  out[8] = 0.546274215296040f * (d.x * d.x - d.y * d.y);
}

// A probe's radiance SH: c[i] is the RGB coefficient of basis function i (the layout of
// TransportData::skySh, so `std::copy(skySh, skySh + kShCount, sh.c)` converts).
struct ShL2 {
  glm::vec3 c[kShCount] = {};
};

// The clamped-cosine convolution per band over π: Â_l / π with Â = (π, 2π/3, π/4)
// (Ramamoorthi & Hanrahan 2001), per coefficient.
constexpr float kCosineOverPi[kShCount] = {1.0f,        2.0f / 3.0f, 2.0f / 3.0f,
                                           2.0f / 3.0f, 0.25f,       0.25f,
                                           0.25f,       0.25f,       0.25f};

// Monte Carlo projection: sh.c[i] += radiance · weight · Y_i(dir). For N directions uniform over
// the sphere the weight is 4π / N (in general 1 / (pdf · N)).
void projectRadiance(glm::vec3 dir, glm::vec3 radiance, float weight, ShL2& sh);

// The radiance the SH reconstructs in direction dir: Σ_i c[i] Y_i(dir).
glm::vec3 evalRadiance(const ShL2& radianceSh, glm::vec3 dir);

// E(n)/π = (1/π) Σ_l Â_l Σ_m L_lm Y_lm(n), n unit: a constant radiance L gives L for every n.
glm::vec3 irradianceOverPi(const ShL2& radianceSh, glm::vec3 normal);

// Deringing: bands 1 and 2 scaled by a Hanning window (Sloan, "Stupid Spherical Harmonics (SH)
// Tricks", 2008, §"Windowing"):
//   σ_l = (1 + cos(π l / w)) / 2  for l ≤ w,   σ_l = 0  for l > w,
// w = `window` (> 0; the band where the window reaches zero, larger is gentler). window ≤ 0
// returns the SH unchanged. The window trades sharpness for less ringing: for one directional
// light, w = 4..8 lifts the negative lobe of the reconstructed radiance and of E/π (the E/π
// minimum −19/480 ≈ −0.040·E0/π, at n·d = −8/15, rises to −0.019..−0.028·E0/π); w ≤ 3 damps
// band 2 so much that E/π opposite the light gets *more* negative (−3/64·E0/π at w = 3), so keep
// w ≥ 4 for irradiance. Apply it to the radiance SH before irradianceOverPi / the exports.
ShL2 deringed(const ShL2& radianceSh, float window);

// The SH at a located point (locateProbe): its probes' SH mixed with their weights.
ShL2 mixProbes(const ProbeLocation& where, const std::vector<ShL2>& probeSh);

// --- Unity ---------------------------------------------------------------------------------
//
// What Unity documents (Manual, "Light Probes: Technical information"): L2 SH, 27 floats, the
// basis and notation of Sloan's "Stupid SH Tricks", coefficients ordered per colour channel
//   L00, L1-1 (y), L10 (z), L11 (x), L2-2 (xy), L2-1 (yz), L20 (zz), L21 (xz), L22 (xx − yy),
// i.e. our order; SphericalHarmonicsL2[rgb, i] indexes channel then coefficient (0..8).
// What Unity does not document, and we take from the shader and from reimplementations of
// SphericalHarmonicsL2.AddDirectionalLight (not from Unity's source): the stored values are
// *premultiplied* for shading: each is the radiance coefficient convolved with the clamped
// cosine, times its basis function's constant, over π,
//   U[c][i] = k_i · (Â_l / π) · L_i[c],   k = (0.282095, 0.488603 ×3, 1.092548 ×2, 0.315392,
//                                               1.092548, 0.546274),
// so that ShadeSH9(n) = Σ_i U[i] · p_i(n) with the bare polynomials p = (1, y, z, x, xy, yz,
// 3z² − 1, xz, x² − y²) is E(n)/π in Unity's units (a constant ambient colour C has U[0] = C,
// as SphericalHarmonicsL2.AddAmbientLight adds; ShadeSH9 × albedo is the diffuse colour).
// Confidence: the order is documented; the premultiplication is consistent across the shader
// packing and two independent reimplementations but is not in Unity's documentation.
//
// Axes. Unity is left-handed (+Y up, +Z forward); glTF right-handed (+Y up, +Z toward the
// viewer). A handedness change negates one axis. Khronos' UnityGLTF importer negates X
// ((x, y, z) → (−x, y, z), its SchemaExtensions.CoordinateSpaceConversionScale = (−1, 1, 1)),
// the default here; some pipelines negate Z instead ((x, y, −z), e.g. Unity's USD importer's
// default basis change). Use the one that imported the level's geometry. Negating an axis
// flips the sign of the coefficients odd in it: X → 3 (x), 4 (xy), 7 (xz); Z → 2 (z), 5 (yz),
// 7 (xz).
enum class UnityAxes {
  NegateX,  // (x, y, z)_glTF = (−x, y, z)_Unity (UnityGLTF; the default)
  NegateZ,  // (x, y, z)_glTF = (x, y, −z)_Unity
  AsIs,     // the level is already in Unity's axes: no flip
};

// A direction in our (glTF) axes as Unity sees it (and back: the map is its own inverse).
glm::vec3 toUnityDirection(glm::vec3 dir, UnityAxes axes = UnityAxes::NegateX);

// SphericalHarmonicsL2's 27 floats, index [rgb · 9 + i] (sh[rgb, i] in C#).
using UnitySh = std::array<float, 3 * kShCount>;
UnitySh toUnitySH(const ShL2& radianceSh, UnityAxes axes = UnityAxes::NegateX);
ShL2 fromUnitySH(const UnitySh& unity, UnityAxes axes = UnityAxes::NegateX);

// Σ_i U[i] · p_i(n) per channel, n in Unity's axes (what SphericalHarmonicsL2.Evaluate and
// ShadeSH9 return under the convention above).
glm::vec3 evalUnitySH(const UnitySh& unity, glm::vec3 unityNormal);

// The 7 constants Unity's shaders read (unity_SHAr, SHAg, SHAb, SHBr, SHBg, SHBb, SHC), packed
// from the premultiplied SH the way Unity packs them (as in keijiro's LightProbeUtility):
//   SHA[c] = (U[c][3], U[c][1], U[c][2], U[c][0] − U[c][6])        (x, y, z, constant)
//   SHB[c] = (U[c][4], U[c][5], 3·U[c][6], U[c][7])                (xy, yz, zz, xz)
//   SHC    = (U[r][8], U[g][8], U[b][8], 1)                       (x² − y²)
// With them ShadeSH9(n) = E(n)/π (not E): evalShaderConstants(toShaderConstants(sh, a),
// toUnityDirection(n, a)) == irradianceOverPi(sh, n).
using ShaderConstants = std::array<glm::vec4, 7>;
ShaderConstants toShaderConstants(const ShL2& radianceSh, UnityAxes axes = UnityAxes::NegateX);

// What UnityCG.cginc's ShadeSH9 does with the constants (SHEvalLinearL0L1 + SHEvalLinearL2),
// n a unit normal in Unity's axes: per channel dot(SHA, (n, 1)) + dot(SHB, n.xyzz · n.yzzx)
// + SHC.rgb · (n.x² − n.y²).
glm::vec3 evalShaderConstants(const ShaderConstants& constants, glm::vec3 unityNormal);

}  // namespace afterglow::runtime
