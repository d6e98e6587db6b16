// Direct light stays sharp with two resolutions (issue 29): the lightmap keeps each light's
// direct light per lightmap texel, only the bounced light comes from the coarse grid, so a
// sun's shadow edge through a 20 cm slit onto a floor at 16 texels/m is as wide as the reference
// path tracer's at the same texels (within one texel), whatever the grid's density. Direct
// light read from the grid (4 texels/m here) would spread each edge over a grid texel: four
// lightmap texels.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/uv/indirect.h"
#include "bake_fixtures.h"

namespace afterglow::baker {
namespace {

constexpr float kFine = 16.0f, kGrid = 4.0f;

// The 10%-90% widths (metres) of a profile's two edges across the slit, from values at sorted
// x: dark is the mean under the roof (|x| > 0.4 m), lit the largest; each edge's crossings
// interpolated between samples, walking in from each side.
struct Edges {
  double left = 0.0, right = 0.0;
};
Edges edgeWidths(const std::vector<std::pair<float, float>>& profile) {
  double dark = 0.0, lit = 0.0;
  int darkCount = 0;
  for (const auto& [x, v] : profile) {
    if (std::abs(x) > 0.4f) dark += v, ++darkCount;
    lit = std::max(lit, double(v));
  }
  dark /= std::max(darkCount, 1);
  // Where the profile, walked from index `from` by `step`, first reaches `level`.
  auto crossing = [&](double level, int from, int step) {
    const double y = dark + level * (lit - dark);
    for (int i = from; i + step >= 0 && i + step < int(profile.size()); i += step) {
      const auto& [x0, v0] = profile[size_t(i)];
      const auto& [x1, v1] = profile[size_t(i + step)];
      if (v0 < y && v1 >= y) return double(x0) + (y - v0) / (double(v1) - v0) * double(x1 - x0);
    }
    return std::nan("");
  };
  const int last = int(profile.size()) - 1;
  Edges e;
  e.left = crossing(0.9, 0, 1) - crossing(0.1, 0, 1);
  e.right = crossing(0.1, last, -1) - crossing(0.9, last, -1);
  return e;
}

// Per row of floor texels across the slit (|z| < 0.5 m, |x| < 0.6 m), the profile of a value.
template <class Value>
std::vector<Edges> rowsEdges(const BakeResult& b, const std::vector<uint32_t>& texels,
                             const Value& value) {
  std::map<int, std::vector<std::pair<float, float>>> rows;
  for (size_t i = 0; i < texels.size(); ++i) {
    const glm::vec3 p = b.texels.position[texels[i]];
    rows[int(std::floor(p.z * kFine))].push_back({p.x, value(i)});
  }
  std::vector<Edges> out;
  for (auto& [row, profile] : rows) {
    std::sort(profile.begin(), profile.end());
    out.push_back(edgeWidths(profile));
  }
  return out;
}

void checkSlit(float angularDiameter) {
  scenes::Scene scene = floorUnderASlit(true, -0.1f, 0.2f);
  scene.lights[0].angularDiameter = angularDiameter;
  unwrapAt(scene, kFine);
  uv::clearIndirect(scene);
  Result<uv::IndirectLayout> packed = uv::packIndirect(scene, kGrid);
  ASSERT_TRUE(packed) << packed.message();
  const BakeResult b = bakeOrDie(scene, draftOptions());
  ASSERT_TRUE(b.transport.lightmap.active()) << "the bake should have used the indirect grid";

  std::vector<uint32_t> band;
  for (uint32_t t = 0; t < b.texels.size(); ++t) {
    const glm::vec3 p = b.texels.position[t];
    if (b.texels.valid[t] && b.texels.instance[t] == 0 && std::abs(p.z) < 0.5f &&
        std::abs(p.x) < 0.6f)
      band.push_back(t);
  }
  ASSERT_GT(band.size(), 200u);
  const ReferenceTexels ref = referenceOrDie(scene, b.texels, Environment{}, 1024, band);
  ASSERT_EQ(ref.texels.size(), band.size());

  const std::vector<Edges> baked = rowsEdges(b, band, [&](size_t i) {
    return b.texelDirect[band[i]].x + b.texelIndirect[band[i]].x;
  });
  const std::vector<Edges> wanted = rowsEdges(b, band, [&](size_t i) {
    return ref.direct[i].x + ref.indirect[i].x;
  });
  ASSERT_EQ(baked.size(), wanted.size());
  double bakedMean = 0.0, wantedMean = 0.0, worst = 0.0;
  for (size_t r = 0; r < baked.size(); ++r)
    for (auto [bw, rw] : {std::pair{baked[r].left, wanted[r].left},
                          std::pair{baked[r].right, wanted[r].right}}) {
      ASSERT_TRUE(std::isfinite(bw) && std::isfinite(rw)) << "row " << r << ": no edge found";
      bakedMean += bw;
      wantedMean += rw;
      worst = std::max(worst, std::abs(bw - rw));
    }
  bakedMean /= double(2 * baked.size());
  wantedMean /= double(2 * baked.size());
  std::printf("sun %.2f deg, %zu rows: 10-90%% edge width %.2f texels (reference %.2f), worst "
              "row's difference %.2f texels\n",
              double(angularDiameter) * 180.0 / M_PI, baked.size(), bakedMean * kFine,
              wantedMean * kFine, worst * kFine);
  EXPECT_LE(worst * kFine, 1.0);
}

TEST(SharpShadows, ASunsEdgeThroughASlitIsAsWideAsTheReferences) {
  checkSlit(0.00925f);  // the sun's 0.53 degrees: a 1 cm penumbra, under a texel
}

TEST(SharpShadows, AWideSunsPenumbraIsAsWideAsTheReferences) {
  checkSlit(0.14f);  // 8 degrees: a 14 cm penumbra, over two texels
}

}  // namespace
}  // namespace afterglow::baker
