// The math basics every library shares, defined once: π, a finiteness test for GLM vectors, a
// linear colour's luminance and a 64-bit hash.
// Header-only and GLM-only, so the runtime (which links GLM alone) uses it too.
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

namespace afterglow {

constexpr double kPiDouble = 3.14159265358979323846;
constexpr float kPi = float(kPiDouble);

// Whether every component of v is finite (no NaN, no infinity).
template <glm::length_t N, class T, glm::qualifier Q>
bool finite(const glm::vec<N, T, Q>& v) {
  for (glm::length_t i = 0; i < N; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

// Rec. 709 luminance of a linear RGB colour.
inline float luminance(glm::vec3 c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

// SplitMix64's finaliser: a cheap, well-mixed 64-bit hash (the baker's random numbers, the ray
// tracer's choices at glass).
inline uint64_t mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace afterglow
