// A small deterministic generator for the runtime tests' synthetic transports: the same numbers
// on every standard library, unlike <random>'s distributions.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "afterglow/core/math.h"

namespace afterglow::runtime::test {

struct Rng {
  uint64_t state;
  uint32_t next() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return uint32_t(state >> 33);
  }
  uint32_t below(uint32_t n) { return n ? next() % n : 0; }
  float unit() { return float(next() >> 8) / float(1u << 23); }
};

// A direction uniform over the unit sphere (z uniform, φ uniform).
inline glm::vec3 randomDirection(Rng& rng) {
  const float z = 1.0f - 2.0f * rng.unit();
  const float phi = 2.0f * kPi * rng.unit();
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

}  // namespace afterglow::runtime::test
