// A cluster reflects its texels' direct light averaged over their footprints, not at their
// samples (issue 16, direct.cpp): the sunlight a floor reflects under a roof with a slit is the
// slit's area times the sun's light, wherever the slit's edges fall between samples. Samples
// alone count a texel as wholly lit or wholly dark, off by up to a texel's width of slit (and
// footprint points at fixed places in the texel are off too where an edge lines up with them); on
// Sponza-sun slivers of sun thinner than a texel went missing and walls that see them came out
// up to 97% too dark.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "afterglow/baker/bake.h"
#include "bake_fixtures.h"

namespace afterglow::baker {
namespace {

// Σ over the floor's front clusters of the sun's transfer × area (the reflected sunlight, up to
// the albedo), and the same from the texels' samples.
struct Floor {
  double clusters = 0.0, samples = 0.0, area = 0.0;
};
Floor sunOnTheFloor(const BakeResult& b) {
  Floor f;
  const runtime::Source& sun = b.transport.sources.at(0);
  for (uint32_t c = 0; c < b.clusters.size(); ++c) {
    if (b.clusters.back[c] || b.clusters.firstTexel[c] == b.clusters.firstTexel[c + 1]) continue;
    if (b.texels.instance[b.clusters.memberTexels[b.clusters.firstTexel[c]]] != 0) continue;
    f.clusters += double(sun.clusterTransfer[c]) * double(b.clusters.area[c]);
  }
  for (uint32_t t = 0; t < b.texels.size(); ++t)
    if (b.texels.valid[t] && b.texels.instance[t] == 0) {
      f.samples += double(sun.texelTransfer[t]) * double(b.texels.area[t]);
      f.area += double(b.texels.area[t]);
    }
  return f;
}

TEST(BakeFootprintLight, AFloorReflectsTheSunThroughASlitWhereverItsEdgesFall) {
  BakeOptions options = draftOptions();
  scenes::Scene open = floorUnderASlit(false, 0.0f, 0.0f);
  unwrapAt(open, 4.0f);
  const Floor full = sunOnTheFloor(bakeOrDie(open, options));
  ASSERT_GT(full.area, 15.0);
  const double perArea = full.clusters / full.area;  // the sun's transfer on open floor
  // A 60 cm slit at five offsets over one texel, and a 20 cm one centred on a texel edge: its
  // two columns lit 40% each, which points at the cells' centres saw lit 50% (+25%).
  struct Slit {
    float from, width;
  };
  const Slit slits[] = {{-0.3f, 0.6f}, {-0.23f, 0.6f}, {-0.17f, 0.6f}, {-0.11f, 0.6f},
                        {-0.05f, 0.6f}, {-0.1f, 0.2f}};
  double worstClusters = 0.0, worstSamples = 0.0;
  for (const Slit& slit : slits) {
    scenes::Scene scene = floorUnderASlit(true, slit.from, slit.width);
    unwrapAt(scene, 4.0f);
    const Floor f = sunOnTheFloor(bakeOrDie(scene, options));
    const double want = perArea * double(slit.width) * 4.0;  // the slit's width × 4 m of floor
    const double clusters = f.clusters / want - 1.0, samples = f.samples / want - 1.0;
    std::printf("slit %.0f cm from x = %+.2f: sunlight reflected %+.1f%% off (footprints), "
                "%+.1f%% (samples)\n", 100.0 * slit.width, slit.from, 100.0 * clusters,
                100.0 * samples);
    worstClusters = std::max(worstClusters, std::abs(clusters));
    worstSamples = std::max(worstSamples, std::abs(samples));
  }
  // A texel's 4 × 4 points, multi-jittered (16 strata along each axis), place an edge along the
  // grid to a sixteenth of a texel, without bias: 1.7% off at worst, measured over four
  // different jitters (with the points at their cells' centres 4.7% on the wide slits and +25%
  // on the narrow one).
  EXPECT_LE(worstClusters, 0.05);
  // The samples alone miss by up to a texel column (25% measured, the slit's edges at five
  // offsets over one texel; 100% on the narrow slit): the scene tests what it should.
  EXPECT_GE(worstSamples, 0.15);
}

}  // namespace
}  // namespace afterglow::baker
