#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "afterglow/runtime/transport.h"
#include "printable_name.h"

namespace afterglow::runtime {

void resolveAtlas(const AtlasLayout& layout, const std::vector<glm::vec3>& texelValues,
                  std::vector<glm::vec3>& image) {
  image.assign(size_t(layout.width) * size_t(layout.height), glm::vec3(0.0f));
  refreshAtlas(layout, texelValues, image);
}

void refreshAtlas(const AtlasLayout& layout, const std::vector<glm::vec3>& texelValues,
                  std::vector<glm::vec3>& image) {
  const size_t pixels = std::min(size_t(layout.width) * size_t(layout.height), image.size());
  const size_t mapped = std::min(pixels, layout.texelOfPixel.size());
  // The arrays' pointers and sizes held once: a runtime refreshes every pixel every frame.
  const glm::vec3* values = texelValues.data();
  const size_t count = texelValues.size();
  const uint32_t* texelOf = layout.texelOfPixel.data();
  glm::vec3* out = image.data();
  for (size_t p = 0; p < mapped; ++p)
    if (texelOf[p] < count) out[p] = values[texelOf[p]];
  const uint32_t* mixStart = layout.mixStart.data();
  const uint32_t* mixTexel = layout.mixTexel.data();
  const float* mixWeight = layout.mixWeight.data();
  const size_t mixes =
      layout.mixStart.empty() ? 0 : std::min(layout.mixStart.size() - 1, layout.mixPixel.size());
  for (size_t i = 0; i < mixes; ++i) {
    const uint32_t p = layout.mixPixel[i];
    if (p >= pixels) continue;
    glm::vec3 sum(0.0f);
    for (uint32_t k = mixStart[i]; k < mixStart[i + 1]; ++k)
      if (mixTexel[k] < count) sum += mixWeight[k] * values[mixTexel[k]];
    out[p] = sum;
  }
}

void SparseMatrix::appendNormalisedRow(std::vector<std::pair<uint32_t, float>>& entries) {
  std::sort(entries.begin(), entries.end());
  double total = 0.0;
  for (const auto& e : entries) total += double(e.second);
  for (size_t i = 0; i < entries.size();) {
    size_t j = i;
    double w = 0.0;
    while (j < entries.size() && entries[j].first == entries[i].first) w += double(entries[j++].second);
    column.push_back(entries[i].first);
    weight.push_back(total > 0.0 ? float(w / total) : 0.0f);
    i = j;
  }
  rowStart.push_back(uint32_t(column.size()));
}

SparseMatrix normalisedRows(size_t count, const NormalisedRowFill& fill,
                            const ParallelFor& parallelFor) {
  constexpr size_t kRowsPerBlock = 4096;
  std::vector<SparseMatrix> blocks((count + kRowsPerBlock - 1) / kRowsPerBlock);
  auto build = [&](size_t begin, size_t end) {
    std::vector<std::pair<uint32_t, float>> entries;
    for (size_t b = begin; b < end; ++b)
      for (size_t r = b * kRowsPerBlock; r < std::min(count, (b + 1) * kRowsPerBlock); ++r) {
        entries.clear();
        fill(r, entries);
        blocks[b].appendNormalisedRow(entries);
      }
  };
  if (parallelFor) parallelFor(blocks.size(), build);
  else build(0, blocks.size());
  SparseMatrix out;
  size_t total = 0;
  for (const SparseMatrix& b : blocks) total += b.size();
  out.rowStart.reserve(count + 1);
  out.column.reserve(total);
  out.weight.reserve(total);
  for (const SparseMatrix& b : blocks) {
    const uint32_t base = uint32_t(out.column.size());
    for (size_t r = 1; r < b.rowStart.size(); ++r) out.rowStart.push_back(base + b.rowStart[r]);
    out.column.insert(out.column.end(), b.column.begin(), b.column.end());
    out.weight.insert(out.weight.end(), b.weight.begin(), b.weight.end());
  }
  return out;
}

uint32_t SparseLinks::bitsFor(uint32_t targets) {
  uint32_t bits = 1;
  while (bits < 32 && (uint64_t(1) << bits) < uint64_t(targets)) ++bits;
  return bits;
}

void SparseLinks::appendRow(const uint32_t* targets, const float* weights, size_t n) {
  float largest = 0.0f;
  double total = 0.0;
  for (size_t i = 0; i < n; ++i) largest = std::max(largest, weights[i]), total += double(weights[i]);
  const float top = float(maxCode());
  const float step = largest > 0.0f ? largest / top : 0.0f;
  uint64_t codes = 0;
  for (size_t i = 0; i < n && step > 0.0f; ++i) {
    // Rounded half up (weights are not negative) without a call to round().
    const double q = std::floor(double(weights[i] / step) + 0.5);
    if (!(q >= 1.0)) continue;
    const uint32_t code = uint32_t(std::min(q, double(top)));
    codes += code;
    link.push_back((code << targetBits) | targets[i]);
  }
  // The scale that keeps the row's sum (its energy): the codes' rounding errors, and weights
  // too small for a code, go to every link in proportion instead of being lost.
  rowScale.push_back(codes > 0 ? float(total / double(codes)) : 0.0f);
  const size_t length = link.size() - rowStart.back();
  if (length % kLinkGroup != 0)
    link.resize(link.size() + kLinkGroup - length % kLinkGroup, link.back() & targetMask());
  rowStart.push_back(uint32_t(link.size()));
}

size_t SparseLinks::linkCount() const {
  size_t n = 0;
  for (uint32_t entry : link) n += isPadding(entry, targetBits) ? 0 : 1;
  return n;
}

uint16_t floatToHalf(float value) {
  uint32_t f;
  std::memcpy(&f, &value, 4);
  const uint32_t sign = (f >> 16) & 0x8000u;
  const uint32_t exponent = (f >> 23) & 0xffu;
  uint32_t mantissa = f & 0x7fffffu;
  if (exponent == 0xffu)  // Inf and NaN (kept a NaN)
    return uint16_t(sign | 0x7c00u | (mantissa ? 0x200u : 0u));
  const int e = int(exponent) - 127 + 15;
  if (e >= 31) return uint16_t(sign | 0x7c00u);  // overflow: Inf
  if (e <= 0) {
    // Subnormal half (or zero): shift the mantissa with its implicit bit in, round to even.
    if (e < -10) return uint16_t(sign);
    mantissa |= 0x800000u;
    const uint32_t shift = uint32_t(14 - e);
    uint32_t half = mantissa >> shift;
    const uint32_t rest = mantissa & ((1u << shift) - 1u), halfway = 1u << (shift - 1u);
    if (rest > halfway || (rest == halfway && (half & 1u))) ++half;
    return uint16_t(sign | half);
  }
  uint32_t half = (uint32_t(e) << 10) | (mantissa >> 13);
  const uint32_t rest = mantissa & 0x1fffu;
  if (rest > 0x1000u || (rest == 0x1000u && (half & 1u))) ++half;  // may carry into Inf: right
  return uint16_t(sign | half);
}


glm::vec3 sourceScale(const TransportData& data, const Source& s) {
  if (!s.enabled) return glm::vec3(0.0f);
  if (s.kind == SourceKind::Emissive) return data.materials[s.material].emission;
  return s.color * s.intensity;
}

glm::vec3 directScale(const TransportData& data, const Source& s) {
  return s.mode == LightMode::Baked ? sourceScale(data, s) : glm::vec3(0.0f);
}

namespace {

// Checks a row-compressed matrix's shape: rows+1 ascending offsets ending at the entry count,
// and every column below `columns`.
template <class Column>
bool checkRows(const std::vector<uint32_t>& rowStart, const std::vector<Column>& column,
               size_t rows, size_t columns, const char* name, std::ostringstream& why) {
  if (rowStart.size() != rows + 1) {
    why << name << ": " << (rowStart.empty() ? 0 : rowStart.size() - 1) << " rows, expected "
        << rows;
    return false;
  }
  if (rowStart.front() != 0 || rowStart.back() != column.size()) {
    why << name << ": row offsets do not cover its " << column.size() << " entries";
    return false;
  }
  for (size_t r = 0; r < rows; ++r)
    if (rowStart[r] > rowStart[r + 1]) {
      why << name << ": row " << r << " ends before it starts";
      return false;
    }
  for (size_t k = 0; k < column.size(); ++k)
    if (size_t(column[k]) >= columns) {
      why << name << ": entry " << k << " refers to " << column[k] << " of " << columns;
      return false;
    }
  return true;
}

}  // namespace

namespace {

template <class T>
size_t bytesOf(const std::vector<T>& v) {
  return v.size() * sizeof(T);
}

size_t bytesOf(const SparseMatrix& m) {
  return bytesOf(m.rowStart) + bytesOf(m.column) + bytesOf(m.weight);
}

// A SparseLinks' shape, its target bits, and every target below `targets`.
bool checkLinks(const SparseLinks& m, size_t rows, size_t targets, const char* name,
                std::ostringstream& why) {
  if (m.targetBits < 1 || m.targetBits > 32 - kMinWeightBits) {
    why << name << ": " << m.targetBits << " target bits, expected 1 to " << 32 - kMinWeightBits;
    return false;
  }
  // The rows' shape here; their targets (the low bits of each link) below.
  if (!checkRows(m.rowStart, m.link, rows, SIZE_MAX, name, why)) return false;
  for (size_t r = 0; r < rows; ++r)
    if ((m.rowStart[r + 1] - m.rowStart[r]) % kLinkGroup != 0) {
      why << name << ": row " << r << " holds " << m.rowStart[r + 1] - m.rowStart[r]
          << " entries, not a multiple of " << kLinkGroup;
      return false;
    }
  for (size_t k = 0; k < m.size(); ++k)
    if (m.targetAt(k) >= targets) {
      why << name << ": entry " << k << " refers to " << m.targetAt(k) << " of " << targets;
      return false;
    }
  if (m.rowScale.size() != rows) {
    why << name << ": row scales do not match the rows";
    return false;
  }
  return true;
}

}  // namespace

size_t TransportData::memoryBytes() const {
  size_t b = bytesOf(links.rowStart) + bytesOf(links.link) + bytesOf(links.rowScale) +
             bytesOf(sharedFar.rowStart) + bytesOf(sharedFar.link) + bytesOf(sharedFar.rowScale) +
             bytesOf(farClusters) + bytesOf(clusterGather) + bytesOf(pointFilter) +
             bytesOf(texelGather) + bytesOf(texelPoint) + bytesOf(texelNeighbours) +
             bytesOf(texelSky) + bytesOf(clusterSky) + bytesOf(clusterMaterial) +
             bytesOf(clusterAlbedoTexture) + bytesOf(clusterEmissionTexture) +
             bytesOf(clusterPosition) + bytesOf(pointPosition) + bytesOf(pointNormal);
  for (const Source& s : sources)
    b += bytesOf(s.texelTransfer) + bytesOf(s.clusterTransfer) + bytesOf(s.probeTransfer);
  b += probeBytes() + reflectionBytes() + lightmap.memoryBytes();
  for (const AtlasLayout& a : atlases)
    b += bytesOf(a.texelOfPixel) + bytesOf(a.mixPixel) + bytesOf(a.mixStart) +
         bytesOf(a.mixTexel) + bytesOf(a.mixWeight);
  return b;
}

size_t TransportData::probeBytes() const {
  const ProbeTransport& p = probes;
  size_t b = bytesOf(p.mesh.positions) + bytesOf(p.mesh.tetrahedra) + bytesOf(p.mesh.neighbours) +
             bytesOf(p.binSh) + bytesOf(p.links.rowStart) + bytesOf(p.links.link) +
             bytesOf(p.links.rowScale) + bytesOf(p.sky) + bytesOf(p.depth);
  for (const Source& s : sources) b += bytesOf(s.probeTransfer);
  return b;
}

size_t TransportData::reflectionBytes() const {
  return bytesOf(reflections.hits) + bytesOf(reflections.bakedAlbedo) +
         reflections.probes.size() * sizeof(ReflectionProbeCapture);
}

std::string TransportData::validate() const {
  std::ostringstream why;
  const size_t texels = texelCount, clusters = clusterCount, points = gatherPointCount;
  // rows() is rowStart.size() - 1: an empty offset array would wrap around.
  if (links.rowStart.empty() || sharedFar.rowStart.empty() || clusterGather.rowStart.empty() ||
      pointFilter.rowStart.empty() || texelGather.rowStart.empty() || farClusters.rowStart.empty())
    return "a sparse matrix has no row offsets (not even the leading 0)";
  if (links.rows() < points) {
    why << "links: " << links.rows() << " rows, fewer than the " << points << " gather points";
    return why.str();
  }
  const size_t rows = links.rows();
  // Far clusters (each a mix of clusters) and shared far fields: with the clusters, no more
  // than links address.
  if (farClusters.rows() >= kMaxLinkTargets || sharedFar.rows() >= kMaxLinkTargets ||
      size_t(clusters) + farClusters.rows() + sharedFar.rows() > kMaxLinkTargets) {
    why << "links: " << clusters << " clusters, " << farClusters.rows() << " far clusters and "
        << sharedFar.rows() << " shared far fields, more than links address (" << kMaxLinkTargets
        << ")";
    return why.str();
  }
  if (!checkRows(farClusters.rowStart, farClusters.column, farClusters.rows(), clusters,
                 "far clusters", why))
    return why.str();
  if (farClusters.weight.size() != farClusters.column.size())
    return "far clusters: as many weights as columns";
  const size_t farBase = clusters + farClusters.rows();
  if (!checkLinks(sharedFar, sharedFar.rows(), farBase, "shared far fields", why) ||
      !checkLinks(links, rows, farBase + sharedFar.rows(), "links", why))
    return why.str();
  if (!checkRows(clusterGather.rowStart, clusterGather.column, clusters, rows, "cluster gather", why) ||
      !checkRows(pointFilter.rowStart, pointFilter.column,
                 pointFilter.rows() == 0 ? 0 : points, points, "gather point filter", why) ||
      !checkRows(texelGather.rowStart, texelGather.column, texels, points, "texel gather", why))
    return why.str();
  if (clusterGather.weight.size() != clusterGather.column.size() ||
      pointFilter.weight.size() != pointFilter.column.size() ||
      texelGather.weight.size() != texelGather.column.size())
    return "a sparse matrix has as many weights as columns";
  if (filterPasses < 0 || (filterPasses > 0 && pointFilter.rows() != points))
    return "the gather point filter does not cover the gather points";
  if (!texelPoint.empty() || !texelNeighbours.empty())
    if (std::string why2 = checkGatherSource(*this); !why2.empty()) return why2;
  if (clusterMaterial.size() != clusters || clusterAlbedoTexture.size() != clusters ||
      clusterEmissionTexture.size() != clusters) {
    why << "per-cluster material arrays do not have " << clusters << " entries";
    return why.str();
  }
  for (size_t c = 0; c < clusters; ++c)
    if (clusterMaterial[c] >= materials.size()) {
      why << "cluster " << c << " uses material " << clusterMaterial[c] << " of "
          << materials.size();
      return why.str();
    }
  if (hasDirections() || !clusterPosition.empty() || !pointNormal.empty()) {
    if (clusterPosition.size() != clusters || pointPosition.size() != points ||
        pointNormal.size() != points) {
      why << "directions: " << clusterPosition.size() << " cluster positions and "
          << pointPosition.size() << " gather point positions and " << pointNormal.size()
          << " normals, for " << clusters << " clusters and " << points << " gather points";
      return why.str();
    }
    auto finite = [](glm::vec3 v) {
      return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    };
    for (size_t c = 0; c < clusters; ++c)
      if (!finite(clusterPosition[c])) {
        why << "directions: cluster " << c << " has a position that is not finite";
        return why.str();
      }
    for (size_t p = 0; p < points; ++p)
      if (!finite(pointPosition[p]) || !finite(pointNormal[p])) {
        why << "directions: gather point " << p << " has a position or normal that is not finite";
        return why.str();
      }
  }
  if (!texelSky.empty() && texelSky.size() != texels * kShCount) return "texel sky transfer size";
  if (!clusterSky.empty() && clusterSky.size() != clusters * kShCount)
    return "cluster sky transfer size";
  // Light probes: the mesh (indices, orientation, neighbours), one row of links per region,
  // links to clusters and far clusters only, the sky transfer.
  const size_t probeCount = probes.count();
  if (probes.links.rowStart.empty()) return "probe links: no row offsets (not even the leading 0)";
  if (probeCount > 0) {
    for (size_t i = 0; i < probeCount; ++i)
      if (!std::isfinite(probes.mesh.positions[i].x) || !std::isfinite(probes.mesh.positions[i].y) ||
          !std::isfinite(probes.mesh.positions[i].z)) {
        why << "probes: probe " << i << " has a position that is not finite";
        return why.str();
      }
    if (std::string bad = checkProbeTetrahedra(probes.mesh); !bad.empty()) return "probes: " + bad;
    if (probes.bins == 0 || probes.bins > kMaxProbeRegions) {
      why << "probes: " << probes.bins << " regions per probe (1 to " << kMaxProbeRegions << ")";
      return why.str();
    }
    if (probes.binSh.size() != size_t(probes.bins) * kShCount)
      return "probes: region SH size does not match the regions";
    if (probes.sky.size() != probeCount * kProbeSkyCount)
      return "probes: sky transfer size does not match the probes";
    if (!probes.depth.empty() && probes.depth.size() != probeCount * 2 * 64)
      return "probes: depth maps' size does not match the probes";
  } else if (!probes.binSh.empty() || !probes.sky.empty() || probes.links.rows() != 0 ||
             !probes.depth.empty() ||
             !probes.mesh.tetrahedra.empty()) {
    return "probes: transfer without probes";
  }
  if (!checkLinks(probes.links, probeCount * probes.bins, farBase, "probe links", why))
    return why.str();
  for (size_t i = 0; i < sources.size(); ++i) {
    const Source& s = sources[i];
    // At two resolutions the texels are the indirect grid's: a source's direct light is per
    // lightmap texel, in the layers, and a texel transfer beside it would be counted twice.
    if (lightmap.active() && !s.texelTransfer.empty()) {
      why << "source " << i << " ('" << printableName(s.name)
          << "'): a texel transfer beside the lightmap layers' direct light";
      return why.str();
    }
    if ((!s.texelTransfer.empty() && s.texelTransfer.size() != texels) ||
        (!s.clusterTransfer.empty() && s.clusterTransfer.size() != clusters) ||
        (!s.probeTransfer.empty() && s.probeTransfer.size() != probeCount * kShCount)) {
      why << "source " << i << " ('" << printableName(s.name) << "'): transfer sizes do not match";
      return why.str();
    }
    if (s.kind == SourceKind::Emissive && s.material >= materials.size()) {
      why << "source " << i << " ('" << printableName(s.name) << "'): material " << s.material << " of "
          << materials.size();
      return why.str();
    }
  }
  for (size_t a = 0; a < atlases.size(); ++a) {
    const AtlasLayout& l = atlases[a];
    const size_t pixels = size_t(std::max(l.width, 0)) * size_t(std::max(l.height, 0));
    if (l.width <= 0 || l.height <= 0 || l.texelOfPixel.size() != pixels) {
      why << "atlas " << a << ": " << l.texelOfPixel.size() << " pixels for " << l.width << "x"
          << l.height;
      return why.str();
    }
    for (uint32_t t : l.texelOfPixel)
      if (t != kNoTexel && t >= texels) {
        why << "atlas " << a << ": a pixel refers to texel " << t << " of " << texels;
        return why.str();
      }
    if (l.mixPixel.size() + 1 != l.mixStart.size() || l.mixTexel.size() != l.mixWeight.size()) {
      why << "atlas " << a << ": mixes do not match their offsets";
      return why.str();
    }
    if (!checkRows(l.mixStart, l.mixTexel, l.mixPixel.size(), texels, "atlas mixes", why))
      return why.str();
    for (uint32_t p : l.mixPixel)
      if (p >= pixels) {
        why << "atlas " << a << ": a mix writes pixel " << p << " of " << pixels;
        return why.str();
      }
  }
  // The layers' corners read the indirect grid, i.e. the atlases above.
  if (std::string bad = lightmap.validate(sources.size(), atlases); !bad.empty()) return bad;
  // Reflection hits sample the lightmap, whichever resolution its texels are.
  return reflections.validate(materials.size(), lightmapAtlases().size());
}

}  // namespace afterglow::runtime
