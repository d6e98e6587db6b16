// Union-find over 0..n-1 (path halving): which triangles form one chart, one closed shell.
// The smaller root wins, so the sets and their roots do not depend on the order of unions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace afterglow {

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a < b) parent[b] = a;
    else if (b < a) parent[a] = b;
  }
};

}  // namespace afterglow
