// Issue 16's smoothness check: no blotches in the bounced light on flat walls. The gather's rays
// leave low-frequency mottling a few texels across ("splotchy GI"), which per-texel error
// figures (baker_accuracy_test.cpp) barely see but a level designer sees at once.
//
// On McGuire's Cornell box (the accuracy test's bake: one 256² atlas, the lamp emitting
// downwards only), the bounced light of the back wall and of the ceiling is band-passed between
// 2 and 12 texels: a difference of two Gaussian blurs (σ 2 and 12 texels) computed inside the
// wall only, each blur normalised by the blur of the wall's mask so other charts and empty atlas
// pixels do not leak in. A converged reference path tracer gives the same on a sub-grid of the
// same texels (every second texel each way, the blurs scaled to it).
//
// The issue asks for the band-pass's standard deviation relative to the wall's mean to be
// ≤ 1.5× the reference's and ≤ 1% absolute. As this test measures it, the reference's own figure
// is 8% on the back wall and 11% on the ceiling (5% even 12 texels inside the walls):
// bounced light really does change over 2-12 texels towards the corners, the lamp and the
// boxes. Against that real structure blotches add in quadrature and hide (a bake with half its
// rays and no smoothing still passes 1.5×), and no bake, not even the reference, can reach 1%.
// So the 1.5× ratio is checked as asked, and the 1% bound applies to what the check is for, the
// blotches: the band-pass of the bake's difference from the reference on the sub-grid, the
// reference's own noise (propagated through the filter's weights) removed in quadrature.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/baker/bake.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/uv/unwrap.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace afterglow::baker {
namespace {

using runtime::kNoTexel;

// One wall's texels on a grid of every `step`-th atlas pixel (step 1: every texel), with the
// connected piece of the wall each cell belongs to, so a wall cut into several charts is
// filtered chart by chart (two charts side by side in the atlas are not side by side on the
// wall).
struct WallGrid {
  int width = 0, height = 0;
  std::vector<uint32_t> texel;  // per cell, kNoTexel outside the wall
  std::vector<int> piece;       // per cell, -1 outside the wall
};

WallGrid wallGrid(const scenes::Scene& scene, const TexelSet& texels, int material, int step) {
  const runtime::AtlasLayout& layout = texels.atlases[0];
  WallGrid g;
  g.width = (layout.width + step - 1) / step;
  g.height = (layout.height + step - 1) / step;
  g.texel.assign(size_t(g.width) * size_t(g.height), kNoTexel);
  g.piece.assign(g.texel.size(), -1);
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const uint32_t t = layout.texelOfPixel[size_t(y * step) * size_t(layout.width) +
                                             size_t(x * step)];
      if (t != kNoTexel && texels.valid[t] && texelMaterial(scene, texels, t) == material)
        g.texel[size_t(y) * size_t(g.width) + size_t(x)] = t;
    }
  // Pieces: 4-connected components, by flood fill.
  int pieces = 0;
  std::vector<size_t> stack;
  for (size_t seed = 0; seed < g.texel.size(); ++seed) {
    if (g.texel[seed] == kNoTexel || g.piece[seed] >= 0) continue;
    g.piece[seed] = pieces;
    stack.push_back(seed);
    while (!stack.empty()) {
      const size_t c = stack.back();
      stack.pop_back();
      const int x = int(c % size_t(g.width)), y = int(c / size_t(g.width));
      const int nx[4] = {x - 1, x + 1, x, x}, ny[4] = {y, y, y - 1, y + 1};
      for (int k = 0; k < 4; ++k) {
        if (nx[k] < 0 || ny[k] < 0 || nx[k] >= g.width || ny[k] >= g.height) continue;
        const size_t n = size_t(ny[k]) * size_t(g.width) + size_t(nx[k]);
        if (g.texel[n] == kNoTexel || g.piece[n] >= 0) continue;
        g.piece[n] = pieces;
        stack.push_back(n);
      }
    }
    ++pieces;
  }
  return g;
}

struct BandPass {
  size_t cells = 0;
  double mean = 0.0;   // of the values over the wall
  double std = 0.0;    // of the band-pass over the wall
  double noise = 0.0;  // the part of std the values' own noise accounts for: √ of the
                       //   band-pass's noise variance, mean over the wall
};

// The band-pass (σ fine and coarse, in grid cells) of `value` (per texel) over the grid's
// cells, each Gaussian normalised by the blur of the cell's own piece. `variance` (per texel,
// may be empty) is the values' noise variance, propagated through the filter's weights.
BandPass bandPass(const WallGrid& g, const std::vector<float>& value,
                    const std::vector<float>& variance, double sigmaFine, double sigmaCoarse,
                    int margin = 0) {
  const int radius = int(std::ceil(3.0 * sigmaCoarse));
  std::vector<double> pass;
  double sumValue = 0.0, sumNoise = 0.0;
  std::vector<double> wFine, wCoarse;
  std::vector<size_t> near;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const size_t c = size_t(y) * size_t(g.width) + size_t(x);
      if (g.piece[c] < 0) continue;
      bool inside = true;
      for (int j = y - margin; j <= y + margin && inside; ++j)
        for (int i = x - margin; i <= x + margin && inside; ++i)
          inside = i >= 0 && j >= 0 && i < g.width && j < g.height &&
                   g.piece[size_t(j) * size_t(g.width) + size_t(i)] == g.piece[c];
      if (!inside) continue;
      wFine.clear(), wCoarse.clear(), near.clear();
      double fine = 0.0, coarse = 0.0;
      for (int j = std::max(0, y - radius); j <= std::min(g.height - 1, y + radius); ++j)
        for (int i = std::max(0, x - radius); i <= std::min(g.width - 1, x + radius); ++i) {
          const size_t n = size_t(j) * size_t(g.width) + size_t(i);
          if (g.piece[n] != g.piece[c]) continue;
          const double d2 = double((i - x) * (i - x) + (j - y) * (j - y));
          near.push_back(n);
          wFine.push_back(std::exp(-0.5 * d2 / (sigmaFine * sigmaFine)));
          wCoarse.push_back(std::exp(-0.5 * d2 / (sigmaCoarse * sigmaCoarse)));
          fine += wFine.back();
          coarse += wCoarse.back();
        }
      double out = 0.0, noise = 0.0;
      for (size_t k = 0; k < near.size(); ++k) {
        const double w = wFine[k] / fine - wCoarse[k] / coarse;
        out += w * double(value[g.texel[near[k]]]);
        if (!variance.empty()) noise += w * w * double(variance[g.texel[near[k]]]);
      }
      pass.push_back(out);
      sumValue += double(value[g.texel[c]]);
      sumNoise += noise;
    }
  BandPass s;
  s.cells = pass.size();
  if (pass.empty()) return s;
  const double n = double(pass.size());
  s.mean = sumValue / n;
  double m1 = 0.0, m2 = 0.0;
  for (double p : pass) m1 += p, m2 += p * p;
  m1 /= n, m2 /= n;
  s.std = std::sqrt(std::max(0.0, m2 - m1 * m1));
  s.noise = std::sqrt(sumNoise / n);
  return s;
}

// Bounced light as one number per texel: the mean of its three channels.
float grey(glm::vec3 v) { return (v.x + v.y + v.z) / 3.0f; }

// Blotches today: 0.7% on the back wall and 0.8% on the ceiling. They were 1.2% and 1.5% with
// each texel's rays jittered on its own grid, its block's shared far field thinned to three of
// its square's four blocks, and texels at a wall's edge smoothed with their inner neighbours
// only (sampling::TiledSobol, links.cpp's sharedRow, runtime gather_maps.cpp's mixOf). About
// 20 s on two cores.
TEST(BakeSmoothness, CornellWallsBouncedLightHasNoBlotchesBeyondTheReference) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_mcguire/CornellBox-Original.gltf");
  const scenes::Scene scene = cornellForAccuracy(path);  // the lamp emits downwards only
  ASSERT_FALSE(scene.materials.empty());

  Result<BakeResult> baked = bake(scene, BakeOptions());
  ASSERT_TRUE(baked) << baked.message();
  const BakeResult& b = baked.value();
  std::vector<float> bakeValue(b.texels.size());
  for (uint32_t t = 0; t < b.texels.size(); ++t) bakeValue[t] = grey(b.texelIndirect[t]);

  // The reference on every kStep-th texel each way (a quarter of the paths; the 2-texel blur is
  // still one sub-grid cell), at 8192 paths: its noise in the band is about 0.55% of the mean.
  constexpr int kStep = 2;
  constexpr double kFine = 2.0, kCoarse = 12.0;  // texels
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  for (const char* wall : {"backWall", "ceiling"}) {
    SCOPED_TRACE(wall);
    int material = -1;
    for (size_t m = 0; m < scene.materials.size(); ++m)
      if (scene.materials[m].name == wall) material = int(m);
    ASSERT_GE(material, 0) << "no material " << wall;
    const WallGrid full = wallGrid(scene, b.texels, material, 1);
    const WallGrid sub = wallGrid(scene, b.texels, material, kStep);
    std::vector<uint32_t> which;
    for (uint32_t t : sub.texel)
      if (t != kNoTexel) which.push_back(t);
    ASSERT_GT(which.size(), 500u);

    ReferenceOptions high;
    high.samples = 8192;
    Result<ReferenceTexels> ref =
        referenceTexels(scene, *tracer.value(), b.texels, Environment(), high, which);
    ASSERT_TRUE(ref) << ref.message();
    std::vector<float> refValue(b.texels.size(), 0.0f), refVariance(b.texels.size(), 0.0f);
    for (size_t i = 0; i < ref->texels.size(); ++i) {
      refValue[ref->texels[i]] = grey(ref->indirect[i]);
      // The channels come from the same paths: their noise adds up as if fully correlated.
      const glm::vec3 sd = glm::sqrt(ref->indirectVariance[i]);
      refVariance[ref->texels[i]] = grey(sd) * grey(sd);
    }

    const BandPass bakeFull = bandPass(full, bakeValue, {}, kFine, kCoarse);
    const BandPass bakeSub = bandPass(sub, bakeValue, {}, kFine / kStep, kCoarse / kStep);
    const BandPass refSub = bandPass(sub, refValue, refVariance, kFine / kStep, kCoarse / kStep);
    std::vector<float> difference(b.texels.size(), 0.0f);
    for (uint32_t t : which) difference[t] = bakeValue[t] - refValue[t];
    const BandPass error = bandPass(sub, difference, refVariance, kFine / kStep, kCoarse / kStep);
    // Everything relative to the reference's mean over the wall. The reference's noise passes
    // the filter independently of the signal, so it is removed in quadrature.
    auto relative = [&](double v) { return v / refSub.mean; };
    auto denoised = [&](const BandPass& p) {
      return relative(std::sqrt(std::max(0.0, p.std * p.std - p.noise * p.noise)));
    };
    const double reference = denoised(refSub), blotches = denoised(error);
    std::printf("%-8s bounced light band-passed 2-12 texels, std / mean: bake %.2f%% (%zu "
                "texels); on the sub-grid (%zu texels, reference at %d paths) bake %.2f%%, "
                "reference %.2f%% (%.2f%% less its noise %.2f%%); blotches (bake - reference) "
                "%.2f%% (%.2f%% less the reference's noise); mean bake %.5f reference %.5f\n",
                wall, 100.0 * bakeFull.std / bakeFull.mean, bakeFull.cells, refSub.cells,
                high.samples, 100.0 * relative(bakeSub.std), 100.0 * reference,
                100.0 * relative(refSub.std), 100.0 * relative(refSub.noise), 100.0 * blotches,
                100.0 * relative(error.std), bakeSub.mean, refSub.mean);
    // The reference must be converged well below the bound for the comparison to mean anything.
    EXPECT_LT(relative(refSub.noise), 0.007);
    EXPECT_LE(relative(bakeSub.std), 1.5 * reference);
    EXPECT_LE(blotches, 0.01);
  }
}

}  // namespace
}  // namespace afterglow::baker
