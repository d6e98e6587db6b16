// A small deterministic generator for the runtime tests' synthetic transports: the same numbers
// on every standard library, unlike <random>'s distributions.
#pragma once

#include <cstdint>

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

}  // namespace afterglow::runtime::test
