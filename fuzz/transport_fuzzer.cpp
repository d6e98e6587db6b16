// libFuzzer target for the transport file reader: every input must give a TransportData or a
// one-line error, never a crash, a sanitizer report, a leak, a hang or an allocation much larger
// than the input.
//
// The checksum is off (ParseOptions::verifyChecksum = false) so mutations reach the section
// table and the payloads instead of all stopping at the checksum. A mutation that changes the
// length also breaks the header's file size, so an input whose size field disagrees is parsed a
// second time with the field patched. Whatever is accepted is then used the way a solver would
// (every index dereferenced, atlases resolved), and written and read back, which must give the
// same bytes.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "afterglow/runtime/transport_file.h"

using namespace afterglow::runtime;

namespace {

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "transport_fuzzer: %s\n", what);
  std::abort();
}

// Checks a row-compressed matrix the way a solver walks it: rows, offsets, every column.
template <class W>
double walk(const std::vector<uint32_t>& rowStart, const std::vector<uint32_t>& column,
            const std::vector<W>& weight, size_t columns, const char* what) {
  if (rowStart.empty() || rowStart.back() != column.size() || weight.size() != column.size())
    fail(what);
  double sum = 0.0;
  for (size_t r = 0; r + 1 < rowStart.size(); ++r) {
    if (rowStart[r] > rowStart[r + 1]) fail(what);
    for (uint32_t k = rowStart[r]; k < rowStart[r + 1]; ++k) {
      if (column[k] >= columns) fail(what);
      sum += double(weight[k]);
    }
  }
  return sum;
}

// Uses everything an engine would use, with its own bounds checks: validate() said it was safe.
void touch(const TransportData& t) {
  const size_t rows = t.links.rows();
  if (rows < t.gatherPointCount || t.links.rowScale.size() != rows) fail("links rows");
  std::vector<float> seen(t.linkTargetCount(), 0.0f);
  walk(t.farClusters.rowStart, t.farClusters.column, t.farClusters.weight, t.clusterCount,
       "far clusters");
  if (t.links.rowStart.size() != rows + 1 || t.links.rowStart.back() != t.links.size())
    fail("links offsets");
  for (size_t r = 0; r < rows; ++r)
    for (uint32_t k = t.links.rowStart[r]; k < t.links.rowStart[r + 1]; ++k) {
      if (t.links.targetAt(k) >= t.linkTargetCount()) fail("links");
      seen[t.links.targetAt(k)] += t.links.weightAt(r, k);
    }
  // The shared far fields gather clusters and far clusters only (the solver writes their
  // light after those: a shared field of shared fields would read a stale value).
  const SparseLinks& shared = t.sharedFar;
  if (shared.rowStart.size() != shared.rows() + 1 || shared.rowStart.back() != shared.size() ||
      shared.rowScale.size() != shared.rows())
    fail("shared far fields offsets");
  for (size_t r = 0; r < shared.rows(); ++r)
    for (uint32_t k = shared.rowStart[r]; k < shared.rowStart[r + 1]; ++k) {
      if (shared.targetAt(k) >= t.sharedFarBase()) fail("shared far fields");
      seen[shared.targetAt(k)] += shared.weightAt(r, k);
    }
  walk(t.clusterGather.rowStart, t.clusterGather.column, t.clusterGather.weight, rows,
       "cluster gather");
  if (t.clusterGather.rows() != t.clusterCount) fail("cluster gather rows");
  if (t.pointFilter.rows() != 0 && t.pointFilter.rows() != t.gatherPointCount)
    fail("point filter rows");
  if (t.filterPasses < 0 || (t.filterPasses > 0 && t.pointFilter.rows() != t.gatherPointCount))
    fail("filter passes");
  walk(t.pointFilter.rowStart, t.pointFilter.column, t.pointFilter.weight, t.gatherPointCount,
       "point filter");
  walk(t.texelGather.rowStart, t.texelGather.column, t.texelGather.weight, t.gatherPointCount,
       "texel gather");
  if (t.texelGather.rows() != t.texelCount) fail("texel gather rows");
  if (t.clusterMaterial.size() != t.clusterCount || t.clusterAlbedoTexture.size() != t.clusterCount ||
      t.clusterEmissionTexture.size() != t.clusterCount)
    fail("cluster arrays");
  for (uint32_t m : t.clusterMaterial)
    if (m >= t.materials.size()) fail("cluster material");
  for (const Source& s : t.sources) {
    if (!s.texelTransfer.empty() && s.texelTransfer.size() != t.texelCount) fail("texel transfer");
    if (!s.clusterTransfer.empty() && s.clusterTransfer.size() != t.clusterCount)
      fail("cluster transfer");
    if (s.kind == SourceKind::Emissive && s.material >= t.materials.size()) fail("source material");
    if (s.kind != SourceKind::Light && s.kind != SourceKind::Emissive) fail("source kind");
  }
  if (!t.texelSky.empty() && t.texelSky.size() != size_t(t.texelCount) * kShCount) fail("texel sky");
  if (!t.clusterSky.empty() && t.clusterSky.size() != size_t(t.clusterCount) * kShCount)
    fail("cluster sky");
  float sky = 0.0f;
  for (uint16_t h : t.texelSky) sky += halfToFloat(h);
  (void)sky;
  // The atlases, through the same code the bake and the runtime use.
  std::vector<glm::vec3> texels(t.texelCount, glm::vec3(1.0f)), image;
  for (const AtlasLayout& a : t.atlases) {
    if (a.width <= 0 || a.height <= 0 ||
        a.texelOfPixel.size() != size_t(a.width) * size_t(a.height))
      fail("atlas size");
    for (uint32_t p : a.texelOfPixel)
      if (p != kNoTexel && p >= t.texelCount) fail("atlas pixel");
    for (uint32_t p : a.mixPixel)
      if (p >= a.texelOfPixel.size()) fail("atlas mix pixel");
    walk(a.mixStart, a.mixTexel, a.mixWeight, t.texelCount, "atlas mixes");
    if (a.mixStart.size() != a.mixPixel.size() + 1) fail("atlas mix offsets");
    resolveAtlas(a, texels, image);
  }
  // Two resolutions: the lightmap's own atlases and texels, each texel's corners in the atlases
  // above (read through the runtime's cornerWeights), the direct light per lightmap texel.
  const LightmapLayers& l = t.lightmap;
  for (const Source& s : t.sources)
    if (l.active() && !s.texelTransfer.empty()) fail("texel transfer beside lightmap layers");
  if (l.corners.size() != l.texelCount || (l.active() && l.direct.size() != t.sources.size()) ||
      l.directScale.size() != l.direct.size())
    fail("lightmap layers");
  std::vector<glm::vec3> lightmapTexels(l.texelCount, glm::vec3(1.0f));
  for (const AtlasLayout& a : l.atlases) {
    // As the reflection capture samples it: a pixel at least.
    if (a.width <= 0 || a.height <= 0 ||
        a.texelOfPixel.size() != size_t(a.width) * size_t(a.height))
      fail("lightmap atlas size");
    for (uint32_t p : a.texelOfPixel)
      if (p != kNoTexel && p >= l.texelCount) fail("lightmap atlas pixel");
    for (uint32_t p : a.mixPixel)
      if (p >= a.texelOfPixel.size()) fail("lightmap atlas mix pixel");
    walk(a.mixStart, a.mixTexel, a.mixWeight, l.texelCount, "lightmap atlas mixes");
    if (a.mixStart.size() != a.mixPixel.size() + 1) fail("lightmap atlas mix offsets");
    resolveAtlas(a, lightmapTexels, image);
  }
  float bounced = 0.0f;
  for (const IndirectCorners& c : l.corners) {
    uint32_t texel[4];
    float weight[4];
    cornerWeights(c, t.atlases, texel, weight);
    for (int k = 0; k < 4; ++k)
      if (weight[k] > 0.0f) {
        if (texel[k] >= t.texelCount) fail("lightmap corner texel");
        bounced += weight[k] * texels[texel[k]].x;
      }
  }
  (void)bounced;
  for (const std::vector<uint16_t>& direct : l.direct) {
    if (!direct.empty() && direct.size() != l.texelCount) fail("lightmap direct light");
    for (uint16_t h : direct) sky += halfToFloat(h);
  }
  // Reflection hits (misses aside) sample the lightmap's atlases.
  for (const ReflectionHit& h : t.reflections.hits)
    if (h.material != kReflectionMiss && h.atlas != kReflectionNoAtlas &&
        h.atlas >= t.lightmapAtlases().size())
      fail("reflection hit atlas");
}

// Written and read back: accepted, and the same bytes again.
void roundTrip(const TransportData& t) {
  const std::vector<uint8_t> bytes = serializeTransport(t);
  TransportData again;
  std::string error;
  if (!parseTransport(bytes.data(), bytes.size(), again, &error)) {
    std::fprintf(stderr, "transport_fuzzer: re-reading what was written: %s\n", error.c_str());
    std::abort();
  }
  if (serializeTransport(again) != bytes) fail("written again, the bytes differ");
}

bool parse(const uint8_t* data, size_t size, TransportData& t) {
  ParseOptions options;
  options.verifyChecksum = false;
  std::string error;
  const bool ok = parseTransport(data, size, t, &error, options);
  if (!ok) {
    if (error.empty() || error.find('\n') != std::string::npos) fail("error is not one line");
    if (t.texelCount != 0 || !t.atlases.empty() || !t.sources.empty() || !t.links.link.empty())
      fail("a failed parse left data behind");
  }
  return ok;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > (1u << 20)) return 0;
  TransportData t;
  bool ok = parse(data, size, t);
  uint64_t declared = 0;
  if (!ok && size >= 24) std::memcpy(&declared, data + 16, 8);
  if (!ok && size >= 24 && declared != size) {
    std::vector<uint8_t> patched(data, data + size);
    const uint64_t actual = size;
    std::memcpy(patched.data() + 16, &actual, 8);
    ok = parse(patched.data(), patched.size(), t);
  }
  if (ok) {
    touch(t);
    roundTrip(t);
  }
  return 0;
}
