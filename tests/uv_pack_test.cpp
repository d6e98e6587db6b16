// Packing: footprints checked against a brute-force rasterisation written here (polygon clipping
// against each texel), not against the packer's own bitmaps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "afterglow/core/parallel.h"
#include "afterglow/uv/pack.h"

namespace afterglow::uv {
namespace {

// Area of the triangle clipped to [x0,x1] x [y0,y1] (Sutherland-Hodgman).
double clippedArea(const glm::dvec2 tri[3], double x0, double y0, double x1, double y1) {
  std::vector<glm::dvec2> poly(tri, tri + 3);
  auto clip = [&](auto inside, auto intersect) {
    std::vector<glm::dvec2> out;
    for (size_t i = 0; i < poly.size(); ++i) {
      const glm::dvec2 a = poly[i], b = poly[(i + 1) % poly.size()];
      const bool ia = inside(a), ib = inside(b);
      if (ia) out.push_back(a);
      if (ia != ib) out.push_back(intersect(a, b));
    }
    poly = out;
  };
  auto lerpX = [](double x) {
    return [x](glm::dvec2 a, glm::dvec2 b) { return a + (b - a) * ((x - a.x) / (b.x - a.x)); };
  };
  auto lerpY = [](double y) {
    return [y](glm::dvec2 a, glm::dvec2 b) { return a + (b - a) * ((y - a.y) / (b.y - a.y)); };
  };
  clip([&](glm::dvec2 p) { return p.x >= x0; }, lerpX(x0));
  clip([&](glm::dvec2 p) { return p.x <= x1; }, lerpX(x1));
  clip([&](glm::dvec2 p) { return p.y >= y0; }, lerpY(y0));
  clip([&](glm::dvec2 p) { return p.y <= y1; }, lerpY(y1));
  double area = 0.0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const glm::dvec2 a = poly[i], b = poly[(i + 1) % poly.size()];
    area += a.x * b.y - a.y * b.x;
  }
  return std::abs(area) * 0.5;
}

struct Check {
  size_t covered = 0, overlapping = 0, paddingViolations = 0, outside = 0;
  std::vector<size_t> coveredPerAtlas;
};

// Places every chart as the unwrap would (float rotation * p + offset), marks texels whose
// square (shrunk by 1e-3 texel for float round-off) the triangle overlaps with positive area,
// then counts overlaps and pairs closer than `padding` empty texels.
Check bruteForce(const std::vector<PackChart>& charts, const PackResult& r, int padding) {
  Check check;
  for (size_t a = 0; a < r.atlasSizes.size(); ++a) {
    const int W = r.atlasSizes[a].x, H = r.atlasSizes[a].y;
    std::vector<int> owner(size_t(W) * H, -1);
    size_t covered = 0;
    for (size_t i = 0; i < charts.size(); ++i) {
      const ChartPlacement& pl = r.placements[i];
      if (pl.atlas != int(a)) continue;
      const std::vector<glm::vec2>& t = charts[i].triangles;
      for (size_t k = 0; k + 2 < t.size(); k += 3) {
        glm::dvec2 v[3];
        for (int j = 0; j < 3; ++j) {
          v[j] = glm::dvec2(pl.rotation * t[k + j] + pl.offset);
          if (v[j].x < -1e-3 || v[j].y < -1e-3 || v[j].x > W + 1e-3 || v[j].y > H + 1e-3)
            ++check.outside;
        }
        const int xs = std::max(0, int(std::floor(std::min({v[0].x, v[1].x, v[2].x}))));
        const int ys = std::max(0, int(std::floor(std::min({v[0].y, v[1].y, v[2].y}))));
        const int xe = std::min(W - 1, int(std::floor(std::max({v[0].x, v[1].x, v[2].x}))));
        const int ye = std::min(H - 1, int(std::floor(std::max({v[0].y, v[1].y, v[2].y}))));
        for (int y = ys; y <= ye; ++y)
          for (int x = xs; x <= xe; ++x) {
            if (clippedArea(v, x + 1e-3, y + 1e-3, x + 1 - 1e-3, y + 1 - 1e-3) <= 0.0) continue;
            int& o = owner[size_t(y) * W + x];
            if (o < 0) {
              o = int(i);
              ++covered;
            } else if (o != int(i)) {
              ++check.overlapping;
            }
          }
      }
    }
    check.covered += covered;
    check.coveredPerAtlas.push_back(covered);
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const int o = owner[size_t(y) * W + x];
        if (o < 0) continue;
        bool bad = false;
        for (int yy = std::max(0, y - padding); yy <= std::min(H - 1, y + padding); ++yy)
          for (int xx = std::max(0, x - padding); xx <= std::min(W - 1, x + padding); ++xx) {
            const int o2 = owner[size_t(yy) * W + xx];
            bad |= o2 >= 0 && o2 != o;
          }
        check.paddingViolations += bad;
      }
  }
  return check;
}

PackChart rectangle(float w, float h, float angle, glm::vec2 at) {
  const float c = std::cos(angle), s = std::sin(angle);
  auto p = [&](float x, float y) { return glm::vec2(c * x - s * y, s * x + c * y) + at; };
  return PackChart{{p(0, 0), p(w, 0), p(w, h), p(0, 0), p(w, h), p(0, h)}};
}

std::vector<PackChart> randomCharts(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<PackChart> charts;
  for (int i = 0; i < count; ++i) {
    const glm::vec2 at(200 * u(rng) - 100, 200 * u(rng) - 100);
    const float kind = u(rng);
    if (kind < 0.4f) {
      const float scale = u(rng) < 0.2f ? 30.0f : 4.0f;
      const float angle = u(rng) < 0.5f ? 0.0f : 6.2831853f * u(rng);
      charts.push_back(rectangle(0.2f + scale * u(rng), 0.2f + scale * u(rng), angle, at));
    } else if (kind < 0.85f) {
      const float s = u(rng) < 0.2f ? 25.0f : 3.0f;
      charts.push_back(PackChart{{at + s * glm::vec2(u(rng), u(rng)),
                                  at + s * glm::vec2(u(rng), u(rng)),
                                  at + s * glm::vec2(u(rng), u(rng))}});
    } else {  // sliver: far thinner than a texel, several texels long
      const glm::vec2 d(10 * u(rng) + 1, 10 * u(rng) - 5);
      const glm::vec2 n = glm::normalize(glm::vec2(-d.y, d.x)) * 1e-3f;
      charts.push_back(PackChart{{at, at + d, at + d + n}});
    }
  }
  return charts;
}

void expectOrthonormal(const glm::mat2& m) {
  const glm::mat2 id = glm::transpose(m) * m;
  EXPECT_NEAR(id[0][0], 1.0f, 1e-6f);
  EXPECT_NEAR(id[1][1], 1.0f, 1e-6f);
  EXPECT_NEAR(id[0][1], 0.0f, 1e-6f);
  EXPECT_NEAR(glm::determinant(m), 1.0f, 1e-6f);  // a turn, never a mirror
}

TEST(UvPack, RandomChartsNoOverlapAndPaddingKept) {
  const std::vector<PackChart> charts = randomCharts(600, 1);
  for (int padding : {0, 1, 2, 3}) {
    PackOptions options;
    options.padding = padding;
    const PackResult r = packCharts(charts, options);
    ASSERT_EQ(r.placements.size(), charts.size());
    ASSERT_EQ(r.atlasSizes.size(), 1u);
    EXPECT_EQ(r.atlasSizes[0].x % 4, 0);
    EXPECT_EQ(r.atlasSizes[0].y % 4, 0);
    for (const ChartPlacement& p : r.placements) {
      EXPECT_EQ(p.atlas, 0);
      expectOrthonormal(p.rotation);
    }
    const Check check = bruteForce(charts, r, padding);
    EXPECT_EQ(check.outside, 0u) << "padding " << padding;
    EXPECT_EQ(check.overlapping, 0u) << "padding " << padding;
    EXPECT_EQ(check.paddingViolations, 0u) << "padding " << padding;
    EXPECT_GT(check.covered, 0u);
  }
}

TEST(UvPack, SliversCoverEveryTexelTheyCross) {
  // A diagonal sliver 1e-3 texels thick crossing 10 columns must reserve a staircase of texels;
  // packed next to full squares, nothing may overlap it.
  std::vector<PackChart> charts;
  for (int i = 0; i < 20; ++i) {
    const glm::vec2 a(0.3f, 0.3f), d(9.4f, 3.1f + 0.1f * float(i));
    const glm::vec2 n = glm::normalize(glm::vec2(-d.y, d.x)) * 1e-3f;
    charts.push_back(PackChart{{a, a + d, a + d + n}});
    charts.push_back(rectangle(3, 3, 0, glm::vec2(0)));
  }
  PackOptions options;
  options.padding = 1;
  const PackResult r = packCharts(charts, options);
  const Check check = bruteForce(charts, r, 1);
  EXPECT_EQ(check.overlapping, 0u);
  EXPECT_EQ(check.paddingViolations, 0u);
  EXPECT_GE(check.covered, 20u * (10 + 9));  // each sliver crosses at least 10 columns
}

TEST(UvPack, ThinRotatedRectangleIsTurnedToItsMinimumAreaBox) {
  // 100 x 2 texels at 30°: packed unturned its box would be ~88 x 52 texels.
  const std::vector<PackChart> charts = {rectangle(100, 2, 0.5235988f, glm::vec2(7.3f, -2.1f))};
  const PackResult r = packCharts(charts);
  ASSERT_EQ(r.atlasSizes.size(), 1u);
  // Float round-off of the turn must not cost a column: exactly 100 x 2 texels.
  const glm::ivec2 size = r.atlasSizes[0];
  EXPECT_EQ(std::min(size.x, size.y), 4);
  EXPECT_EQ(std::max(size.x, size.y), 100);
  EXPECT_EQ(bruteForce(charts, r, 2).covered, 200u);
  expectOrthonormal(r.placements[0].rotation);
}

TEST(UvPack, EqualSquaresPackAtTheLatticeBound) {
  // 4 x 4 texel squares with 2 texels of padding: the best lattice has a pitch of 6, so
  // 16 / 36 = 0.444 of an unbounded atlas is covered; squares on the atlas border need no
  // padding outside, so a finite atlas may do slightly better. Demand 95% of the lattice bound.
  std::vector<PackChart> charts;
  for (int i = 0; i < 1000; ++i) charts.push_back(rectangle(4, 4, 0, glm::vec2(float(i), 0.0f)));
  const PackResult r = packCharts(charts);
  ASSERT_EQ(r.atlasSizes.size(), 1u);
  const Check check = bruteForce(charts, r, 2);
  EXPECT_EQ(check.covered, 16000u);
  EXPECT_EQ(check.overlapping, 0u);
  EXPECT_EQ(check.paddingViolations, 0u);
  const double utilisation = 16000.0 / (double(r.atlasSizes[0].x) * r.atlasSizes[0].y);
  EXPECT_GE(utilisation, 0.95 * 16.0 / 36.0);
}

TEST(UvPack, SpillsIntoMoreAtlasesAndRejectsOversizedCharts) {
  // 10 x 10 squares, padding 2, 64-texel atlases: 5 per row (5*10 + 4*2 = 58), 25 per atlas.
  std::vector<PackChart> charts;
  for (int i = 0; i < 60; ++i) charts.push_back(rectangle(10, 10, 0, glm::vec2(0)));
  charts.push_back(rectangle(70, 70, 0, glm::vec2(0)));  // larger than an atlas in any turn
  PackOptions options;
  options.maxAtlasSize = 64;
  const PackResult r = packCharts(charts, options);
  EXPECT_EQ(r.atlasSizes.size(), 3u);
  for (const glm::ivec2& s : r.atlasSizes) {
    EXPECT_LE(s.x, 64);
    EXPECT_LE(s.y, 64);
  }
  std::vector<int> perAtlas(r.atlasSizes.size(), 0);
  for (size_t i = 0; i < 60; ++i) {
    ASSERT_GE(r.placements[i].atlas, 0);
    ASSERT_LT(r.placements[i].atlas, int(r.atlasSizes.size()));
    ++perAtlas[r.placements[i].atlas];
  }
  EXPECT_EQ(perAtlas[0], 25);
  EXPECT_EQ(perAtlas[1], 25);
  EXPECT_EQ(perAtlas[2], 10);
  EXPECT_EQ(r.placements[60].atlas, -1);
  const std::vector<PackChart> placed(charts.begin(), charts.begin() + 60);
  const PackResult placedOnly{r.atlasSizes, {r.placements.begin(), r.placements.begin() + 60}};
  const Check check = bruteForce(placed, placedOnly, 2);
  EXPECT_EQ(check.outside, 0u);
  EXPECT_EQ(check.overlapping, 0u);
  EXPECT_EQ(check.paddingViolations, 0u);
  EXPECT_EQ(check.covered, 6000u);
}

TEST(UvPack, AtlasesWiderThan4096Texels) {
  // More than 64 words per atlas row: the word-level search runs over several 64-bit masks.
  // Without the extra quarter turn the long chart lies along x (its wide side) and sets the width.
  std::vector<PackChart> charts = randomCharts(300, 3);
  charts.push_back(rectangle(5000, 3, 0, glm::vec2(0)));
  PackOptions options;
  options.maxAtlasSize = 8192;
  options.allowRotation = false;
  const PackResult r = packCharts(charts, options);
  ASSERT_EQ(r.atlasSizes.size(), 1u);
  EXPECT_GE(r.atlasSizes[0].x, 5000);
  for (const ChartPlacement& p : r.placements) EXPECT_EQ(p.atlas, 0);
  const Check check = bruteForce(charts, r, 2);
  EXPECT_EQ(check.outside, 0u);
  EXPECT_EQ(check.overlapping, 0u);
  EXPECT_EQ(check.paddingViolations, 0u);
}

TEST(UvPack, SameResultWhateverTheThreadCount) {
  const std::vector<PackChart> charts = randomCharts(3000, 7);
  setThreadCount(1);
  const PackResult one = packCharts(charts);
  setThreadCount(2);
  const PackResult two = packCharts(charts);
  setThreadCount(0);
  ASSERT_EQ(one.atlasSizes, two.atlasSizes);
  ASSERT_EQ(one.placements.size(), two.placements.size());
  for (size_t i = 0; i < one.placements.size(); ++i) {
    EXPECT_EQ(one.placements[i].atlas, two.placements[i].atlas);
    EXPECT_EQ(one.placements[i].rotation, two.placements[i].rotation);
    EXPECT_EQ(one.placements[i].offset, two.placements[i].offset);
  }
}

TEST(UvPack, EmptyInputGivesNoAtlas) {
  const PackResult r = packCharts({});
  EXPECT_TRUE(r.atlasSizes.empty());
  EXPECT_TRUE(r.placements.empty());
}

}  // namespace
}  // namespace afterglow::uv
