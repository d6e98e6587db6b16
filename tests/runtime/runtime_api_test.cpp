// The relighting API (runtime/include/afterglow/runtime/runtime.h and afterglow_runtime.h) on a
// small synthetic transport: bit-exact agreement with the bake's solve, linearity in the
// sources, the settings' meaning, warm starts, files, threads and the C API. Links
// afterglow_runtime alone (no baker).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "afterglow/runtime/reflection_capture.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/runtime.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/runtime/transport_file.h"
#include "afterglow_runtime.h"
#include "test_rng.h"

// Counts heap allocations on threads that ask for it, to prove update() allocates nothing.
// Not under sanitizers, whose own operator new must stay.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define AFTERGLOW_COUNT_ALLOCATIONS 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define AFTERGLOW_COUNT_ALLOCATIONS 0
#endif
#endif
#ifndef AFTERGLOW_COUNT_ALLOCATIONS
#define AFTERGLOW_COUNT_ALLOCATIONS 1
#endif
namespace {
std::atomic<long> gAllocations{0};
thread_local bool gCountAllocations = false;
}  // namespace
#if AFTERGLOW_COUNT_ALLOCATIONS
namespace {
void* countedAlloc(std::size_t n) {
  if (gCountAllocations) gAllocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
}  // namespace
void* operator new(std::size_t n) { return countedAlloc(n); }
void* operator new[](std::size_t n) { return countedAlloc(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#endif

// From c_api_compile.c (compiled as C).
extern "C" int afterglow_test_c_relight(const char* path, float* rgb, size_t float_count,
                                        char* err, size_t err_size);
extern "C" int afterglow_test_c_load_fails(const char* path, char* err, size_t err_size);
extern "C" int afterglow_test_c_probes(const char* path, float* out);
extern "C" int afterglow_test_c_reflections(const char* path, float* cube, float* projected,
                                            int* probes, float* weights, int* count,
                                            AfterglowReflectionProbeBox* box);

namespace afterglow::runtime {
namespace {

using test::Rng;

// A valid transport whose bounces converge: every links row sees at most 80% of its hemisphere,
// albedos stay below 1, gathers and filters are averages. Lights "key", "fill", "rim"; materials
// "floor", "wall" and the emissive "lamp"; a sky; two atlases with mixes. `scale` multiplies the
// texel count and the atlases' sides.
TransportData makeScene(uint32_t scale = 1, uint64_t seed = 7) {
  Rng rng{seed};
  TransportData d;
  d.texelCount = 60 * scale * scale;
  d.clusterCount = 20;
  d.gatherPointCount = 30;
  const uint32_t backRows = 3, rows = d.gatherPointCount + backRows;

  const int sides[2][2] = {{9, 7}, {5, 4}};
  for (const auto& side : sides) {
    AtlasLayout a;
    a.width = side[0] * int(scale);
    a.height = side[1] * int(scale);
    for (int p = 0; p < a.width * a.height; ++p)
      a.texelOfPixel.push_back(rng.below(6) == 0 ? kNoTexel : rng.below(d.texelCount));
    for (int p = 0; p < a.width * a.height; p += 3 + int(rng.below(5))) {
      a.mixPixel.push_back(uint32_t(p));
      for (uint32_t k = 0, n = 1 + rng.below(3); k < n; ++k) {
        a.mixTexel.push_back(rng.below(d.texelCount));
        a.mixWeight.push_back(0.2f + 0.3f * rng.unit());
      }
      a.mixStart.push_back(uint32_t(a.mixTexel.size()));
    }
    d.atlases.push_back(std::move(a));
  }

  d.materials.push_back({"floor", glm::vec3(0.5f, 0.6f, 0.7f), glm::vec3(0.0f)});
  d.materials.push_back({"wall", glm::vec3(0.7f), glm::vec3(0.0f)});
  d.materials.push_back({"lamp", glm::vec3(0.6f), glm::vec3(5.0f, 4.0f, 3.0f)});

  const char* names[3] = {"key", "fill", "rim"};
  const glm::vec3 colors[3] = {{1.0f, 0.9f, 0.8f}, {0.3f, 0.4f, 1.0f}, {1.0f, 0.5f, 0.2f}};
  for (int i = 0; i < 4; ++i) {
    Source s;
    s.name = i < 3 ? names[i] : "lamp";
    s.kind = i < 3 ? SourceKind::Light : SourceKind::Emissive;
    s.material = i < 3 ? 0u : 2u;
    if (i < 3) {
      s.color = colors[i];
      s.intensity = 1.5f + float(i);
      s.bounceIntensity = i == 2 ? 0.5f : 1.0f;
    }
    for (uint32_t t = 0; t < d.texelCount; ++t)
      s.texelTransfer.push_back(rng.below(4) == 0 ? 0.0f : rng.unit());
    for (uint32_t c = 0; c < d.clusterCount; ++c) s.clusterTransfer.push_back(rng.unit());
    d.sources.push_back(std::move(s));
  }
  // Insert the emissive source between lights, so light indices differ from source indices.
  std::swap(d.sources[1], d.sources[3]);
  std::swap(d.sources[2], d.sources[3]);  // order: key, lamp, fill, rim

  for (uint32_t c = 0; c < d.clusterCount; ++c) {
    d.clusterMaterial.push_back(rng.below(3));
    d.clusterAlbedoTexture.push_back(glm::vec3(0.5f + 0.5f * rng.unit()));
    d.clusterEmissionTexture.push_back(glm::vec3(1.0f));
  }

  std::vector<uint32_t> cols;
  std::vector<float> w;
  for (uint32_t r = 0; r < rows; ++r) {
    cols.clear();
    w.clear();
    float sum = 0.0f;
    for (uint32_t c = rng.below(3); c < d.clusterCount; c += 1 + rng.below(4)) {
      cols.push_back(c);
      w.push_back(0.1f + rng.unit());
      sum += w.back();
    }
    for (float& x : w) x *= 0.8f / sum;
    d.links.appendRow(cols.data(), w.data(), cols.size());
  }
  // Rows of a sparse matrix mixing `count` random columns with weights summing to 1.
  auto average = [&](SparseMatrix& m, uint32_t rowCount, uint32_t columns, uint32_t count) {
    for (uint32_t r = 0; r < rowCount; ++r) {
      cols.clear();
      w.clear();
      for (uint32_t k = 0; k < count; ++k) {
        cols.push_back(rng.below(columns));
        w.push_back(1.0f / float(count));
      }
      m.appendRow(cols.data(), w.data(), cols.size());
    }
  };
  average(d.clusterGather, d.clusterCount, rows, 2);
  // Texels read random gather points and smooth with random atlas neighbours.
  d.filterPasses = 1;
  for (uint32_t t = 0; t < d.texelCount; ++t) {
    d.texelPoint.push_back(rng.below(d.gatherPointCount));
    d.texelNeighbours.push_back(uint8_t(rng.below(256)));
  }
  buildGatherMaps(d);

  for (uint32_t i = 0; i < d.texelCount * kShCount; ++i)
    d.texelSky.push_back(floatToHalf(i % kShCount == 0 ? 0.3f * rng.unit() : 0.05f * rng.unit()));
  for (uint32_t i = 0; i < d.clusterCount * kShCount; ++i)
    d.clusterSky.push_back(floatToHalf(i % kShCount == 0 ? 0.3f * rng.unit() : 0.05f * rng.unit()));
  for (int i = 0; i < kShCount; ++i) d.skySh[i] = glm::vec3(0.2f, 0.3f, 0.5f) * (i == 0 ? 1.0f : 0.1f);
  d.indirectIntensity = 1.0f;
  d.albedoBoost = 1.0f;
  // Five light probes in two tetrahedra, three regions each (an odd count: the runtime pairs
  // regions), seeing random clusters (one region none), the sky and every source.
  ProbeTransport& probes = d.probes;
  probes.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  probes.mesh.tetrahedra = {{0, 1, 2, 3}, {1, 4, 2, 3}};
  probes.mesh.neighbours = {{1, -1, -1, -1}, {-1, 0, -1, -1}};
  probes.bins = 3;
  for (uint32_t k = 0; k < probes.bins * kShCount; ++k) probes.binSh.push_back(rng.unit() - 0.3f);
  probes.links = SparseLinks(d.clusterCount);
  for (uint32_t r = 0; r < 5 * probes.bins; ++r) {
    cols.clear();
    w.clear();
    for (uint32_t c = rng.below(4); c < d.clusterCount && r != 4; c += 1 + rng.below(5)) {
      cols.push_back(c);
      w.push_back(0.05f + 0.1f * rng.unit());
    }
    probes.links.appendRow(cols.data(), w.data(), cols.size());
  }
  for (uint32_t k = 0; k < 5 * kProbeSkyCount; ++k) probes.sky.push_back(floatToHalf(rng.unit() - 0.4f));
  for (Source& s : d.sources)
    for (uint32_t k = 0; k < 5 * kShCount; ++k) s.probeTransfer.push_back(rng.unit() - 0.2f);
  EXPECT_EQ(d.validate(), "");
  return d;
}

// makeScene with two reflection probes of 2² and 4² texels a face and two bounces: overlapping
// turned boxes around (0.5, 0.5, 0.5) (the second more important, fading in there, with a
// projection box of its own), whose capture rays hit random points of the scene's materials and atlases facing the
// probe, a quarter of them missing (the sky).
TransportData withReflections(TransportData d, uint64_t seed = 11) {
  Rng rng{seed};
  ReflectionTransport& r = d.reflections;
  r.bounces = 2;
  for (const MaterialParams& m : d.materials) r.bakedAlbedo.push_back(m.albedo);
  for (uint32_t side : {2u, 4u}) {
    ReflectionProbeCapture c;
    c.name = "probe" + std::to_string(side);
    c.resolution = side;
    c.firstHit = r.hits.size();
    c.box.centre = glm::vec3(0.3f + 0.4f * rng.unit(), 0.3f + 0.4f * rng.unit(), 0.5f);
    c.box.axes = glm::mat3(glm::vec3(0, 0, 1), glm::vec3(0, 1, 0), glm::vec3(-1, 0, 0));
    c.box.halfSize = glm::vec3(1.0f + rng.unit(), 2.0f, 1.5f);
    c.box.blendDistance = 0.8f;
    c.box.importance = int(side);
    c.box.capturePosition = c.box.centre + glm::vec3(0.1f);
    if (side == 4) {
      // Smaller, so that (0.5, 0.5, 0.5) lies in its blend region, 0.5 inside its z = 0 face:
      // the two probes share that point.
      c.box.centre = glm::vec3(0.5f, 0.5f, 1.0f);
      c.box.halfSize = glm::vec3(1.0f);
      c.box.capturePosition = c.box.centre + glm::vec3(0.1f);
      c.box.projectionCentre = c.box.centre - glm::vec3(0.2f);
      c.box.projectionHalfSize = c.box.halfSize * 0.5f;
    }
    r.probes.push_back(c);
    for (int face = 0; face < kCubeFaceCount; ++face)
      for (uint32_t y = 0; y < side; ++y)
        for (uint32_t x = 0; x < side; ++x) {
          ReflectionHit h;
          if (rng.below(4) != 0) {
            const glm::vec3 ray = cubemapTexelDirection(face, int(x), int(y), int(side));
            const glm::vec3 normal = glm::normalize(
                -ray + 0.5f * glm::vec3(rng.unit() - 0.5f, rng.unit() - 0.5f, rng.unit() - 0.5f));
            h.material = rng.below(uint32_t(d.materials.size()));
            h.atlas = uint16_t(rng.below(uint32_t(d.atlases.size())));
            h.roughness = floatToHalf(rng.unit());
            h.lightmapUv = glm::vec2(rng.unit(), rng.unit());
            for (int k = 0; k < 3; ++k) {
              h.diffuse[k] = floatToHalf(0.8f * rng.unit());
              h.emission[k] = floatToHalf(rng.below(2) ? 1.0f : 0.0f);
              h.f0[k] = floatToHalf(0.04f + 0.9f * rng.unit());
              h.normal[k] = floatToHalf(normal[k]);
            }
            h.distance = 0.5f + rng.unit();
          }
          r.hits.push_back(h);
        }
  }
  EXPECT_EQ(d.validate(), "");
  return d;
}

std::unique_ptr<Runtime> make(TransportData d) {
  std::string error;
  auto rt = Runtime::fromData(std::move(d), &error);
  EXPECT_TRUE(rt) << error;
  return rt;
}

std::vector<glm::vec3> texels(const Runtime& rt) {
  std::vector<glm::vec3> t(size_t(rt.texelCount()));
  rt.readTexels(t.data());
  return t;
}

std::vector<std::vector<glm::vec3>> atlases(const Runtime& rt) {
  std::vector<std::vector<glm::vec3>> out(size_t(rt.atlasCount()));
  for (int a = 0; a < rt.atlasCount(); ++a) EXPECT_TRUE(rt.readAtlas(a, out[size_t(a)]));
  return out;
}

// What baker/src/bake.cpp does with a transport: solve, gather, sum, resolve.
std::vector<std::vector<glm::vec3>> bake(const TransportData& d, const SolveOptions& options) {
  Solver solver(d);
  solver.solve(options);
  std::vector<glm::vec3> direct, indirect;
  solver.gatherTexels(direct, indirect);
  std::vector<glm::vec3> values(direct.size());
  for (size_t t = 0; t < values.size(); ++t) values[t] = direct[t] + indirect[t];
  std::vector<std::vector<glm::vec3>> images;
  for (const AtlasLayout& layout : d.atlases) {
    images.emplace_back();
    resolveAtlas(layout, values, images.back());
  }
  return images;
}

bool bitEqual(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::vec3)) == 0;
}
bool bitEqual(const std::vector<std::vector<glm::vec3>>& a,
              const std::vector<std::vector<glm::vec3>>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (!bitEqual(a[i], b[i])) return false;
  return true;
}

float maxComponent(const std::vector<glm::vec3>& v) {
  float m = 0.0f;
  for (const glm::vec3& x : v) m = std::max({m, std::abs(x.x), std::abs(x.y), std::abs(x.z)});
  return m;
}

// |a - b| within rel of b per component, plus a floor against the largest value.
void expectNear(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b, float rel,
                const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  const float floor = 1e-6f * maxComponent(b);
  for (size_t t = 0; t < a.size(); ++t)
    for (int c = 0; c < 3; ++c)
      ASSERT_LE(std::abs(a[t][c] - b[t][c]), rel * std::abs(b[t][c]) + floor)
          << what << ": texel " << t << " channel " << c << ": " << a[t][c] << " vs " << b[t][c];
}

UpdateOptions scratch(int bounces, float tolerance = 1e-3f) {
  UpdateOptions o;
  o.maxBounces = bounces;
  o.tolerance = tolerance;
  o.fromScratch = true;
  return o;
}

// No sky and no emission: the texels are linear in the lights alone.
std::unique_ptr<Runtime> lightsOnly(uint32_t scale = 1) {
  auto rt = make(makeScene(scale));
  rt->setSky(glm::vec3(0.0f));
  rt->setEmission("lamp", glm::vec3(0.0f));
  return rt;
}

// ---- Agreement with the bake ------------------------------------------------------------------

TEST(RuntimeApi, FromScratchMatchesTheBakeBitForBit) {
  const TransportData d = makeScene();
  for (int bounces : {0, 1, 5}) {
    auto rt = make(d);
    const UpdateStats s = rt->update(scratch(bounces));
    SolveOptions o;
    o.maxBounces = bounces;
    EXPECT_TRUE(bitEqual(atlases(*rt), bake(d, o))) << bounces << " bounces";
    if (bounces > 0) EXPECT_EQ(s.bounces, bounces);
    else EXPECT_TRUE(s.converged);
  }
}

TEST(RuntimeApi, RelitFromScratchEqualsAFreshRuntimeAndBakeWithTheSettingsBakedIn) {
  TransportData changed = makeScene();
  auto rt = make(changed);
  rt->update();  // a warm solution with the old settings, to be thrown away
  ASSERT_TRUE(rt->setLightColor("key", glm::vec3(0.2f, 1.0f, 0.3f)));
  ASSERT_TRUE(rt->setLightIntensity(1, 7.0f));
  ASSERT_TRUE(rt->setBounceIntensity("key", 2.0f));
  ASSERT_TRUE(rt->setLightEnabled("rim", false));
  ASSERT_TRUE(rt->setAlbedo("wall", glm::vec3(0.2f, 0.5f, 0.9f)));
  ASSERT_TRUE(rt->setEmission("lamp", glm::vec3(1.0f, 8.0f, 2.0f)));
  ASSERT_TRUE(rt->setSky(glm::vec3(0.4f, 0.1f, 0.2f)));
  ASSERT_TRUE(rt->setIndirectIntensity(1.5f));
  rt->update(scratch(0, 1e-4f));

  // The same settings written straight into the transport (key, lamp, fill, rim).
  changed.sources[0].color = glm::vec3(0.2f, 1.0f, 0.3f);
  changed.sources[2].intensity = 7.0f;
  changed.sources[0].bounceIntensity = 2.0f;
  changed.sources[3].enabled = false;
  changed.materials[1].albedo = glm::vec3(0.2f, 0.5f, 0.9f);
  changed.materials[2].emission = glm::vec3(1.0f, 8.0f, 2.0f);
  constantSkySh(glm::vec3(0.4f, 0.1f, 0.2f), changed.skySh);
  changed.indirectIntensity = 1.5f;
  auto fresh = make(changed);
  fresh->update(scratch(0, 1e-4f));
  EXPECT_TRUE(bitEqual(atlases(*rt), atlases(*fresh)));
  EXPECT_TRUE(bitEqual(texels(*rt), texels(*fresh)));
  SolveOptions o;
  o.tolerance = 1e-4f;
  EXPECT_TRUE(bitEqual(atlases(*rt), bake(changed, o)));
  // data() shows the applied settings.
  EXPECT_EQ(rt->data().sources[3].enabled, false);
  EXPECT_EQ(rt->data().materials[2].emission, glm::vec3(1.0f, 8.0f, 2.0f));
}

// ---- Linearity and the settings' meaning ------------------------------------------------------

TEST(RuntimeApi, ScalingEveryLightScalesEveryTexel) {
  auto base = lightsOnly();
  base->update(scratch(20));
  auto scaled = lightsOnly();
  const float k = 2.5f;
  for (int i = 0; i < scaled->lightCount(); ++i)
    ASSERT_TRUE(scaled->setLightIntensity(i, k * scaled->lightIntensity(i)));
  scaled->update(scratch(20));
  std::vector<glm::vec3> expected = texels(*base);
  ASSERT_GT(maxComponent(expected), 0.0f);
  for (glm::vec3& v : expected) v *= k;
  expectNear(texels(*scaled), expected, 1e-5f, "k x lights");
}

TEST(RuntimeApi, SingleLightSolvesAddUpToTheTwoLightSolve) {
  auto only = [](const char* on) {
    auto rt = lightsOnly();
    for (int i = 0; i < rt->lightCount(); ++i) rt->setLightEnabled(i, rt->lightName(i) == on);
    rt->update(scratch(20));
    return texels(*rt);
  };
  auto both = lightsOnly();
  both->setLightEnabled("rim", false);
  both->update(scratch(20));
  std::vector<glm::vec3> sum = only("key"), fill = only("fill");
  for (size_t t = 0; t < sum.size(); ++t) sum[t] += fill[t];
  expectNear(texels(*both), sum, 1e-5f, "key + fill");
}

TEST(RuntimeApi, DisabledLightEqualsZeroIntensity) {
  auto disabled = make(makeScene());
  auto zero = make(makeScene());
  ASSERT_TRUE(disabled->setLightEnabled("fill", false));
  ASSERT_TRUE(zero->setLightIntensity("fill", 0.0f));
  disabled->update(scratch(0));
  zero->update(scratch(0));
  EXPECT_TRUE(bitEqual(atlases(*disabled), atlases(*zero)));
  EXPECT_FALSE(disabled->lightEnabled(disabled->findLight("fill")));
}

TEST(RuntimeApi, ZeroBounceIntensityLeavesOnlyTheLightsDirectLight) {
  auto rt = lightsOnly();
  const int key = rt->findLight("key");
  for (int i = 0; i < rt->lightCount(); ++i) rt->setLightEnabled(i, i == key);
  ASSERT_TRUE(rt->setBounceIntensity(key, 0.0f));
  rt->update(scratch(20));
  const Source& s = rt->data().sources[0];
  ASSERT_EQ(s.name, "key");
  const glm::vec3 scale = s.color * s.intensity;
  const std::vector<glm::vec3> t = texels(*rt);
  for (size_t i = 0; i < t.size(); ++i) ASSERT_EQ(t[i], scale * s.texelTransfer[i]) << i;
  // With bounces the same light does add indirect light.
  rt->setBounceIntensity(key, 1.0f);
  rt->update(scratch(20));
  const std::vector<glm::vec3> bounced = texels(*rt);
  float extra = 0.0f;
  for (size_t i = 0; i < t.size(); ++i) extra = std::max(extra, bounced[i].x - t[i].x);
  EXPECT_GT(extra, 1e-3f);
}

TEST(RuntimeApi, IndirectIntensityScalesBouncedLightWithoutAPass) {
  auto rt = make(makeScene());
  rt->update(scratch(0));
  const std::vector<glm::vec3> one = texels(*rt);
  rt->setIndirectIntensity(0.0f);
  EXPECT_EQ(rt->update(scratch(-1)).bounces, 0);  // reset, no pass: direct light only
  rt->setIndirectIntensity(1.0f);
  EXPECT_EQ(rt->update(UpdateOptions{-1}).bounces, 0);
  const std::vector<glm::vec3> direct = texels(*rt);
  rt->setIndirectIntensity(3.0f);
  rt->update(scratch(0));
  const std::vector<glm::vec3> three = texels(*rt);
  std::vector<glm::vec3> expected(one.size());
  for (size_t t = 0; t < one.size(); ++t) expected[t] = direct[t] + 3.0f * (one[t] - direct[t]);
  expectNear(three, expected, 1e-5f, "indirect x3");
  EXPECT_GT(maxComponent(three), maxComponent(one));
}

TEST(RuntimeApi, EmissionDrivesTheEmissiveSource) {
  auto rt = lightsOnly();
  for (int i = 0; i < rt->lightCount(); ++i) rt->setLightEnabled(i, false);
  rt->update(scratch(5));
  EXPECT_EQ(maxComponent(texels(*rt)), 0.0f);
  ASSERT_TRUE(rt->setEmission("lamp", glm::vec3(2.0f)));
  rt->update(scratch(5));
  const std::vector<glm::vec3> two = texels(*rt);
  ASSERT_TRUE(rt->setEmission("lamp", glm::vec3(4.0f)));
  rt->update(scratch(5));
  std::vector<glm::vec3> expected = two;
  for (glm::vec3& v : expected) v *= 2.0f;
  EXPECT_GT(maxComponent(two), 0.0f);
  expectNear(texels(*rt), expected, 1e-5f, "emission x2");
}

// ---- Warm starts and budgets ------------------------------------------------------------------

TEST(RuntimeApi, WarmStartConvergesToTheColdAnswer) {
  auto warm = make(makeScene());
  warm->update(scratch(0, 1e-6f));
  warm->setLightColor("key", glm::vec3(1.0f, 0.2f, 0.1f));
  warm->setAlbedo("floor", glm::vec3(0.3f));
  UpdateOptions o;
  o.tolerance = 1e-6f;
  const UpdateStats ws = warm->update(o);
  EXPECT_TRUE(ws.converged);

  auto cold = make(makeScene());
  cold->setLightColor("key", glm::vec3(1.0f, 0.2f, 0.1f));
  cold->setAlbedo("floor", glm::vec3(0.3f));
  const UpdateStats cs = cold->update(scratch(0, 1e-6f));
  EXPECT_LE(ws.bounces, cs.bounces);
  expectNear(texels(*warm), texels(*cold), 1e-4f, "warm vs cold");

  // Nothing changed: one more warm pass barely moves it.
  const UpdateStats again = warm->update(UpdateOptions{1});
  EXPECT_EQ(again.bounces, 1);
  EXPECT_LT(again.change, 1e-5f);
}

TEST(RuntimeApi, TimeBudgetRunsAtLeastOnePass) {
  auto rt = make(makeScene());
  UpdateOptions o;
  o.timeBudgetMs = 1e-9;  // smaller than any pass
  o.fromScratch = true;
  const UpdateStats s = rt->update(o);
  EXPECT_EQ(s.bounces, 1);
  EXPECT_FALSE(s.converged);
  EXPECT_GT(s.milliseconds, 0.0);
  o.timeBudgetMs = 1e6;  // ample
  EXPECT_TRUE(rt->update(o).converged);
}

TEST(RuntimeApi, BlackBeforeTheFirstUpdate) {
  auto rt = make(makeScene());
  EXPECT_EQ(maxComponent(texels(*rt)), 0.0f);
  for (const auto& image : atlases(*rt)) EXPECT_EQ(maxComponent(image), 0.0f);
  rt->update();
  EXPECT_GT(maxComponent(texels(*rt)), 0.0f);
}

// Heap allocations made on this thread by f().
template <class F>
long allocationsOf(F&& f) {
  gAllocations = 0;
  gCountAllocations = true;
  f();
  gCountAllocations = false;
  return gAllocations.load();
}

// Neither update() nor the Solver calls it makes allocate once the runtime is loaded: an
// engine calls them every frame.
TEST(RuntimeApi, UpdateDoesNotAllocate) {
  if (!AFTERGLOW_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are not counted under sanitizers";
  const TransportData d = makeScene();
  Solver solver(d);
  glm::vec3 scratchTexels[64];
  ASSERT_LE(d.texelCount, 64u);
  EXPECT_EQ(allocationsOf([&] { solver.iterate(); }), 0);
  EXPECT_EQ(allocationsOf([&] { solver.directTexels(scratchTexels); }), 0);
  EXPECT_EQ(allocationsOf([&] { solver.indirectTexels(scratchTexels); }), 0);

  auto rt = make(makeScene());
  rt->update();
  std::vector<glm::vec3> image(size_t(rt->atlasWidth(0) * rt->atlasHeight(0)));
  const std::string key = "key";
  const long counted = allocationsOf([&] {
    for (int frame = 0; frame < 5; ++frame) {
      rt->setLightColor(key, glm::vec3(1.0f, 0.1f * float(frame), 0.5f));
      rt->setAlbedo(0, glm::vec3(0.1f * float(frame)));
      rt->setSky(glm::vec3(0.01f * float(frame)));
      rt->setEmission(2, glm::vec3(float(frame)));
      rt->update(UpdateOptions{1});  // direct light changed
      rt->update(scratch(0));        // nothing changed
      rt->readAtlas(0, image);
      rt->readAtlas(1, &image[0].x);
    }
  });
  EXPECT_EQ(counted, 0);
}

// ---- Lookups and refusals ---------------------------------------------------------------------

TEST(RuntimeApi, LookupsAndRefusals) {
  auto rt = make(makeScene());
  EXPECT_EQ(rt->lightCount(), 3);
  EXPECT_EQ(rt->lightName(0), "key");
  EXPECT_EQ(rt->lightName(1), "fill");  // the emissive source between them is not a light
  EXPECT_EQ(rt->findLight("rim"), 2);
  EXPECT_EQ(rt->findLight("lamp"), -1);
  EXPECT_EQ(rt->findLight(""), -1);
  EXPECT_EQ(rt->lightName(3), "");
  EXPECT_EQ(rt->materialCount(), 3);
  EXPECT_EQ(rt->findMaterial("lamp"), 2);
  EXPECT_EQ(rt->findMaterial("nope"), -1);
  EXPECT_EQ(rt->materialName(-1), "");

  EXPECT_FALSE(rt->setLightColor("nope", glm::vec3(1.0f)));
  EXPECT_FALSE(rt->setLightColor(3, glm::vec3(1.0f)));
  EXPECT_FALSE(rt->setLightColor(-1, glm::vec3(1.0f)));
  EXPECT_FALSE(rt->setLightIntensity("nope", 1.0f));
  EXPECT_FALSE(rt->setBounceIntensity("nope", 1.0f));
  EXPECT_FALSE(rt->setLightEnabled("nope", false));
  EXPECT_FALSE(rt->setAlbedo("nope", glm::vec3(0.5f)));
  EXPECT_FALSE(rt->setEmission("nope", glm::vec3(0.5f)));
  EXPECT_FALSE(rt->setLightIntensity(0, std::nanf("")));
  EXPECT_FALSE(rt->setLightColor(0, glm::vec3(INFINITY, 0.0f, 0.0f)));
  EXPECT_FALSE(rt->setSky(glm::vec3(NAN)));
  EXPECT_FALSE(rt->setIndirectIntensity(NAN));
  EXPECT_EQ(rt->lightIntensity(0), 1.5f);  // unchanged by the refusals

  // Emission only for materials with an emissive source at bake time.
  EXPECT_TRUE(rt->canSetEmission(2));
  EXPECT_FALSE(rt->canSetEmission(0));
  EXPECT_FALSE(rt->canSetEmission(3));
  EXPECT_FALSE(rt->setEmission("floor", glm::vec3(1.0f)));
  EXPECT_EQ(rt->emission(0), glm::vec3(0.0f));
  EXPECT_TRUE(rt->setEmission("lamp", glm::vec3(1.0f, 2.0f, 3.0f)));
  EXPECT_EQ(rt->emission(2), glm::vec3(1.0f, 2.0f, 3.0f));

  EXPECT_TRUE(rt->setLightColor("fill", glm::vec3(0.5f)));
  EXPECT_EQ(rt->lightColor(1), glm::vec3(0.5f));
  glm::vec3 sh[kShCount];
  rt->setSky(glm::vec3(1.0f));
  rt->skySh(sh);
  EXPECT_GT(sh[0].x, 3.0f);
  EXPECT_EQ(sh[1], glm::vec3(0.0f));

  EXPECT_EQ(rt->atlasCount(), 2);
  EXPECT_EQ(rt->atlasWidth(0), 9);
  EXPECT_EQ(rt->atlasHeight(1), 4);
  EXPECT_EQ(rt->atlasWidth(2), 0);
  std::vector<glm::vec3> image;
  EXPECT_FALSE(rt->readAtlas(2, image));
}

TEST(RuntimeApi, InvalidDataIsRefused) {
  TransportData d = makeScene();
  d.clusterMaterial[3] = 9;
  std::string error;
  EXPECT_EQ(Runtime::fromData(std::move(d), &error), nullptr);
  EXPECT_NE(error.find("cluster 3"), std::string::npos) << error;
}

// ---- Files ------------------------------------------------------------------------------------

std::string tempPath(const char* name) {
  return (std::filesystem::path(::testing::TempDir()) / name).string();
}

TEST(RuntimeApi, LoadingAMissingFileNamesIt) {
  const std::string path = tempPath("afterglow_runtime_api_missing.agt");
  std::filesystem::remove(path);
  std::string error;
  EXPECT_EQ(Runtime::load(path, &error), nullptr);
  EXPECT_EQ(error.rfind(path, 0), 0u) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos);
}

TEST(RuntimeApi, SavedAndLoadedTransportRelightsLikeTheOriginal) {
  const TransportData d = makeScene();
  const std::string path = tempPath("afterglow_runtime_api_roundtrip.agt");
  std::string error;
  ASSERT_TRUE(saveTransport(d, path, &error)) << error;
  auto loaded = Runtime::load(path, &error);
  std::filesystem::remove(path);
  ASSERT_TRUE(loaded) << error;
  auto inMemory = make(d);
  for (Runtime* rt : {loaded.get(), inMemory.get()}) {
    rt->setLightColor("rim", glm::vec3(0.1f, 0.9f, 0.4f));
    rt->setEmission("lamp", glm::vec3(3.0f));
    rt->update();
    rt->update(UpdateOptions{2});
  }
  EXPECT_TRUE(bitEqual(atlases(*loaded), atlases(*inMemory)));
  EXPECT_TRUE(bitEqual(texels(*loaded), texels(*inMemory)));
}

// ---- Threads ----------------------------------------------------------------------------------

// One thread relights and updates; another reads atlases and texels throughout. Every frame is
// the base frame times an integer k (all lights scaled alike, no sky or emission), so a read
// that mixed two frames would show two different ratios.
TEST(RuntimeApi, ReadsSeeWholeFramesWhileUpdating) {
  auto rt = lightsOnly(20);  // big enough that a torn read would be caught
  std::vector<glm::vec3> colors;
  for (int i = 0; i < rt->lightCount(); ++i) colors.push_back(rt->lightColor(i));
  rt->update(scratch(4));
  const std::vector<std::vector<glm::vec3>> base = atlases(*rt);
  const std::vector<glm::vec3> baseTexels = texels(*rt);

  // The k of a frame, or -1 when its pixels disagree.
  auto frameScale = [](const std::vector<glm::vec3>& image, const std::vector<glm::vec3>& ref) {
    const float floor = 1e-3f * maxComponent(ref);
    int k = 0;
    for (size_t p = 0; p < image.size(); ++p)
      for (int c = 0; c < 3; ++c) {
        if (std::abs(ref[p][c]) <= floor) continue;
        const float ratio = image[p][c] / ref[p][c];
        const int rounded = int(std::lround(ratio));
        if (std::abs(ratio - float(rounded)) > 1e-4f * float(rounded) || rounded < 1) return -1;
        if (k == 0) k = rounded;
        if (rounded != k) return -1;
      }
    return k;
  };

  const int frames = 200;
  std::atomic<bool> done{false};
  std::atomic<int> reads{0}, bad{0};
  std::thread reader([&] {
    std::vector<glm::vec3> image, t(baseTexels.size());
    int seen = 0;
    while (!done.load() || seen < 5) {
      for (int a = 0; a < rt->atlasCount(); ++a) {
        rt->readAtlas(a, image);
        if (frameScale(image, base[size_t(a)]) < 0) ++bad;
      }
      rt->readTexels(t.data());
      if (frameScale(t, baseTexels) < 0) ++bad;
      ++reads;
      ++seen;
    }
  });
  for (int f = 0; f < frames; ++f) {
    const float k = float(1 + f % 5);
    for (int i = 0; i < rt->lightCount(); ++i) rt->setLightColor(i, k * colors[size_t(i)]);
    rt->update(scratch(4));
  }
  done = true;
  reader.join();
  EXPECT_EQ(bad.load(), 0) << "of " << reads.load() << " reads";
  EXPECT_GE(reads.load(), 5);
}

// ---- Light probes -----------------------------------------------------------------------------

// A probe's SH from the runtime equals the transfer written out by hand: the sources scaled by
// colour × intensity (emission for the lamp), the sky through K, and the regions' rows of links
// over the clusters' reflected light, scaled by the indirect intensity.
// Both kernels of the probes' refresh (AVX2 where the CPU has it, and the baseline's, which
// AFTERGLOW_NO_AVX2 selects) against the transfer summed by hand.
TEST(RuntimeApi, ProbeShIsTheTransferSummedByHand) {
  TransportData d = makeScene();
  d.indirectIntensity = 0.75f;
  for (const bool baseline : {false, true}) {
    SCOPED_TRACE(baseline ? "baseline kernel" : "the CPU's best kernel");
    if (baseline) setenv("AFTERGLOW_NO_AVX2", "1", 1);
    Solver solver(d);
    unsetenv("AFTERGLOW_NO_AVX2");
    solver.solve({4, 0.0f});
    std::vector<ShL2> sh(d.probes.count());
    solver.probeRadiance(0, sh.size(), sh.data());
    const std::vector<glm::vec3>& r = solver.clusterReflected();
    for (size_t p = 0; p < d.probes.count(); ++p) {
      for (int i = 0; i < kShCount; ++i) {
        glm::dvec3 want(0.0);
        for (const Source& s : d.sources) {
          const glm::vec3 scale =
              s.kind == SourceKind::Emissive ? d.materials[s.material].emission : s.color * s.intensity;
          want += glm::dvec3(scale) * double(s.probeTransfer[p * kShCount + size_t(i)]);
        }
        for (int j = 0; j < kShCount; ++j)
          want += glm::dvec3(d.skySh[j]) *
                  double(halfToFloat(d.probes.sky[p * kProbeSkyCount + size_t(probeSkyIndex(i, j))]));
        for (uint32_t b = 0; b < d.probes.bins; ++b) {
          const size_t row = p * d.probes.bins + b;
          glm::dvec3 gathered(0.0);
          for (size_t k = d.probes.links.rowStart[row]; k < d.probes.links.rowStart[row + 1]; ++k)
            gathered += double(d.probes.links.weightAt(row, k)) * glm::dvec3(r[d.probes.links.targetAt(k)]);
          want += 0.75 * double(d.probes.binSh[b * kShCount + size_t(i)]) * gathered;
        }
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(sh[p].c[i][c], want[c], 1e-5 * (1.0 + std::abs(want[c])))
              << "probe " << p << " coefficient " << i;
      }
    }
  }
  // Sampled at a probe, the runtime returns that probe; between them, a convex mix.
  auto rt = make(d);
  rt->update(scratch(4));
  ShL2 own;
  ASSERT_TRUE(rt->probeSh(4, &own));
  int hint = 0;
  const ShL2 at = rt->sampleProbes(glm::vec3(1, 1, 1), &hint);
  EXPECT_EQ(hint, 1);
  for (int i = 0; i < kShCount; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(at.c[i][c], own.c[i][c], 1e-5f * (1.0f + std::abs(own.c[i][c])));
  EXPECT_FALSE(rt->probeSh(5, &own));
  EXPECT_EQ(rt->probePosition(9), glm::vec3(0.0f));
}

// ---- C API ------------------------------------------------------------------------------------

TEST(RuntimeApi, CApiMatchesTheCppApi) {
  const std::string path = tempPath("afterglow_runtime_api_c.agt");
  std::string error;
  ASSERT_TRUE(saveTransport(makeScene(), path, &error)) << error;

  // The same calls as afterglow_test_c_relight (c_api_compile.c) makes, through C++.
  auto rt = Runtime::load(path, &error);
  ASSERT_TRUE(rt) << error;
  const int fill = rt->findLight("fill");
  rt->setLightColor(fill, glm::vec3(0.25f, 0.5f, 2.0f));
  rt->setLightIntensity(fill, 3.0f);
  rt->setBounceIntensity(0, 0.5f);
  rt->setLightEnabled(2, false);
  rt->setSky(glm::vec3(0.1f, 0.2f, 0.3f));
  rt->setAlbedo("wall", glm::vec3(0.3f, 0.4f, 0.5f));
  rt->setEmission("lamp", glm::vec3(1.0f, 2.0f, 3.0f));
  rt->setIndirectIntensity(1.25f);
  rt->update(scratch(4));
  std::vector<float> expected(size_t(rt->atlasWidth(0) * rt->atlasHeight(0) * 3));
  ASSERT_TRUE(rt->readAtlas(0, expected.data()));

  std::vector<float> fromC(expected.size(), -1.0f);
  char err[256] = "untouched";
  EXPECT_EQ(afterglow_test_c_relight(path.c_str(), fromC.data(), fromC.size(), err, sizeof err), 1)
      << err;
  std::filesystem::remove(path);
  EXPECT_EQ(std::memcmp(fromC.data(), expected.data(), expected.size() * sizeof(float)), 0);

  // Errors name the file, truncated to the buffer.
  char small[12];
  EXPECT_EQ(afterglow_test_c_load_fails(path.c_str(), small, sizeof small), 1);
  EXPECT_EQ(std::string(small), path.substr(0, sizeof small - 1));
  char full[512];
  EXPECT_EQ(afterglow_test_c_load_fails(path.c_str(), full, sizeof full), 1);
  EXPECT_EQ(std::string(full).rfind(path, 0), 0u) << full;
  EXPECT_EQ(afterglow_runtime_load(nullptr, full, sizeof full), nullptr);
  // The light probes through C: the same SH, positions and irradiance as through C++.
  {
    ASSERT_TRUE(saveTransport(makeScene(), path, &error)) << error;
    auto probes = Runtime::load(path, &error);
    ASSERT_TRUE(probes) << error;
    probes->update(scratch(4));
    float fromCProbes[27 * 3 + 6] = {};
    EXPECT_EQ(afterglow_test_c_probes(path.c_str(), fromCProbes), 1);
    std::filesystem::remove(path);
    ShL2 own;
    ASSERT_TRUE(probes->probeSh(2, &own));
    const ShL2 mid = probes->sampleProbes(glm::vec3(0.25f, 0.25f, 0.25f));
    const glm::vec3 e = Runtime::evaluateIrradiance(mid, glm::normalize(glm::vec3(1, 2, 3)));
    for (int i = 0; i < kShCount; ++i)
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(fromCProbes[3 * i + c], own.c[i][c]);
        EXPECT_EQ(fromCProbes[27 + 3 * i + c], mid.c[i][c]);
      }
    EXPECT_EQ(fromCProbes[54], 0.0f);  // probe 2's position (0, 1, 0)
    EXPECT_EQ(fromCProbes[55], 1.0f);
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(fromCProbes[57 + 3 + c], e[c]);
    const glm::vec3 lit = Runtime::evaluateIrradiance(
        probes->sampleProbeLighting(glm::vec3(0.25f, 0.25f, 0.25f)), glm::normalize(glm::vec3(1, 2, 3)));
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(fromCProbes[63 + c], lit[c]);
  }
  EXPECT_EQ(afterglow_runtime_light_count(nullptr), 0);
  EXPECT_EQ(afterglow_runtime_update(nullptr, nullptr, nullptr), 0);
}

// The reflection probe calls through C: the same cubemaps (equal to the bake's own
// solveReflectionProbes from the same lightmaps), probes and weights, boxes and box projection
// as through C++, and weights that sum to 1 everywhere.
TEST(RuntimeApi, CApiReflectionProbesMatchTheCppApi) {
  const std::string path = tempPath("afterglow_runtime_api_c_reflections.agt");
  std::string error;
  ASSERT_TRUE(saveTransport(withReflections(makeScene()), path, &error)) << error;
  auto rt = Runtime::load(path, &error);
  ASSERT_TRUE(rt) << error;
  rt->setSky(glm::vec3(0.1f, 0.2f, 0.3f));
  const UpdateStats stats = rt->update(scratch(4));
  EXPECT_EQ(stats.reflectionPasses, 6);

  float cube[51], projected[3] = {};
  int probes[4] = {-1, -1, -1, -1}, count = 0;
  float weights[4] = {};
  AfterglowReflectionProbeBox box{};
  EXPECT_EQ(afterglow_test_c_reflections(path.c_str(), cube, projected, probes, weights, &count,
                                         &box), 1);

  // The cubemaps: C's equal C++'s, bit for bit, which equal the bake's function's.
  float want[48], wantMip1[3];
  ASSERT_TRUE(rt->readCubemap(2, 0, 3, want));
  ASSERT_TRUE(rt->readCubemap(1, 1, 0, wantMip1));
  EXPECT_EQ(std::memcmp(cube, want, sizeof want), 0);
  EXPECT_EQ(std::memcmp(cube + 48, wantMip1, sizeof wantMip1), 0);
  const std::vector<CubemapChain> baked =
      solveReflectionProbes(rt->data(), atlases(*rt), rt->dfgTable(), kDfgSize);
  ASSERT_EQ(baked.size(), 3u);
  for (int k = 0; k < 16; ++k)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(want[3 * k + c], baked[2][0].texels[size_t(3 * 16 + k)][c]) << k;
  float sum = 0.0f;
  for (int c = 0; c < 3; ++c) sum += std::abs(want[c]) + std::abs(wantMip1[c]);
  EXPECT_GT(sum, 0.0f);  // not the black of no update

  // Probes and weights at the point.
  const std::vector<ProbeWeight> at = rt->reflectionProbesAt(glm::vec3(0.5f));
  ASSERT_EQ(count, int(at.size()));
  ASSERT_GE(count, 2);  // inside both boxes: not the sky alone
  for (int i = 0; i < count; ++i) {
    EXPECT_EQ(probes[i], at[size_t(i)].probe);
    EXPECT_EQ(weights[i], at[size_t(i)].weight);
  }

  // Probe 2's box field by field, and probe 1's box projection.
  const ReflectionProbeBox& b = *rt->reflectionProbeBox(2);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(box.centre[a], b.centre[a]);
    EXPECT_EQ(box.half_size[a], b.halfSize[a]);
    EXPECT_EQ(box.capture_position[a], b.capturePosition[a]);
    EXPECT_EQ(box.projection_centre[a], b.projectionCentre[a]);
    EXPECT_EQ(box.projection_half_size[a], b.projectionHalfSize[a]);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(box.axes[3 * k + a], b.axes[k][a]) << k << a;
  }
  EXPECT_EQ(box.blend_distance, b.blendDistance);
  EXPECT_EQ(box.importance, b.importance);
  EXPECT_EQ(box.box_projection, b.boxProjection ? 1 : 0);
  const glm::vec3 p = boxProject(*rt->reflectionProbeBox(1), glm::vec3(0.5f), glm::vec3(1, 2, -3));
  for (int a = 0; a < 3; ++a) EXPECT_EQ(projected[a], p[a]);
  EXPECT_NEAR(glm::length(p), 1.0f, 1e-5f);  // projected: normalised

  // Through the C handle: weights ≥ 0 summing to 1 at random points in and around the boxes,
  // and the C box projection of every box equal to C++'s.
  AfterglowRuntime* c = afterglow_runtime_load(path.c_str(), nullptr, 0);
  ASSERT_NE(c, nullptr);
  Rng rng{3};
  int blended = 0;
  for (int k = 0; k < 500; ++k) {
    const glm::vec3 q(4.0f * rng.unit() - 1.5f, 4.0f * rng.unit() - 1.5f, 4.0f * rng.unit() - 1.5f);
    int ids[3];
    float w[3];
    const int n = afterglow_runtime_reflection_probes_at(c, q.x, q.y, q.z, ids, w, 3);
    ASSERT_GE(n, 1);
    ASSERT_LE(n, 3);
    blended += n > 1;
    double total = 0.0;
    for (int i = 0; i < n; ++i) {
      EXPECT_GE(ids[i], 0);
      EXPECT_LT(ids[i], 3);
      EXPECT_GT(w[i], 0.0f);
      total += double(w[i]);
    }
    EXPECT_NEAR(total, 1.0, 1e-6) << "at " << q.x << ", " << q.y << ", " << q.z;
    const glm::vec3 dir(rng.unit() - 0.5f, rng.unit() - 0.5f, rng.unit() - 0.5f);
    for (int probe = 1; probe <= 2; ++probe) {
      AfterglowReflectionProbeBox cb;
      ASSERT_EQ(afterglow_runtime_reflection_probe_box(c, probe, &cb), 1);
      float out[3];
      ASSERT_EQ(afterglow_runtime_box_project(&cb, q.x, q.y, q.z, dir.x, dir.y, dir.z, out), 1);
      const glm::vec3 e = boxProject(*rt->reflectionProbeBox(probe), q, dir);
      for (int a = 0; a < 3; ++a) EXPECT_EQ(out[a], e[a]);
    }
  }
  EXPECT_GT(blended, 50);  // the points did fall in the boxes
  // The DFG table as C++ has it.
  std::vector<float> dfg(size_t(2 * kDfgSize * kDfgSize));
  ASSERT_EQ(afterglow_runtime_read_dfg(c, dfg.data(), dfg.size()), 1);
  for (size_t i = 0; i < rt->dfgTable().size(); ++i) {
    ASSERT_EQ(dfg[2 * i], rt->dfgTable()[i].x);
    ASSERT_EQ(dfg[2 * i + 1], rt->dfgTable()[i].y);
  }
  // A budgeted round through C runs at least one unit and reports it.
  AfterglowUpdateStats cs{};
  ASSERT_EQ(afterglow_runtime_update_reflection_probes(c, -1, 1e-6, &cs), 1);
  EXPECT_EQ(cs.reflection_passes, 1);
  afterglow_runtime_free(c);
  std::filesystem::remove(path);

  // Without reflection probes: no probes, no table, the sky alone everywhere, and updates that
  // run no reflection passes.
  ASSERT_TRUE(saveTransport(makeScene(), path, &error)) << error;
  AfterglowRuntime* none = afterglow_runtime_load(path.c_str(), nullptr, 0);
  ASSERT_NE(none, nullptr);
  std::filesystem::remove(path);
  EXPECT_EQ(afterglow_runtime_reflection_probe_count(none), 0);
  EXPECT_EQ(afterglow_runtime_reflection_mip_count(none), 0);
  EXPECT_EQ(afterglow_runtime_reflection_face_size(none, 0, 0), 0);
  EXPECT_EQ(afterglow_runtime_dfg_size(none), 0);
  int id = -1;
  float weight = 0.0f;
  EXPECT_EQ(afterglow_runtime_reflection_probes_at(none, 0.0f, 0.0f, 0.0f, &id, &weight, 1), 1);
  EXPECT_EQ(id, 0);
  EXPECT_EQ(weight, 1.0f);
  AfterglowUpdateOptions options;
  afterglow_runtime_default_options(&options);
  options.max_bounces = 1;
  ASSERT_EQ(afterglow_runtime_update(none, &options, &cs), 1);
  EXPECT_EQ(cs.reflection_passes, 0);
  EXPECT_EQ(cs.reflection_milliseconds, 0.0);
  afterglow_runtime_free(none);
}

}  // namespace
}  // namespace afterglow::runtime
