// What the texels' gather rays found (transport_precompute.h traces them): the input of both
// the clustering and the form factors.
#pragma once

#include <cstdint>
#include <vector>

namespace afterglow::baker {

struct TexelGather {
  // Hit codes: the texel whose surface a ray reached, with kBackSide set when it reached the
  // back of a double-sided surface; kNoHit for misses (sky) and absorbed rays (backs of
  // single-sided geometry, dynamic instances, surfaces without texels).
  static constexpr uint32_t kBackSide = 0x80000000u;
  static constexpr uint32_t kNoHit = 0xffffffffu;
  uint32_t raysPerTexel = 0;               // the first pass's rays per texel
  // Texel t's rays are hits[hitStart[t] .. hitStart[t+1]): raysPerTexel, plus more for texels
  // near other geometry (LinkOptions::nearRays), none for invalid texels.
  std::vector<uint32_t> hitStart;
  std::vector<uint32_t> hits;
  std::vector<float> sky;                  // texel-major, kShCount per texel: sky SH transfer
  std::vector<float> harmonicDistance;     // metres: N / Σ 1/d over the rays (∞: open sky)
  // Texels whose back side some ray reached (double-sided surfaces seen from behind): only
  // those get back-side clusters, since light on a back nobody sees goes nowhere. Their
  // harmonic distance seen from behind (an eighth of the rays) drives that clustering.
  std::vector<uint8_t> backSeen;
  std::vector<float> backHarmonicDistance;
};

}  // namespace afterglow::baker
