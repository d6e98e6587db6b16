// The transport file (runtime/include/afterglow/runtime/transport_file.h): round trips, every
// kind of damage a file can suffer, semantic checks through validate(), half floats, and the
// load time of a Sponza-sized transport. Links afterglow_runtime alone (no baker).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "afterglow/runtime/transport_file.h"
#include "test_rng.h"

namespace afterglow::runtime {
namespace {

// ---- Synthetic transports --------------------------------------------------------------------

using test::Rng;

struct Shape {
  uint32_t texels = 300, clusters = 40, farClusters = 6, sharedFar = 4, points = 90, backRows = 5;
  uint32_t linksPerRow = 12;
  int atlasSides[3][2] = {{16, 12}, {10, 10}, {7, 5}};
  int lightsWithTexelTransfer = 2;
  bool probes = true;  // four light probes in one tetrahedron, three regions each
  bool reflections = true;  // two reflection probes of 2² and 4² texels a face
};

// Every field populated, and valid (validate() is empty).
TransportData makeTransport(const Shape& s, uint64_t seed = 1) {
  Rng rng{seed};
  TransportData d;
  d.texelCount = s.texels;
  d.clusterCount = s.clusters;
  d.gatherPointCount = s.points;

  uint32_t nextTexel = 0;
  for (const auto& side : s.atlasSides) {
    AtlasLayout a;
    a.width = side[0];
    a.height = side[1];
    const uint32_t pixels = uint32_t(a.width * a.height);
    for (uint32_t p = 0; p < pixels; ++p)
      a.texelOfPixel.push_back(rng.below(5) == 0 ? kNoTexel : (nextTexel++ % s.texels));
    for (uint32_t p = 0; p < pixels; p += 1 + rng.below(7)) {
      a.mixPixel.push_back(p);
      const uint32_t n = rng.below(4);
      for (uint32_t k = 0; k < n; ++k) {
        a.mixTexel.push_back(rng.below(s.texels));
        a.mixWeight.push_back(rng.unit());
      }
      a.mixStart.push_back(uint32_t(a.mixTexel.size()));
    }
    d.atlases.push_back(std::move(a));
  }

  d.materials.push_back({"floor", glm::vec3(0.5f, 0.6f, 0.7f), glm::vec3(0.0f)});
  d.materials.push_back({"", glm::vec3(0.1f), glm::vec3(0.0f)});
  d.materials.push_back({"Mörtel \xe2\x9c\x93", glm::vec3(0.9f, 0.2f, 0.3f), glm::vec3(4, 5, 6)});
  d.materials.push_back({"lamp", glm::vec3(0.8f), glm::vec3(10.0f, 9.0f, 8.0f)});

  for (int i = 0; i < 4; ++i) {
    Source src;
    src.name = i < 2 ? "light " + std::to_string(i) : d.materials[size_t(i)].name;
    src.kind = i < 2 ? SourceKind::Light : SourceKind::Emissive;
    src.material = i < 2 ? 0u : uint32_t(i);
    src.color = glm::vec3(0.1f * float(i + 1), 0.5f, 1.0f - 0.2f * float(i));
    src.intensity = 3.5f + float(i);
    src.bounceIntensity = 0.25f * float(i + 1);
    src.enabled = i != 1;
    if (i < s.lightsWithTexelTransfer || i == 3)
      for (uint32_t t = 0; t < s.texels; ++t) src.texelTransfer.push_back(rng.unit());
    if (i != 2)
      for (uint32_t c = 0; c < s.clusters; ++c) src.clusterTransfer.push_back(rng.unit());
    if (s.probes && i != 1)
      for (uint32_t k = 0; k < 4 * kShCount; ++k) src.probeTransfer.push_back(rng.unit() - 0.5f);
    d.sources.push_back(std::move(src));
  }

  for (uint32_t c = 0; c < s.clusters; ++c) {
    d.clusterMaterial.push_back(rng.below(uint32_t(d.materials.size())));
    d.clusterAlbedoTexture.push_back(glm::vec3(rng.unit(), rng.unit(), rng.unit()));
    d.clusterEmissionTexture.push_back(glm::vec3(rng.unit(), rng.unit(), rng.unit()));
    d.clusterPosition.push_back(glm::vec3(rng.unit(), rng.unit(), rng.unit()) * 10.0f);
  }
  for (uint32_t p = 0; p < s.points; ++p) {
    d.pointPosition.push_back(glm::vec3(rng.unit(), rng.unit(), rng.unit()) * 10.0f);
    d.pointNormal.push_back(glm::normalize(glm::vec3(rng.unit(), rng.unit(), rng.unit()) + 0.1f));
  }

  for (uint32_t f = 0; f < s.farClusters; ++f) {
    const uint32_t first = f * s.clusters / s.farClusters, last = (f + 1) * s.clusters / s.farClusters;
    std::vector<uint32_t> cols;
    std::vector<float> w;
    for (uint32_t c = first; c < last; ++c) {
      cols.push_back(c);
      w.push_back(1.0f / float(last - first));
    }
    d.farClusters.appendRow(cols.data(), w.data(), cols.size());
  }

  const uint32_t rows = s.points + s.backRows;
  std::vector<uint32_t> targets;
  std::vector<float> weights;
  for (uint32_t r = 0; r < s.sharedFar; ++r) {  // far clusters only
    targets.clear();
    weights.clear();
    for (uint32_t t = s.clusters + r % 2; t < s.clusters + s.farClusters; t += 2) {
      targets.push_back(t);
      weights.push_back(0.01f + rng.unit());
    }
    d.sharedFar.appendRow(targets.data(), weights.data(), targets.size());
  }
  for (uint32_t r = 0; r < rows; ++r) {
    targets.clear();
    weights.clear();
    const uint32_t n = rng.below(s.linksPerRow * 2 + 1);
    uint32_t t = rng.below(3);
    for (uint32_t k = 0; k < n && t < s.clusters + s.farClusters + s.sharedFar;
         ++k, t += 1 + rng.below(4)) {
      targets.push_back(t);
      weights.push_back(0.01f + rng.unit());
    }
    d.links.appendRow(targets.data(), weights.data(), targets.size());
  }

  auto sparse = [&](SparseMatrix& m, uint32_t rowCount, uint32_t columns, uint32_t perRow) {
    std::vector<uint32_t> cols;
    std::vector<float> w;
    for (uint32_t r = 0; r < rowCount; ++r) {
      cols.clear();
      w.clear();
      const uint32_t n = rng.below(perRow * 2 + 1);
      for (uint32_t k = 0; k < n; ++k) {
        cols.push_back(rng.below(columns));
        w.push_back(rng.unit());
      }
      m.appendRow(cols.data(), w.data(), cols.size());
    }
  };
  sparse(d.clusterGather, s.clusters, rows, 3);
  // The gather maps from a random source: one texel in eight invalid, random neighbours.
  d.filterPasses = 2;
  for (uint32_t t = 0; t < s.texels; ++t) {
    d.texelPoint.push_back(rng.below(8) == 0 ? kNoTexel : rng.below(s.points));
    d.texelNeighbours.push_back(uint8_t(rng.below(256)));
  }
  buildGatherMaps(d);

  for (uint32_t i = 0; i < s.texels * kShCount; ++i)
    d.texelSky.push_back(floatToHalf(rng.unit() * 2.0f - 0.5f));
  for (uint32_t i = 0; i < s.clusters * kShCount; ++i) d.clusterSky.push_back(floatToHalf(rng.unit()));

  if (s.probes) {
    ProbeTransport& p = d.probes;
    p.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    p.mesh.tetrahedra = {{0, 1, 2, 3}};
    p.mesh.neighbours = {{-1, -1, -1, -1}};
    p.bins = 3;
    for (uint32_t k = 0; k < p.bins * kShCount; ++k) p.binSh.push_back(rng.unit() - 0.5f);
    p.links = SparseLinks(s.clusters + s.farClusters);
    for (uint32_t r = 0; r < 4 * p.bins; ++r) {
      targets.clear();
      weights.clear();
      for (uint32_t t = rng.below(3); t < s.clusters + s.farClusters; t += 1 + rng.below(9)) {
        targets.push_back(t);
        weights.push_back(0.01f + rng.unit());
      }
      p.links.appendRow(targets.data(), weights.data(), targets.size());
    }
    for (uint32_t k = 0; k < 4 * kProbeSkyCount; ++k) p.sky.push_back(floatToHalf(rng.unit() - 0.5f));
    for (uint32_t k = 0; k < 4 * 128; ++k) p.depth.push_back(floatToHalf(4.0f * rng.unit()));
  }

  if (s.reflections) {
    ReflectionTransport& r = d.reflections;
    r.bounces = 2;
    for (const MaterialParams& m : d.materials) r.bakedAlbedo.push_back(m.albedo);
    for (uint32_t side : {2u, 4u}) {
      ReflectionProbeCapture c;
      c.name = "probe" + std::to_string(side);
      c.resolution = side;
      c.firstHit = r.hits.size();
      c.box.centre = glm::vec3(rng.unit(), rng.unit(), rng.unit());
      c.box.axes = glm::mat3(glm::vec3(0, 0, 1), glm::vec3(0, 1, 0), glm::vec3(-1, 0, 0));
      c.box.halfSize = glm::vec3(1.0f + rng.unit(), 2.0f, 3.0f);
      c.box.blendDistance = 0.5f;
      c.box.importance = int(side);
      c.box.boxProjection = side == 2;
      c.box.capturePosition = c.box.centre + glm::vec3(0.1f);
      c.box.projectionCentre = c.box.centre - glm::vec3(0.2f);
      c.box.projectionHalfSize = c.box.halfSize * 0.5f;
      r.probes.push_back(c);
      for (uint32_t k = 0; k < kCubeFaceCount * side * side; ++k) {
        ReflectionHit h;
        if (rng.below(4) != 0) {
          h.material = rng.below(uint32_t(d.materials.size()));
          h.atlas = uint16_t(rng.below(uint32_t(d.atlases.size())));
          h.roughness = floatToHalf(rng.unit());
          h.lightmapUv = glm::vec2(rng.unit(), rng.unit());
          for (int c3 = 0; c3 < 3; ++c3) {
            h.diffuse[c3] = floatToHalf(rng.unit());
            h.emission[c3] = floatToHalf(rng.unit());
            h.f0[c3] = floatToHalf(rng.unit());
            h.normal[c3] = floatToHalf(rng.unit() - 0.5f);
          }
          h.distance = 1.0f + rng.unit();
        }
        r.hits.push_back(h);
      }
    }
  }

  d.indirectIntensity = 1.5f;
  d.albedoBoost = 1.25f;
  for (int i = 0; i < kShCount; ++i) d.skySh[i] = glm::vec3(0.1f * float(i), -0.2f, 0.3f + float(i));
  return d;
}

// makeTransport() at two resolutions (lightmap_layers.h): its texels are an indirect grid of 2
// in one 2x1 atlas, under 3 lightmap texels in a 3x1 atlas (and a 1x1 one that only mixes, so
// that the lightmap has more atlases than the indirect grid). The first source's direct light
// is in the layers, the others have none. Valid.
TransportData makeLayeredTransport() {
  Shape s;
  s.texels = 2;
  s.clusters = 6;
  s.farClusters = 2;
  s.sharedFar = 2;
  s.points = 2;
  s.backRows = 2;
  s.linksPerRow = 3;
  s.lightsWithTexelTransfer = 0;
  TransportData d = makeTransport(s, 3);
  AtlasLayout indirect;
  indirect.width = 2;
  indirect.height = 1;
  indirect.texelOfPixel = {0, 1};
  d.atlases = {indirect};
  buildGatherMaps(d);  // the texels' neighbours follow their atlas
  for (Source& src : d.sources) src.texelTransfer.clear();  // the layers hold the direct light
  // Reflection hits sample the lightmap: its two atlases.
  for (ReflectionHit& h : d.reflections.hits)
    if (h.atlas != kReflectionNoAtlas) h.atlas = uint16_t(h.atlas % 2);

  LightmapLayers& l = d.lightmap;
  l.texelCount = 3;
  AtlasLayout lightmap;
  lightmap.width = 3;
  lightmap.height = 1;
  lightmap.texelOfPixel = {0, 1, 2};
  AtlasLayout mixed;
  mixed.width = 1;
  mixed.height = 1;
  mixed.texelOfPixel = {kNoTexel};
  mixed.mixPixel = {0};
  mixed.mixStart = {0, 2};
  mixed.mixTexel = {0, 2};
  mixed.mixWeight = {0.25f, 0.75f};
  l.atlases = {lightmap, mixed};
  // The indirect atlas is one pixel high: only the lower corners (bits 0 and 1) can count.
  // Every field differs somewhere, so a swap in the file would show.
  l.corners = {{0, 0, 0, 0x00, 0x1, 0}, {0, 0, 0, 0x08, 0x3, 0}, {1, 0, 0, 0x35, 0x1, 0}};
  l.direct.resize(d.sources.size());
  l.directScale.assign(d.sources.size(), 1.0f);
  l.directScale[0] = encodeDirectLayer({0.5f, 2.0f, 0.125f}, l.direct[0]);
  l.directScale[2] = 0.0f;
  return d;
}

void expectSparseEqual(const SparseMatrix& a, const SparseMatrix& b, const char* what) {
  EXPECT_EQ(a.rowStart, b.rowStart) << what;
  EXPECT_EQ(a.column, b.column) << what;
  EXPECT_EQ(a.weight, b.weight) << what;
}

void expectAtlasesEqual(const std::vector<AtlasLayout>& a, const std::vector<AtlasLayout>& b,
                        const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) {
    SCOPED_TRACE(what + " " + std::to_string(i));
    const AtlasLayout &x = a[i], &y = b[i];
    EXPECT_EQ(x.width, y.width);
    EXPECT_EQ(x.height, y.height);
    EXPECT_EQ(x.texelOfPixel, y.texelOfPixel);
    EXPECT_EQ(x.mixPixel, y.mixPixel);
    EXPECT_EQ(x.mixStart, y.mixStart);
    EXPECT_EQ(x.mixTexel, y.mixTexel);
    EXPECT_EQ(x.mixWeight, y.mixWeight);
  }
}

void expectEqual(const TransportData& a, const TransportData& b) {
  EXPECT_EQ(a.texelCount, b.texelCount);
  EXPECT_EQ(a.clusterCount, b.clusterCount);
  EXPECT_EQ(a.gatherPointCount, b.gatherPointCount);
  expectAtlasesEqual(a.atlases, b.atlases, "atlas");
  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (size_t i = 0; i < a.materials.size(); ++i) {
    EXPECT_EQ(a.materials[i].name, b.materials[i].name);
    EXPECT_EQ(a.materials[i].albedo, b.materials[i].albedo);
    EXPECT_EQ(a.materials[i].emission, b.materials[i].emission);
  }
  ASSERT_EQ(a.sources.size(), b.sources.size());
  for (size_t i = 0; i < a.sources.size(); ++i) {
    SCOPED_TRACE("source " + std::to_string(i));
    const Source &x = a.sources[i], &y = b.sources[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.material, y.material);
    EXPECT_EQ(x.color, y.color);
    EXPECT_EQ(x.intensity, y.intensity);
    EXPECT_EQ(x.bounceIntensity, y.bounceIntensity);
    EXPECT_EQ(x.enabled, y.enabled);
    EXPECT_EQ(x.texelTransfer, y.texelTransfer);
    EXPECT_EQ(x.clusterTransfer, y.clusterTransfer);
    EXPECT_EQ(x.probeTransfer, y.probeTransfer);
  }
  EXPECT_EQ(a.clusterMaterial, b.clusterMaterial);
  EXPECT_EQ(a.clusterAlbedoTexture, b.clusterAlbedoTexture);
  EXPECT_EQ(a.clusterEmissionTexture, b.clusterEmissionTexture);
  EXPECT_EQ(a.clusterPosition, b.clusterPosition);
  EXPECT_EQ(a.pointPosition, b.pointPosition);
  EXPECT_EQ(a.pointNormal, b.pointNormal);
  EXPECT_EQ(a.links.rowStart, b.links.rowStart);
  EXPECT_EQ(a.links.targetBits, b.links.targetBits);
  EXPECT_EQ(a.links.link, b.links.link);
  EXPECT_EQ(a.links.rowScale, b.links.rowScale);
  expectSparseEqual(a.farClusters, b.farClusters, "far clusters");
  EXPECT_EQ(a.sharedFar.targetBits, b.sharedFar.targetBits);
  EXPECT_EQ(a.sharedFar.rowStart, b.sharedFar.rowStart);
  EXPECT_EQ(a.sharedFar.link, b.sharedFar.link);
  EXPECT_EQ(a.sharedFar.rowScale, b.sharedFar.rowScale);
  expectSparseEqual(a.clusterGather, b.clusterGather, "cluster gather");
  EXPECT_EQ(a.texelPoint, b.texelPoint);
  EXPECT_EQ(a.texelNeighbours, b.texelNeighbours);
  expectSparseEqual(a.pointFilter, b.pointFilter, "point filter");
  EXPECT_EQ(a.filterPasses, b.filterPasses);
  expectSparseEqual(a.texelGather, b.texelGather, "texel gather");
  EXPECT_EQ(a.texelSky, b.texelSky);
  EXPECT_EQ(a.clusterSky, b.clusterSky);
  EXPECT_EQ(a.indirectIntensity, b.indirectIntensity);
  EXPECT_EQ(a.albedoBoost, b.albedoBoost);
  for (int i = 0; i < kShCount; ++i) EXPECT_EQ(a.skySh[i], b.skySh[i]) << "sky SH " << i;
  const ProbeTransport &p = a.probes, &q = b.probes;
  EXPECT_EQ(p.mesh.positions, q.mesh.positions);
  EXPECT_EQ(p.mesh.tetrahedra, q.mesh.tetrahedra);
  EXPECT_EQ(p.mesh.neighbours, q.mesh.neighbours);
  EXPECT_EQ(p.bins, q.bins);
  EXPECT_EQ(p.binSh, q.binSh);
  EXPECT_EQ(p.links.targetBits, q.links.targetBits);
  EXPECT_EQ(p.links.rowStart, q.links.rowStart);
  EXPECT_EQ(p.links.link, q.links.link);
  EXPECT_EQ(p.links.rowScale, q.links.rowScale);
  EXPECT_EQ(p.sky, q.sky);
  EXPECT_EQ(p.depth, q.depth);
  const ReflectionTransport &r = a.reflections, &t = b.reflections;
  EXPECT_EQ(r.bounces, t.bounces);
  EXPECT_EQ(r.bakedAlbedo, t.bakedAlbedo);
  ASSERT_EQ(r.probes.size(), t.probes.size());
  for (size_t i = 0; i < r.probes.size(); ++i) {
    SCOPED_TRACE("reflection probe " + std::to_string(i));
    const ReflectionProbeCapture &x = r.probes[i], &y = t.probes[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.resolution, y.resolution);
    EXPECT_EQ(x.firstHit, y.firstHit);
    EXPECT_EQ(x.box.centre, y.box.centre);
    EXPECT_EQ(x.box.axes, y.box.axes);
    EXPECT_EQ(x.box.halfSize, y.box.halfSize);
    EXPECT_EQ(x.box.blendDistance, y.box.blendDistance);
    EXPECT_EQ(x.box.importance, y.box.importance);
    EXPECT_EQ(x.box.boxProjection, y.box.boxProjection);
    EXPECT_EQ(x.box.capturePosition, y.box.capturePosition);
    EXPECT_EQ(x.box.projectionCentre, y.box.projectionCentre);
    EXPECT_EQ(x.box.projectionHalfSize, y.box.projectionHalfSize);
  }
  ASSERT_EQ(r.hits.size(), t.hits.size());
  EXPECT_EQ(0, std::memcmp(r.hits.data(), t.hits.data(), r.hits.size() * sizeof(ReflectionHit)));
  const LightmapLayers &u = a.lightmap, &v = b.lightmap;
  EXPECT_EQ(u.texelCount, v.texelCount);
  expectAtlasesEqual(u.atlases, v.atlases, "lightmap atlas");
  ASSERT_EQ(u.corners.size(), v.corners.size());
  for (size_t i = 0; i < u.corners.size(); ++i) {
    SCOPED_TRACE("lightmap texel " + std::to_string(i));
    const IndirectCorners &x = u.corners[i], &y = v.corners[i];
    EXPECT_EQ(x.x, y.x);
    EXPECT_EQ(x.y, y.y);
    EXPECT_EQ(x.atlas, y.atlas);
    EXPECT_EQ(x.fraction, y.fraction);
    EXPECT_EQ(x.mask, y.mask);
    EXPECT_EQ(x.reserved, y.reserved);
  }
  EXPECT_EQ(u.direct, v.direct);
  EXPECT_EQ(u.directScale, v.directScale);
}

bool isEmpty(const TransportData& d) {
  return d.texelCount == 0 && d.clusterCount == 0 && d.atlases.empty() && d.sources.empty() &&
         d.materials.empty() && d.links.link.empty() && d.texelSky.empty() &&
         d.probes.count() == 0 && d.reflections.count() == 0 && !d.lightmap.active() &&
         d.lightmap.corners.empty() && d.lightmap.direct.empty();
}

// ---- File surgery ----------------------------------------------------------------------------

uint64_t get64(const std::vector<uint8_t>& f, size_t at) {
  uint64_t v;
  std::memcpy(&v, f.data() + at, 8);
  return v;
}
uint32_t get32(const std::vector<uint8_t>& f, size_t at) {
  uint32_t v;
  std::memcpy(&v, f.data() + at, 4);
  return v;
}
void put64(std::vector<uint8_t>& f, size_t at, uint64_t v) { std::memcpy(f.data() + at, &v, 8); }
void put32(std::vector<uint8_t>& f, size_t at, uint32_t v) { std::memcpy(f.data() + at, &v, 4); }

// Recomputes the checksum after a deliberate change.
void reseal(std::vector<uint8_t>& f) { put64(f, 32, transportChecksum(f.data(), f.size())); }

struct Section {
  std::string id;
  uint64_t count = 0;
  std::vector<uint8_t> payload;
};

// The sections of a file, in table order.
std::vector<Section> split(const std::vector<uint8_t>& f) {
  std::vector<Section> sections;
  const uint32_t n = get32(f, 24);
  for (uint32_t i = 0; i < n; ++i) {
    const size_t e = kTransportHeaderSize + size_t(i) * 32;
    Section s;
    s.id.assign(reinterpret_cast<const char*>(f.data() + e), 4);
    const uint64_t offset = get64(f, e + 8), size = get64(f, e + 16);
    s.count = get64(f, e + 24);
    s.payload.assign(f.begin() + long(offset), f.begin() + long(offset + size));
    sections.push_back(std::move(s));
  }
  return sections;
}

// A well-formed file of these sections (layout as the writer's).
std::vector<uint8_t> join(const std::vector<Section>& sections) {
  auto align = [](size_t x) { return (x + 15) & ~size_t(15); };
  std::vector<uint8_t> f(kTransportHeaderSize + sections.size() * 32, 0);
  std::memcpy(f.data(), kTransportMagic, 8);
  put32(f, 8, kTransportVersion);
  put32(f, 12, kTransportHeaderSize);
  put32(f, 24, uint32_t(sections.size()));
  for (size_t i = 0; i < sections.size(); ++i) {
    f.resize(align(f.size()), 0);
    const size_t e = kTransportHeaderSize + i * 32;
    std::memcpy(f.data() + e, sections[i].id.data(), 4);
    put64(f, e + 8, f.size());
    put64(f, e + 16, sections[i].payload.size());
    put64(f, e + 24, sections[i].count);
    f.insert(f.end(), sections[i].payload.begin(), sections[i].payload.end());
  }
  f.resize(align(f.size()), 0);
  put64(f, 16, f.size());
  reseal(f);
  return f;
}

Section* find(std::vector<Section>& sections, const std::string& id) {
  for (Section& s : sections)
    if (s.id == id) return &s;
  return nullptr;
}

std::string parseError(const std::vector<uint8_t>& f, bool verifyChecksum = true) {
  TransportData out;  // something for a failed parse to clear
  out.texelCount = 5;
  out.atlases.resize(1);
  out.sources.resize(1);
  out.texelSky.resize(3);
  std::string error;
  ParseOptions options;
  options.verifyChecksum = verifyChecksum;
  if (parseTransport(f.data(), f.size(), out, &error, options)) return "(parsed)";
  EXPECT_TRUE(isEmpty(out)) << "a failed parse left data behind";
  EXPECT_FALSE(error.empty());
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  return error;
}

std::string tempPath(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "afterglow_runtime_tests";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

// ---- Tests -----------------------------------------------------------------------------------

TEST(TransportFile, Xxh64MatchesTheReference) {
  // Values from the reference xxHash library (XXH64).
  EXPECT_EQ(xxh64("", 0, 0), 0xEF46DB3751D8E999ull);
  EXPECT_EQ(xxh64("a", 1, 0), 0xD24EC4F1A98C6E5Bull);
  EXPECT_EQ(xxh64("abc", 3, 0), 0x44BC2CF5AD770999ull);
  EXPECT_EQ(xxh64("abc", 3, 0x9E3779B97F4A7C15ull), 0x2ED0F59D6B43AC8Bull);
  std::vector<uint8_t> bytes;
  for (int r = 0; r < 4; ++r)
    for (int i = 0; i < 256; ++i) bytes.push_back(uint8_t(i));
  bytes.insert(bytes.end(), {'x', 'y', 'z'});
  EXPECT_EQ(xxh64(bytes.data(), bytes.size(), 0), 0xE146CB31B65BC21Aull);
  EXPECT_EQ(xxh64(bytes.data(), bytes.size(), 0x9E3779B97F4A7C15ull), 0x86B7211D04E93C1Full);
}

TEST(TransportFile, TransportDataHasNoFieldTheFileMisses) {
  // The sizes with libstdc++ on 64-bit when this file format was written. A failure means a
  // field was added: serialise it (transport_file.cpp) and compare it in expectEqual() above.
#if defined(__GLIBCXX__) && UINTPTR_MAX == 0xffffffffffffffffull
  EXPECT_EQ(sizeof(TransportData), 1320u);
  EXPECT_EQ(sizeof(ReflectionTransport), 80u);
  EXPECT_EQ(sizeof(ReflectionProbeCapture), 152u);
  EXPECT_EQ(sizeof(AtlasLayout), 128u);
  EXPECT_EQ(sizeof(Source), 136u);
  EXPECT_EQ(sizeof(ProbeTransport), 232u);
  EXPECT_EQ(sizeof(MaterialParams), 56u);
  EXPECT_EQ(sizeof(LightmapLayers), 104u);
  EXPECT_EQ(sizeof(IndirectCorners), 8u);
#else
  GTEST_SKIP() << "sizes recorded for libstdc++ on 64-bit only";
#endif
}

TEST(TransportFile, RoundTripKeepsEveryField) {
  const TransportData data = makeTransport(Shape());
  ASSERT_EQ(data.validate(), "");
  const std::vector<uint8_t> bytes = serializeTransport(data);
  EXPECT_EQ(bytes.size() % 16, 0u);
  EXPECT_EQ(get64(bytes, 16), bytes.size());

  TransportData parsed;
  std::string error;
  ASSERT_TRUE(parseTransport(bytes.data(), bytes.size(), parsed, &error)) << error;
  expectEqual(data, parsed);
  // Writing what was read gives the same bytes.
  EXPECT_EQ(serializeTransport(parsed), bytes);

  // Through a file.
  const std::string path = tempPath("roundtrip.agt");
  ASSERT_TRUE(saveTransport(data, path, &error)) << error;
  TransportData loaded;
  ASSERT_TRUE(loadTransport(path, loaded, &error)) << error;
  expectEqual(data, loaded);
  std::filesystem::remove(path);
}

TEST(TransportFile, RoundTripOfAnEmptyTransport) {
  const TransportData empty;
  ASSERT_EQ(empty.validate(), "");
  const std::vector<uint8_t> bytes = serializeTransport(empty);
  TransportData parsed = makeTransport(Shape());
  std::string error;
  ASSERT_TRUE(parseTransport(bytes.data(), bytes.size(), parsed, &error)) << error;
  expectEqual(empty, parsed);
}

TEST(TransportFile, RoundTripKeepsLightmapLayers) {
  const TransportData data = makeLayeredTransport();
  ASSERT_TRUE(data.lightmap.active());
  ASSERT_EQ(data.validate(), "");
  // Some reflection hits sample the lightmap's second atlas, which the indirect grid lacks.
  bool secondAtlas = false;
  for (const ReflectionHit& h : data.reflections.hits) secondAtlas |= h.atlas == 1;
  EXPECT_TRUE(secondAtlas);
  // The layers count in the transport's memory.
  TransportData oneResolution = data;
  oneResolution.lightmap = LightmapLayers();
  EXPECT_EQ(data.memoryBytes(), oneResolution.memoryBytes() + data.lightmap.memoryBytes());

  const std::vector<uint8_t> bytes = serializeTransport(data);
  std::vector<Section> sections = split(bytes);
  const Section* layers = find(sections, "LAYR");
  ASSERT_NE(layers, nullptr);
  EXPECT_EQ(layers->count, 3u);
  EXPECT_EQ(get32(layers->payload, 0), 3u);  // texels
  EXPECT_EQ(get32(layers->payload, 4), 2u);  // atlases
  TransportData parsed;
  std::string error;
  ASSERT_TRUE(parseTransport(bytes.data(), bytes.size(), parsed, &error)) << error;
  expectEqual(data, parsed);
  EXPECT_EQ(serializeTransport(parsed), bytes);

  const std::string path = tempPath("layers.agt");
  ASSERT_TRUE(saveTransport(data, path, &error)) << error;
  TransportData loaded;
  ASSERT_TRUE(loadTransport(path, loaded, &error)) << error;
  expectEqual(data, loaded);
  std::filesystem::remove(path);
}

TEST(TransportFile, InconsistentLightmapLayersAreRefused) {
  const TransportData good = makeLayeredTransport();
  ASSERT_EQ(good.validate(), "");
  auto errorOf = [](const TransportData& d) {
    EXPECT_NE(d.validate(), "");
    return parseError(serializeTransport(d));
  };
  {
    TransportData d = good;
    d.lightmap.corners.pop_back();
    EXPECT_EQ(errorOf(d), "section 'LAYR': lightmap layers: 2 corners for 3 lightmap texels");
  }
  {
    TransportData d = good;
    d.lightmap.corners[1].x = 1;  // its right-hand corner is then past the 2x1 indirect atlas
    EXPECT_EQ(errorOf(d), "section 'LAYR': lightmap layers: texel 1 reads pixel (2, 0) outside "
                          "its indirect atlas");
  }
  {
    TransportData d = good;
    d.lightmap.direct[0].pop_back();
    EXPECT_EQ(errorOf(d),
              "section 'LAYR': lightmap layers: source 0 has direct light for 2 of 3 texels");
  }
  {
    TransportData d = good;
    d.lightmap.direct.pop_back();
    EXPECT_EQ(errorOf(d), "section 'LAYR': lightmap layers: direct light for 3 of 4 sources");
  }
  {
    TransportData d = good;
    d.lightmap.atlases[0].texelOfPixel[2] = 3;
    EXPECT_EQ(errorOf(d), "section 'LAYR': lightmap layers: atlas 0 refers to texel 3 of 3");
  }
  {
    TransportData d = good;
    d.lightmap.texelCount = 0;
    EXPECT_EQ(errorOf(d), "section 'LAYR': lightmap layers without lightmap texels");
  }
  {
    // The direct light twice: per indirect texel and in the layers.
    TransportData d = good;
    d.sources[0].texelTransfer.assign(d.texelCount, 0.5f);
    EXPECT_EQ(errorOf(d), "section 'SRCS': source 0 ('light 0'): a texel transfer beside the "
                          "lightmap layers' direct light");
  }
  {
    // The lightmap has two atlases (the indirect grid one): a hit on a third is refused.
    TransportData d = good;
    for (ReflectionHit& h : d.reflections.hits)
      if (h.atlas != kReflectionNoAtlas) {
        h.atlas = 2;
        break;
      }
    const std::string error = errorOf(d);
    EXPECT_EQ(error.rfind("section 'REFL': ", 0), 0u) << error;
  }

  // What the reader checks itself, before validate().
  std::vector<Section> sections = split(serializeTransport(good));
  {
    std::vector<Section> s = sections;
    find(s, "LAYR")->count = 4;
    EXPECT_EQ(parseError(join(s)),
              "section 'LAYR': the table says 4 lightmap texels, the section has 3");
  }
  {
    std::vector<Section> s = sections;
    put32(find(s, "LAYR")->payload, 4, 0xffffffffu);  // atlases
    const std::string error = parseError(join(s));
    EXPECT_EQ(error.rfind("section 'LAYR': 4294967295 lightmap atlases cannot fit", 0), 0u)
        << error;
  }
  {
    // From the end: directScale (16 + 4 × 4 bytes), three empty direct arrays (16 each), the
    // first one's 16 + 3 × 2 bytes padded to 32, and before that the source count padded to 16
    // after the corners.
    std::vector<Section> s = sections;
    std::vector<uint8_t>& p = find(s, "LAYR")->payload;
    const size_t at = p.size() - 32 - 3 * 16 - 32 - 8;
    ASSERT_EQ(get32(p, at), 4u);
    put32(p, at, 0x10000000u);
    const std::string error = parseError(join(s));
    EXPECT_EQ(error.rfind("section 'LAYR': 268435456 direct light layers cannot fit", 0), 0u)
        << error;
  }
  // Every cut of the section's payload is refused, naming it.
  const size_t payloadSize = find(sections, "LAYR")->payload.size();
  for (size_t n = 0; n < payloadSize; ++n) {
    std::vector<Section> s = sections;
    find(s, "LAYR")->payload.resize(n);
    const std::string error = parseError(join(s));
    EXPECT_EQ(error.rfind("section 'LAYR': ", 0), 0u) << "cut at " << n << ": " << error;
  }
}

TEST(TransportFile, ArraysStartSixteenByteAligned) {
  const std::vector<uint8_t> bytes = serializeTransport(makeTransport(Shape()));
  const uint32_t sections = get32(bytes, 24);
  for (uint32_t i = 0; i < sections; ++i) {
    const size_t e = kTransportHeaderSize + i * 32;
    EXPECT_EQ(get64(bytes, e + 8) % 16, 0u) << "section " << i;
  }
  // TSKY is one array: its u64 count at the section start, its data 16 bytes further.
  std::vector<Section> split_ = split(bytes);
  const Section* sky = find(split_, "TSKY");
  ASSERT_NE(sky, nullptr);
  EXPECT_EQ(sky->count, uint64_t(300 * kShCount));
  EXPECT_EQ(sky->payload.size(), 16u + 300 * kShCount * 2);
}

TEST(TransportFile, EveryTruncationFails) {
  Shape small;
  small.texels = 20;
  small.clusters = 6;
  small.points = 8;
  small.backRows = 2;
  small.atlasSides[0][0] = 3;
  small.atlasSides[0][1] = 4;
  small.atlasSides[1][0] = 2;
  small.atlasSides[1][1] = 2;
  small.atlasSides[2][0] = 5;
  small.atlasSides[2][1] = 1;
  const std::vector<uint8_t> bytes = serializeTransport(makeTransport(small));
  ASSERT_LT(bytes.size(), 20000u);
  // Where the last section's payload ends: a cut past it only drops padding.
  uint64_t lastEnd = 0;
  for (uint32_t i = 0; i < get32(bytes, 24); ++i) {
    const size_t e = kTransportHeaderSize + i * 32;
    lastEnd = std::max(lastEnd, get64(bytes, e + 8) + get64(bytes, e + 16));
  }
  for (size_t n = 0; n < bytes.size(); ++n) {
    std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + long(n));
    const std::string error = parseError(cut);
    if (n >= 8) {
      EXPECT_EQ(error.rfind("truncated: the file has " + std::to_string(n) + " bytes", 0), 0u)
          << error;
    }
    EXPECT_NE(parseError(cut, false), "(parsed)") << n;
    // The same cut with its header saying so and a fresh checksum reaches the section checks.
    if (n >= kTransportHeaderSize) {
      put64(cut, 16, n);
      reseal(cut);
      const std::string resealed = parseError(cut);
      if (n < lastEnd) {
        EXPECT_NE(resealed, "(parsed)") << "cut at " << n;
      }
    }
  }
}

TEST(TransportFile, DamagedHeaderBytesAreCaught) {
  const std::vector<uint8_t> bytes = serializeTransport(makeTransport(Shape()));
  for (size_t i = 0; i < kTransportHeaderSize; ++i)
    for (uint8_t mask : {uint8_t(0x01), uint8_t(0x10), uint8_t(0x80), uint8_t(0xff)}) {
      std::vector<uint8_t> f = bytes;
      f[i] ^= mask;
      const std::string error = parseError(f);
      SCOPED_TRACE("byte " + std::to_string(i) + " ^ " + std::to_string(mask) + ": " + error);
      std::string expected;
      if (i < 8) {
        expected = "not an afterglow transport file";
      } else if (i < 12) {
        expected = "version ";
      } else if (i < 16) {
        expected = "header size ";
      } else if (i < 24) {
        expected = get64(f, 16) > f.size() ? "truncated: " : "size mismatch: ";
      } else {
        expected = "checksum mismatch: the file is corrupted";
      }
      EXPECT_EQ(error.rfind(expected, 0), 0u);
      // Without the checksum, the structure still gives damage away (bytes 32..39 are the
      // checksum itself, which is then not looked at).
      if (i < 32) {
        EXPECT_NE(parseError(f, false), "(parsed)");
      }
    }
}

TEST(TransportFile, DamagedPayloadBytesAreCaught) {
  const std::vector<uint8_t> bytes = serializeTransport(makeTransport(Shape()));
  Rng rng{7};
  int structural = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<uint8_t> f = bytes;
    const size_t at = kTransportHeaderSize + rng.below(uint32_t(f.size() - kTransportHeaderSize));
    f[at] ^= uint8_t(1 + rng.below(255));
    EXPECT_EQ(parseError(f), "checksum mismatch: the file is corrupted") << "byte " << at;
    // Without the checksum, never a crash; damage to the table or a count is caught.
    if (parseError(f, false) != "(parsed)") ++structural;
  }
  EXPECT_GT(structural, 0);
  // The table is all structure: any change there is refused even without the checksum.
  for (size_t at = kTransportHeaderSize; at < kTransportHeaderSize + 11 * 32; ++at) {
    std::vector<uint8_t> f = bytes;
    f[at] ^= 0x40;
    EXPECT_NE(parseError(f, false), "(parsed)") << "table byte " << at;
  }
}

TEST(TransportFile, WrongMagicAndVersionSaySo) {
  std::vector<uint8_t> bytes = serializeTransport(makeTransport(Shape()));
  std::vector<uint8_t> png = bytes;
  std::memcpy(png.data(), "\x89PNG\r\n\x1a\n", 8);
  EXPECT_EQ(parseError(png), "not an afterglow transport file");
  EXPECT_EQ(parseError(std::vector<uint8_t>{'{', '}'}), "not an afterglow transport file");
  EXPECT_EQ(parseError(std::vector<uint8_t>{}), "not an afterglow transport file");

  const std::string current = std::to_string(kTransportVersion);
  // 7: before the lightmap layers (LAYR).
  for (uint32_t version : {1u, 6u, 7u, kTransportVersion + 1}) {
    std::vector<uint8_t> other = bytes;
    put32(other, 8, version);
    reseal(other);
    EXPECT_EQ(parseError(other), "version " + std::to_string(version) + "; this runtime reads version " +
                                     current + ": re-bake with this afterglow");
  }

  std::vector<uint8_t> longer = bytes;
  longer.resize(bytes.size() + 16, 0);
  EXPECT_EQ(parseError(longer), "size mismatch: the file has " + std::to_string(longer.size()) +
                                    " bytes, its header says " + std::to_string(bytes.size()));
  std::vector<uint8_t> shorter(bytes.begin(), bytes.end() - 100);
  EXPECT_EQ(parseError(shorter), "truncated: the file has " + std::to_string(shorter.size()) +
                                     " bytes, its header says " + std::to_string(bytes.size()));
}

TEST(TransportFile, SectionTableRules) {
  const TransportData data = makeTransport(Shape());
  const std::vector<uint8_t> bytes = serializeTransport(data);
  const std::vector<Section> sections = split(bytes);
  ASSERT_EQ(sections.size(), 16u);
  // join() rebuilds the writer's layout exactly.
  EXPECT_EQ(join(sections), bytes);

  // An unknown section (a later writer's) is skipped, wherever it sits.
  {
    std::vector<Section> s = sections;
    s.insert(s.begin() + 3, Section{"XTRA", 5, std::vector<uint8_t>(37, 0xab)});
    s.push_back(Section{"zzzz", 0, {}});
    const std::vector<uint8_t> f = join(s);
    TransportData parsed;
    std::string error;
    ASSERT_TRUE(parseTransport(f.data(), f.size(), parsed, &error)) << error;
    expectEqual(data, parsed);
  }
  for (const Section& gone : sections) {
    std::vector<Section> s;
    for (const Section& k : sections)
      if (k.id != gone.id) s.push_back(k);
    EXPECT_EQ(parseError(join(s)), "missing section '" + gone.id + "'");
  }
  {
    std::vector<Section> s = sections;
    s.push_back(*find(s, "LINK"));
    EXPECT_EQ(parseError(join(s)), "section 'LINK' appears twice");
  }
  {
    std::vector<Section> s = sections;
    find(s, "GMAP")->count += 1;
    EXPECT_EQ(parseError(join(s)), "section 'GMAP': the table says 301 texels, the section has 300");
  }
  {
    std::vector<Section> s = sections;
    find(s, "CGAT")->count += 1;
    EXPECT_EQ(parseError(join(s)), "section 'CGAT': the table says 41 rows, the section has 40");
  }
  {
    std::vector<Section> s = sections;
    find(s, "CSKY")->payload.push_back(0);
    EXPECT_EQ(parseError(join(s)), "section 'CSKY': 1 bytes left over");
  }
  {
    // A count far beyond the section: refused before anything is allocated.
    std::vector<Section> s = sections;
    std::vector<uint8_t>& p = find(s, "TSKY")->payload;
    const uint64_t huge = uint64_t(1) << 60;
    std::memcpy(p.data(), &huge, 8);
    const std::string error = parseError(join(s));
    EXPECT_EQ(error.rfind("section 'TSKY': texel sky transfer: 1152921504606846976 values", 0), 0u)
        << error;
  }
  {
    std::vector<Section> s = sections;
    find(s, "ATLS")->count = uint64_t(1) << 40;
    const std::string error = parseError(join(s));
    EXPECT_NE(error.find("atlases cannot fit"), std::string::npos) << error;
  }
  {
    // Offsets that overlap or leave the file.
    std::vector<uint8_t> f = bytes;
    const size_t second = kTransportHeaderSize + 32;
    put64(f, second + 8, get64(f, kTransportHeaderSize + 8));
    reseal(f);
    EXPECT_NE(parseError(f).find("overlaps the section before it"), std::string::npos);
    f = bytes;
    put64(f, second + 16, uint64_t(-16));
    reseal(f);
    EXPECT_NE(parseError(f).find("outside the file"), std::string::npos);
    f = bytes;
    put64(f, second + 8, get64(f, second + 8) + 8);
    reseal(f);
    EXPECT_NE(parseError(f).find("not a multiple of 16"), std::string::npos);
    f = bytes;
    put32(f, 24, 0xffffffffu);
    reseal(f);
    EXPECT_NE(parseError(f).find("section table: 4294967295 sections"), std::string::npos);
  }
}

TEST(TransportFile, BadIndicesAreRefusedByValidate) {
  const TransportData good = makeTransport(Shape());
  auto errorOf = [](const TransportData& d) {
    EXPECT_NE(d.validate(), "");
    return parseError(serializeTransport(d));
  };
  {
    TransportData d = good;
    ASSERT_FALSE(d.links.link.empty());
    d.links.link.back() = (d.links.link.back() & ~d.links.targetMask()) | d.linkTargetCount();
    const std::string error = errorOf(d);
    EXPECT_EQ(error.rfind("section 'LINK': links: entry ", 0), 0u) << error;
  }
  {
    // A row of links the bounce would read past: not padded to kLinkGroup.
    TransportData d = good;
    size_t r = d.links.rows();
    while (r > 0 && d.links.rowStart[r] == d.links.rowStart[r - 1]) --r;
    ASSERT_GT(r, 0u);
    --r;
    const uint32_t length = d.links.rowStart[r + 1] - d.links.rowStart[r];
    d.links.link.erase(d.links.link.begin() + d.links.rowStart[r + 1] - 1);
    for (size_t j = r + 1; j < d.links.rowStart.size(); ++j) --d.links.rowStart[j];
    EXPECT_EQ(errorOf(d), "section 'LINK': links: row " + std::to_string(r) + " holds " +
                              std::to_string(length - 1) + " entries, not a multiple of 4");
  }
  {
    TransportData d = good;
    ASSERT_FALSE(d.sharedFar.link.empty());
    // A shared far field of shared far fields.
    d.sharedFar.link.back() =
        (d.sharedFar.link.back() & ~d.sharedFar.targetMask()) | d.sharedFarBase();
    const std::string error = errorOf(d);
    EXPECT_EQ(error.rfind("section 'SFAR': shared far fields: entry ", 0), 0u) << error;
  }
  {
    TransportData d = good;
    ASSERT_FALSE(d.farClusters.column.empty());
    d.farClusters.column.back() = d.clusterCount;  // a far cluster of far clusters
    const std::string error = errorOf(d);
    EXPECT_EQ(error.rfind("section 'FARC': far clusters: entry ", 0), 0u) << error;
  }
  {
    TransportData d = good;
    d.texelPoint[5] = d.gatherPointCount + 7;
    const std::string error = errorOf(d);
    EXPECT_EQ(error, "section 'GMAP': gather maps: texel 5 reads gather point 97 of 90") << error;
  }
  {
    TransportData d = good;
    d.atlases[1].texelOfPixel[3] = d.texelCount;
    const std::string error = errorOf(d);
    EXPECT_EQ(error, "section 'ATLS': atlas 1: a pixel refers to texel 300 of 300");
  }
  {
    TransportData d = good;
    d.clusterMaterial[2] = 99;
    EXPECT_EQ(errorOf(d), "section 'CLUS': cluster 2 uses material 99 of 4");
  }
  {
    TransportData d = good;
    d.sources[3].material = 4;
    EXPECT_EQ(errorOf(d).rfind("section 'SRCS': source 3 ('lamp')", 0), 0u);
  }
  {
    TransportData d = good;
    d.texelSky.pop_back();
    EXPECT_EQ(errorOf(d).rfind("section 'TSKY': ", 0), 0u);
  }
  {
    // Row offsets that are not even there: refused by the reader (validate() assumes at least
    // the first offset).
    TransportData d = good;
    d.clusterGather.rowStart.clear();
    d.clusterGather.column.clear();
    d.clusterGather.weight.clear();
    EXPECT_EQ(parseError(serializeTransport(d)),
              "section 'CGAT': row offsets: no row offsets (not even the first 0)");
  }
  {
    // The gather map source is what the file stores: without it there is nothing to save.
    TransportData d = good;
    d.texelNeighbours.pop_back();
    EXPECT_EQ(parseError(serializeTransport(d)),
              "section 'GMAP': gather maps: 300 texel points and 299 neighbour masks for 300 texels");
  }
  {
    TransportData d = good;
    d.filterPasses = 5000;
    EXPECT_EQ(parseError(serializeTransport(d)),
              "section 'INFO': filter passes 5000 outside [0, 1024]");
  }
  {
    // An unknown source kind byte.
    std::vector<Section> s = split(serializeTransport(good));
    std::vector<uint8_t>& p = find(s, "SRCS")->payload;
    const uint32_t nameLength = get32(p, 0);
    p[4 + nameLength] = 7;
    EXPECT_EQ(parseError(join(s)), "section 'SRCS': source 0: unknown kind 7");
  }
}

TEST(TransportFile, SaveRefusesInvalidDataAndBadPaths) {
  TransportData d = makeTransport(Shape());
  d.links.link[0] |= d.links.targetMask();
  std::string error;
  const std::string path = tempPath("invalid.agt");
  EXPECT_FALSE(saveTransport(d, path, &error));
  EXPECT_EQ(error.rfind(path + ": not saved, the transport is invalid: links: ", 0), 0u) << error;
  EXPECT_FALSE(std::filesystem::exists(path));

  const std::string nowhere = "/nonexistent-afterglow-dir/transport.agt";
  EXPECT_FALSE(saveTransport(makeTransport(Shape()), nowhere, &error));
  EXPECT_EQ(error.rfind(nowhere + ": ", 0), 0u) << error;
}

TEST(TransportFile, LoadErrorsNameThePath) {
  TransportData out = makeTransport(Shape());
  std::string error;
  const std::string missing = tempPath("does-not-exist.agt");
  EXPECT_FALSE(loadTransport(missing, out, &error));
  EXPECT_TRUE(isEmpty(out));
  EXPECT_EQ(error.rfind(missing + ": ", 0), 0u) << error;
  EXPECT_NE(error.find("No such file"), std::string::npos) << error;

  // A corrupted file on disk.
  std::vector<uint8_t> bytes = serializeTransport(makeTransport(Shape()));
  bytes[bytes.size() / 2] ^= 1;
  const std::string path = tempPath("corrupt.agt");
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(std::fwrite(bytes.data(), 1, bytes.size(), f), bytes.size());
  std::fclose(f);
  EXPECT_FALSE(loadTransport(path, out, &error));
  EXPECT_EQ(error, path + ": checksum mismatch: the file is corrupted");

  // A folder.
  EXPECT_FALSE(loadTransport(std::filesystem::temp_directory_path().string(), out, &error));
  EXPECT_EQ(error.rfind(std::filesystem::temp_directory_path().string() + ": ", 0), 0u);
  std::filesystem::remove(path);
}

// ---- Half floats -----------------------------------------------------------------------------

bool isNanHalf(uint16_t h) { return (h & 0x7c00u) == 0x7c00u && (h & 0x3ffu) != 0; }

TEST(HalfFloat, EveryHalfRoundTrips) {
  for (uint32_t bits = 0; bits < 65536; ++bits) {
    const uint16_t h = uint16_t(bits);
    const float f = halfToFloat(h);
    if (isNanHalf(h)) {
      EXPECT_TRUE(std::isnan(f)) << bits;
      const uint16_t back = floatToHalf(f);
      EXPECT_TRUE(isNanHalf(back)) << bits;
      EXPECT_EQ(back & 0x8000u, h & 0x8000u) << bits;
    } else {
      ASSERT_EQ(floatToHalf(f), h) << "half " << bits << " = " << f;
    }
  }
}

TEST(HalfFloat, KnownValues) {
  EXPECT_EQ(floatToHalf(0.0f), 0x0000);
  EXPECT_EQ(floatToHalf(-0.0f), 0x8000);
  EXPECT_EQ(floatToHalf(1.0f), 0x3c00);
  EXPECT_EQ(floatToHalf(-2.0f), 0xc000);
  EXPECT_EQ(floatToHalf(0.5f), 0x3800);
  EXPECT_EQ(floatToHalf(65504.0f), 0x7bff);  // largest finite half
  EXPECT_FLOAT_EQ(halfToFloat(0x3555), 0.333251953125f);
  // Ties to even: 1 + 2^-11 is halfway between 1 and 1 + 2^-10.
  EXPECT_EQ(floatToHalf(1.0f + std::ldexp(1.0f, -11)), 0x3c00);
  EXPECT_EQ(floatToHalf(1.0f + 3.0f * std::ldexp(1.0f, -11)), 0x3c02);
  EXPECT_EQ(floatToHalf(std::nextafter(1.0f + std::ldexp(1.0f, -11), 2.0f)), 0x3c01);
  // Overflow: 65520 is halfway to 65536 (Inf) and rounds up to even; everything beyond is Inf.
  EXPECT_EQ(floatToHalf(65519.0f), 0x7bff);
  EXPECT_EQ(floatToHalf(65520.0f), 0x7c00);
  EXPECT_EQ(floatToHalf(1e9f), 0x7c00);
  EXPECT_EQ(floatToHalf(-1e30f), 0xfc00);
  EXPECT_EQ(floatToHalf(std::numeric_limits<float>::infinity()), 0x7c00);
  EXPECT_EQ(floatToHalf(-std::numeric_limits<float>::infinity()), 0xfc00);
  EXPECT_TRUE(isNanHalf(floatToHalf(std::numeric_limits<float>::quiet_NaN())));
  // Subnormals: 2^-24 is the smallest; half of it ties to 0; 2^-14 is the smallest normal.
  EXPECT_EQ(floatToHalf(std::ldexp(1.0f, -24)), 0x0001);
  EXPECT_EQ(floatToHalf(std::ldexp(1.0f, -25)), 0x0000);
  EXPECT_EQ(floatToHalf(std::nextafter(std::ldexp(1.0f, -25), 1.0f)), 0x0001);
  EXPECT_EQ(floatToHalf(3.0f * std::ldexp(1.0f, -25)), 0x0002);
  EXPECT_EQ(floatToHalf(std::ldexp(1.0f, -14)), 0x0400);
  EXPECT_EQ(floatToHalf(std::ldexp(1.0f, -14) - std::ldexp(1.0f, -25)), 0x0400);  // tie → even
  EXPECT_EQ(floatToHalf(std::ldexp(1.0f, -30)), 0x0000);
  EXPECT_EQ(floatToHalf(-std::ldexp(1.0f, -30)), 0x8000);
  EXPECT_EQ(halfToFloat(0x0001), std::ldexp(1.0f, -24));
  EXPECT_EQ(halfToFloat(0x03ff), std::ldexp(1023.0f, -24));
}

TEST(HalfFloat, EveryMidpointRoundsToNearestEven) {
  // Between each two neighbouring finite halves (and from 65504 to the Inf boundary 65536):
  // the exact midpoint goes to the even one, anything off it to the nearer one.
  for (uint32_t sign : {0u, 0x8000u})
    for (uint32_t bits = 0; bits < 0x7c00u; ++bits) {
      const uint16_t a = uint16_t(sign | bits), b = uint16_t(sign | (bits + 1));
      const float fa = halfToFloat(a);
      const float fb = bits + 1 == 0x7c00u ? (sign ? -65536.0f : 65536.0f) : halfToFloat(b);
      const float mid = 0.5f * (fa + fb);  // exact: a half has 11 significant bits
      ASSERT_EQ(floatToHalf(mid), (a & 1u) ? b : a) << "between " << fa << " and " << fb;
      ASSERT_EQ(floatToHalf(std::nextafter(mid, fa)), a) << "below " << mid;
      ASSERT_EQ(floatToHalf(std::nextafter(mid, fb)), b) << "above " << mid;
    }
}

// ---- Size of a real level --------------------------------------------------------------------

TEST(TransportFile, LargeTransportSavesAndLoadsQuickly) {
  // About the size of Sponza's transport (~50 MB): informational timings, no assertion on them.
  Shape big;
  big.texels = 600000;
  big.clusters = 15000;
  big.points = 190000;
  big.backRows = 4000;
  big.linksPerRow = 20;
  big.atlasSides[0][0] = big.atlasSides[0][1] = 1024;
  big.atlasSides[1][0] = 512;
  big.atlasSides[1][1] = 256;
  big.atlasSides[2][0] = big.atlasSides[2][1] = 64;
  const TransportData data = makeTransport(big);
  ASSERT_EQ(data.validate(), "");

  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); };
  const std::string path = tempPath("large.agt");
  std::string error;
  const auto t0 = Clock::now();
  ASSERT_TRUE(saveTransport(data, path, &error)) << error;
  const auto t1 = Clock::now();
  TransportData loaded;
  ASSERT_TRUE(loadTransport(path, loaded, &error)) << error;
  const auto t2 = Clock::now();
  const double mb = double(std::filesystem::file_size(path)) / 1e6;
  // In memory, without the disk: serialising, then parsing.
  const auto t2b = Clock::now();
  std::vector<uint8_t> bytes = serializeTransport(data);
  const auto t3 = Clock::now();
  TransportData parsed;
  ASSERT_TRUE(parseTransport(bytes.data(), bytes.size(), parsed, &error)) << error;
  const auto t4 = Clock::now();
  const auto t5 = Clock::now();
  const uint64_t checksum = transportChecksum(bytes.data(), bytes.size());
  const auto t6 = Clock::now();
  EXPECT_EQ(parsed.validate(), "");
  const auto t7 = Clock::now();
  std::printf(
      "[ transport ] %.1f MB: save %.1f ms (%.0f MB/s), load %.1f ms (%.0f MB/s); in memory: "
      "serialise %.1f ms, parse %.1f ms (%.0f MB/s; of which checksum %.1f ms, validate() "
      "%.1f ms) [%016llx]\n",
      mb, ms(t1 - t0), mb / ms(t1 - t0) * 1e3, ms(t2 - t1), mb / ms(t2 - t1) * 1e3,
      ms(t3 - t2b), ms(t4 - t3), mb / ms(t4 - t3) * 1e3, ms(t6 - t5), ms(t7 - t6),
      (unsigned long long)checksum);
  RecordProperty("file_mb", std::to_string(mb));
  RecordProperty("save_ms", std::to_string(ms(t1 - t0)));
  RecordProperty("load_ms", std::to_string(ms(t2 - t1)));
  EXPECT_GT(mb, 40.0);
  expectEqual(data, loaded);
  std::filesystem::remove(path);
}

// A name read from a file is quoted with its control bytes escaped, so an error stays one line
// (the transport fuzzer's input: a reflection probe named with a newline and resolution 0).
TEST(TransportFile, ErrorsQuoteNamesOnOneLine) {
  ReflectionTransport r;
  ReflectionProbeCapture probe;
  probe.name = std::string("h\x9f\n\0x", 5);
  probe.resolution = 0;
  r.probes.push_back(probe);
  const std::string why = r.validate(0, 0);
  EXPECT_EQ(why.find('\n'), std::string::npos) << why;
  EXPECT_EQ(why.find('\0'), std::string::npos) << why;
  EXPECT_NE(why.find("'h\x9f\\x0a\\x00x'"), std::string::npos) << why;
}

}  // namespace
}  // namespace afterglow::runtime
