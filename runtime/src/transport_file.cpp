// The transport file: format in transport_file.h. The writer measures the file first, then fills
// one buffer; the reader bounds every count by the bytes left in its section before it allocates.
#include "afterglow/runtime/transport_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <new>
#include <system_error>
#include <type_traits>

namespace afterglow::runtime {

// The format is little-endian and arrays are memcpy'd as they are.
#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__)
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the transport file is little-endian; this host is not");
#endif
static_assert(sizeof(float) == 4 && sizeof(glm::vec3) == 12 &&
                  std::is_trivially_copyable<glm::vec3>::value,
              "vec3 arrays are copied as 3 packed floats");

namespace {

// ---- XXH64 -----------------------------------------------------------------------------------

constexpr uint64_t kP1 = 0x9E3779B185EBCA87ull, kP2 = 0xC2B2AE3D27D4EB4Full,
                   kP3 = 0x165667B19E3779F9ull, kP4 = 0x85EBCA77C2B2AE63ull,
                   kP5 = 0x27D4EB2F165667C5ull;

inline uint64_t rotl(uint64_t x, int r) { return (x << r) | (x >> (64 - r)); }
inline uint64_t read64(const uint8_t* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}
inline uint32_t read32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
inline uint64_t round64(uint64_t acc, uint64_t input) {
  acc += input * kP2;
  return rotl(acc, 31) * kP1;
}
inline uint64_t merge64(uint64_t acc, uint64_t value) {
  acc ^= round64(0, value);
  return acc * kP1 + kP4;
}

// ---- Section ids -----------------------------------------------------------------------------

constexpr const char* kInfo = "INFO";
constexpr const char* kAtlases = "ATLS";
constexpr const char* kMaterials = "MATL";
constexpr const char* kSources = "SRCS";
constexpr const char* kClusters = "CLUS";
constexpr const char* kFarClusters = "FARC";
constexpr const char* kSharedFar = "SFAR";
constexpr const char* kLinks = "LINK";
constexpr const char* kClusterGather = "CGAT";
constexpr const char* kGatherMaps = "GMAP";
constexpr const char* kTexelSky = "TSKY";
constexpr const char* kClusterSky = "CSKY";
constexpr const char* kProbes = "PROB";
constexpr const char* kReflections = "REFL";
constexpr const char* kLightmap = "LAYR";
constexpr const char* kGeometry = "GEOM";
constexpr const char* kRequired[] = {kInfo,      kAtlases,      kMaterials,   kSources,
                                     kClusters,  kFarClusters,  kSharedFar,   kLinks,
                                     kClusterGather, kGatherMaps, kTexelSky,  kClusterSky,
                                     kProbes,    kReflections,  kLightmap,    kGeometry};
constexpr size_t kSectionCount = sizeof(kRequired) / sizeof(kRequired[0]);

constexpr size_t kEntrySize = 32;    // one section table entry
constexpr size_t kChecksumAt = 32;   // the checksum field in the header
constexpr int kMaxFilterPasses = 1024;  // more would only make a hostile file hang the solver

inline uint64_t align16(uint64_t x) { return (x + 15) & ~uint64_t(15); }

// A section id for messages: printable ASCII as is, anything else as \xNN.
std::string idText(const uint8_t* id) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const uint8_t c = id[i];
    if (c >= 0x20 && c < 0x7f && c != '\'' && c != '\\') {
      s += char(c);
    } else {
      static const char* hex = "0123456789abcdef";
      s += "\\x";
      s += hex[c >> 4];
      s += hex[c & 15];
    }
  }
  return s;
}

// ---- Writer ----------------------------------------------------------------------------------

// Appends fields at `pos`; with no buffer it only measures.
struct Out {
  uint8_t* buf = nullptr;
  size_t pos = 0;

  void put(const void* data, size_t n) {
    if (buf && n) std::memcpy(buf + pos, data, n);
    pos += n;
  }
  template <class T>
  void scalar(T v) {
    static_assert(std::is_trivially_copyable<T>::value, "");
    put(&v, sizeof(T));
  }
  void vec3(const glm::vec3& v) { put(&v, 12); }
  void string(const std::string& s) {
    scalar(uint32_t(s.size()));
    put(s.data(), s.size());
  }
  // Padding bytes stay zero: the buffer starts zeroed.
  void align() { pos = size_t(align16(pos)); }
  template <class T>
  void array(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable<T>::value, "");
    align();
    scalar(uint64_t(v.size()));
    scalar(uint64_t(0));
    put(v.data(), v.size() * sizeof(T));
  }
  template <class SparseT>
  void sparse(const std::vector<uint32_t>& rowStart, const std::vector<uint32_t>& column,
              const std::vector<SparseT>& weight) {
    array(rowStart);
    array(column);
    array(weight);
  }
  void links(const SparseLinks& m) {
    scalar(m.targetBits);
    array(m.rowStart);
    array(m.link);
    array(m.rowScale);
  }
  // An atlas's fields, in ATLS and LAYR alike.
  void atlas(const AtlasLayout& a) {
    scalar(int32_t(a.width));
    scalar(int32_t(a.height));
    array(a.texelOfPixel);
    array(a.mixPixel);
    array(a.mixStart);
    array(a.mixTexel);
    array(a.mixWeight);
  }
};

uint64_t rowsOf(const std::vector<uint32_t>& rowStart) {
  return rowStart.empty() ? 0 : rowStart.size() - 1;
}

struct SectionWriter {
  const char* id;
  uint64_t count;
  void (*write)(const TransportData&, Out&);
};

const SectionWriter kWriters[] = {
    {kInfo, 1,
     [](const TransportData& d, Out& o) {
       o.scalar(d.texelCount);
       o.scalar(d.clusterCount);
       o.scalar(d.gatherPointCount);
       o.scalar(int32_t(d.filterPasses));
       o.scalar(d.indirectIntensity);
       o.scalar(d.albedoBoost);
       for (int i = 0; i < kShCount; ++i) o.vec3(d.skySh[i]);
     }},
    {kAtlases, 0,
     [](const TransportData& d, Out& o) {
       for (const AtlasLayout& a : d.atlases) o.atlas(a);
     }},
    {kMaterials, 0,
     [](const TransportData& d, Out& o) {
       for (const MaterialParams& m : d.materials) {
         o.string(m.name);
         o.vec3(m.albedo);
         o.vec3(m.emission);
       }
     }},
    {kSources, 0,
     [](const TransportData& d, Out& o) {
       for (const Source& s : d.sources) {
         o.string(s.name);
         o.scalar(uint8_t(s.kind));
         o.scalar(uint8_t(s.enabled ? 1 : 0));
         o.scalar(uint8_t(s.mode));
         o.scalar(uint8_t(0));
         o.scalar(s.material);
         o.vec3(s.color);
         o.scalar(s.intensity);
         o.scalar(s.bounceIntensity);
         o.array(s.texelTransfer);
         o.array(s.clusterTransfer);
         o.array(s.probeTransfer);
       }
     }},
    {kClusters, 0,
     [](const TransportData& d, Out& o) {
       o.array(d.clusterMaterial);
       o.array(d.clusterAlbedoTexture);
       o.array(d.clusterEmissionTexture);
     }},
    {kFarClusters, 0,
     [](const TransportData& d, Out& o) {
       o.sparse(d.farClusters.rowStart, d.farClusters.column, d.farClusters.weight);
     }},
    {kSharedFar, 0, [](const TransportData& d, Out& o) { o.links(d.sharedFar); }},
    {kLinks, 0, [](const TransportData& d, Out& o) { o.links(d.links); }},
    {kClusterGather, 0,
     [](const TransportData& d, Out& o) {
       o.sparse(d.clusterGather.rowStart, d.clusterGather.column, d.clusterGather.weight);
     }},
    {kGatherMaps, 0,
     [](const TransportData& d, Out& o) {
       o.array(d.texelPoint);
       o.array(d.texelNeighbours);
     }},
    {kTexelSky, 0, [](const TransportData& d, Out& o) { o.array(d.texelSky); }},
    {kClusterSky, 0, [](const TransportData& d, Out& o) { o.array(d.clusterSky); }},
    {kProbes, 0,
     [](const TransportData& d, Out& o) {
       const ProbeTransport& p = d.probes;
       o.scalar(p.bins);
       o.array(p.mesh.positions);
       o.array(p.mesh.tetrahedra);
       o.array(p.mesh.neighbours);
       o.array(p.binSh);
       o.links(p.links);
       o.array(p.sky);
       o.array(p.depth);
     }},
    {kReflections, 0,
     [](const TransportData& d, Out& o) {
       const ReflectionTransport& r = d.reflections;
       o.scalar(r.bounces);
       o.array(r.bakedAlbedo);
       for (const ReflectionProbeCapture& p : r.probes) {
         const ReflectionProbeBox& b = p.box;
         o.string(p.name);
         o.scalar(p.resolution);
         o.scalar(p.firstHit);
         o.vec3(b.centre);
         for (int a = 0; a < 3; ++a) o.vec3(b.axes[a]);
         o.vec3(b.halfSize);
         o.scalar(b.blendDistance);
         o.scalar(int32_t(b.importance));
         o.scalar(uint32_t(b.boxProjection ? 1 : 0));
         o.vec3(b.capturePosition);
         o.vec3(b.projectionCentre);
         o.vec3(b.projectionHalfSize);
       }
       o.array(r.hits);
     }},
    {kLightmap, 0,
     [](const TransportData& d, Out& o) {
       const LightmapLayers& l = d.lightmap;
       o.scalar(l.texelCount);
       o.scalar(uint32_t(l.atlases.size()));
       for (const AtlasLayout& a : l.atlases) o.atlas(a);
       o.array(l.corners);
       o.scalar(uint32_t(l.direct.size()));
       for (const std::vector<uint16_t>& direct : l.direct) o.array(direct);
       o.array(l.directScale);
     }},
    {kGeometry, 0,
     [](const TransportData& d, Out& o) {
       o.array(d.clusterPosition);
       o.array(d.pointPosition);
       o.array(d.pointNormal);
     }},
};
static_assert(sizeof(kWriters) / sizeof(kWriters[0]) == kSectionCount, "");

// The table's element count of each section (see the header comment).
uint64_t sectionCount(const TransportData& d, const char* id) {
  if (id == kInfo) return 1;
  if (id == kAtlases) return d.atlases.size();
  if (id == kMaterials) return d.materials.size();
  if (id == kSources) return d.sources.size();
  if (id == kClusters) return d.clusterMaterial.size();
  if (id == kFarClusters) return rowsOf(d.farClusters.rowStart);
  if (id == kSharedFar) return rowsOf(d.sharedFar.rowStart);
  if (id == kLinks) return rowsOf(d.links.rowStart);
  if (id == kClusterGather) return rowsOf(d.clusterGather.rowStart);
  if (id == kGatherMaps) return d.texelPoint.size();
  if (id == kTexelSky) return d.texelSky.size();
  if (id == kProbes) return d.probes.count();
  if (id == kReflections) return d.reflections.count();
  if (id == kLightmap) return d.lightmap.texelCount;
  if (id == kGeometry) return d.pointPosition.size();
  return d.clusterSky.size();  // kClusterSky
}

// ---- Reader ----------------------------------------------------------------------------------

// Reads one section's fields from [pos, end) of the file image; on failure `why` says what.
struct In {
  const uint8_t* file;
  uint64_t pos, end;
  std::string why;

  uint64_t left() const { return end - pos; }
  bool fail(const std::string& message) {
    if (why.empty()) why = message;
    return false;
  }
  bool get(void* out, size_t n, const char* what) {
    if (left() < n)
      return fail(std::string(what) + ": needs " + std::to_string(n) + " bytes, " +
                  std::to_string(left()) + " left in the section");
    std::memcpy(out, file + pos, n);
    pos += n;
    return true;
  }
  template <class T>
  bool scalar(T& v, const char* what) {
    return get(&v, sizeof(T), what);
  }
  bool vec3(glm::vec3& v, const char* what) { return get(&v, 12, what); }
  bool string(std::string& s, const char* what) {
    uint32_t n = 0;
    if (!scalar(n, what)) return false;
    if (n > left())
      return fail(std::string(what) + ": a string of " + std::to_string(n) + " bytes, " +
                  std::to_string(left()) + " left in the section");
    s.assign(reinterpret_cast<const char*>(file + pos), n);
    pos += n;
    return true;
  }
  // Section payloads start 16-aligned in the file, so aligning the file offset aligns within
  // the section too.
  bool align(const char* what) {
    const uint64_t next = align16(pos);
    if (next > end)
      return fail(std::string(what) + ": the section ends before it");
    pos = next;
    return true;
  }
  template <class T>
  bool array(std::vector<T>& v, const char* what) {
    static_assert(std::is_trivially_copyable<T>::value, "");
    uint64_t n = 0, zero = 0;
    if (!align(what) || !scalar(n, what) || !scalar(zero, what)) return false;
    // The count is bounded by the bytes left before anything is allocated.
    if (n > left() / sizeof(T))
      return fail(std::string(what) + ": " + std::to_string(n) + " values of " +
                  std::to_string(sizeof(T)) + " bytes, " + std::to_string(left()) +
                  " bytes left in the section");
    v.resize(size_t(n));
    if (n) std::memcpy(v.data(), file + pos, size_t(n) * sizeof(T));
    pos += n * sizeof(T);
    return true;
  }
  // Row offsets: never empty (a matrix of no rows has the single offset 0).
  bool rowStart(std::vector<uint32_t>& v, const char* what) {
    if (!array(v, what)) return false;
    if (v.empty()) return fail(std::string(what) + ": no row offsets (not even the first 0)");
    return true;
  }
  // Before reserving `count` records of at least `minBytes` bytes each.
  bool records(uint64_t count, uint64_t minBytes, const char* what) {
    if (count > left() / minBytes)
      return fail(std::to_string(count) + " " + what + " cannot fit in " +
                  std::to_string(left()) + " bytes");
    return true;
  }
};

// `count` atlases' fields (Out::atlas), ATLS's or LAYR's, named `one` and `many` in errors.
bool readAtlases(In& in, uint64_t count, std::vector<AtlasLayout>& atlases, const char* one,
                 const char* many) {
  // Two ints and five array headers at least.
  if (!in.records(count, 8 + 5 * 16, many)) return false;
  atlases.resize(size_t(count));
  for (uint64_t a = 0; a < count; ++a) {
    AtlasLayout& l = atlases[size_t(a)];
    int32_t width = 0, height = 0;
    if (!in.scalar(width, "atlas width") || !in.scalar(height, "atlas height") ||
        !in.array(l.texelOfPixel, "atlas pixels") || !in.array(l.mixPixel, "mix pixels") ||
        !in.array(l.mixStart, "mix offsets") || !in.array(l.mixTexel, "mix texels") ||
        !in.array(l.mixWeight, "mix weights")) {
      in.why = std::string(one) + " " + std::to_string(a) + ": " + in.why;
      return false;
    }
    l.width = width;
    l.height = height;
  }
  return true;
}

template <class T>
bool readSparse(In& in, std::vector<uint32_t>& rowStart, std::vector<uint32_t>& column,
                std::vector<T>& weight) {
  return in.rowStart(rowStart, "row offsets") && in.array(column, "columns") &&
         in.array(weight, "weights");
}

bool readSection(const char* id, In& in, TransportData& d, uint64_t count) {
  if (id == kInfo) {
    int32_t passes = 0;
    bool ok = in.scalar(d.texelCount, "texel count") &&
              in.scalar(d.clusterCount, "cluster count") &&
              in.scalar(d.gatherPointCount, "gather point count") &&
              in.scalar(passes, "filter passes") &&
              in.scalar(d.indirectIntensity, "indirect intensity") &&
              in.scalar(d.albedoBoost, "albedo boost");
    for (int i = 0; ok && i < kShCount; ++i) ok = in.vec3(d.skySh[i], "sky SH");
    if (!ok) return false;
    if (passes < 0 || passes > kMaxFilterPasses)
      return in.fail("filter passes " + std::to_string(passes) + " outside [0, " +
                     std::to_string(kMaxFilterPasses) + "]");
    d.filterPasses = passes;
    return true;
  }
  if (id == kAtlases) return readAtlases(in, count, d.atlases, "atlas", "atlases");
  if (id == kMaterials) {
    if (!in.records(count, 4 + 24, "materials")) return false;
    d.materials.resize(size_t(count));
    for (uint64_t m = 0; m < count; ++m) {
      MaterialParams& p = d.materials[size_t(m)];
      if (!in.string(p.name, "name") || !in.vec3(p.albedo, "albedo") ||
          !in.vec3(p.emission, "emission")) {
        in.why = "material " + std::to_string(m) + ": " + in.why;
        return false;
      }
    }
    return true;
  }
  if (id == kSources) {
    if (!in.records(count, 4 + 8 + 20 + 3 * 16, "sources")) return false;
    d.sources.resize(size_t(count));
    for (uint64_t i = 0; i < count; ++i) {
      Source& s = d.sources[size_t(i)];
      uint8_t kind = 0, enabled = 0, mode = 0, reserved = 0;
      const bool ok = in.string(s.name, "name") && in.scalar(kind, "kind") &&
                      in.scalar(enabled, "enabled") && in.scalar(mode, "mode") &&
                      in.scalar(reserved, "reserved") &&
                      in.scalar(s.material, "material") && in.vec3(s.color, "colour") &&
                      in.scalar(s.intensity, "intensity") &&
                      in.scalar(s.bounceIntensity, "bounce intensity") &&
                      (kind <= uint8_t(SourceKind::Emissive) ||
                       in.fail("unknown kind " + std::to_string(kind))) &&
                      (enabled <= 1 || in.fail("enabled is " + std::to_string(enabled))) &&
                      (mode <= uint8_t(LightMode::Realtime) ||
                       in.fail("unknown light mode " + std::to_string(mode))) &&
                      in.array(s.texelTransfer, "texel transfer") &&
                      in.array(s.clusterTransfer, "cluster transfer") &&
                      in.array(s.probeTransfer, "probe transfer");
      if (!ok) {
        in.why = "source " + std::to_string(i) + ": " + in.why;
        return false;
      }
      s.kind = SourceKind(kind);
      s.enabled = enabled != 0;
      s.mode = LightMode(mode);
    }
    return true;
  }
  if (id == kClusters) {
    if (!in.array(d.clusterMaterial, "cluster materials") ||
        !in.array(d.clusterAlbedoTexture, "cluster albedo textures") ||
        !in.array(d.clusterEmissionTexture, "cluster emission textures"))
      return false;
    if (count != d.clusterMaterial.size())
      return in.fail("the table says " + std::to_string(count) + " clusters, the section has " +
                     std::to_string(d.clusterMaterial.size()));
    return true;
  }
  if (id == kProbes) {
    ProbeTransport& p = d.probes;
    if (!in.scalar(p.bins, "regions per probe") || !in.array(p.mesh.positions, "probe positions") ||
        !in.array(p.mesh.tetrahedra, "tetrahedra") || !in.array(p.mesh.neighbours, "neighbours") ||
        !in.array(p.binSh, "region SH") || !in.scalar(p.links.targetBits, "target bits") ||
        !in.rowStart(p.links.rowStart, "row offsets") || !in.array(p.links.link, "links") ||
        !in.array(p.links.rowScale, "row scales") || !in.array(p.sky, "probe sky transfer") ||
        !in.array(p.depth, "probe depth maps"))
      return false;
    if (count != p.count())
      return in.fail("the table says " + std::to_string(count) + " probes, the section has " +
                     std::to_string(p.count()));
    return true;
  }
  if (id == kReflections) {
    ReflectionTransport& r = d.reflections;
    if (!in.scalar(r.bounces, "reflection bounces") ||
        !in.array(r.bakedAlbedo, "baked albedos"))
      return false;
    // A name's length, two counts and 26 scalars at least.
    if (!in.records(count, 4 + 4 + 8 + 26 * 4, "reflection probes")) return false;
    r.probes.resize(size_t(count));
    for (uint64_t i = 0; i < count; ++i) {
      ReflectionProbeCapture& p = r.probes[size_t(i)];
      ReflectionProbeBox& b = p.box;
      int32_t importance = 0;
      uint32_t projection = 0;
      bool ok = in.string(p.name, "name") && in.scalar(p.resolution, "resolution") &&
                in.scalar(p.firstHit, "first hit") && in.vec3(b.centre, "centre");
      for (int a = 0; ok && a < 3; ++a) ok = in.vec3(b.axes[a], "axes");
      ok = ok && in.vec3(b.halfSize, "half size") &&
           in.scalar(b.blendDistance, "blend distance") && in.scalar(importance, "importance") &&
           in.scalar(projection, "box projection") &&
           (projection <= 1 || in.fail("box projection is " + std::to_string(projection))) &&
           in.vec3(b.capturePosition, "capture position") &&
           in.vec3(b.projectionCentre, "projection centre") &&
           in.vec3(b.projectionHalfSize, "projection half size");
      if (!ok) {
        in.why = "reflection probe " + std::to_string(i) + ": " + in.why;
        return false;
      }
      b.importance = importance;
      b.boxProjection = projection != 0;
    }
    return in.array(r.hits, "reflection hits");
  }
  if (id == kLightmap) {
    LightmapLayers& l = d.lightmap;
    uint32_t atlases = 0, sources = 0;
    if (!in.scalar(l.texelCount, "lightmap texel count")) return false;
    if (count != l.texelCount)
      return in.fail("the table says " + std::to_string(count) +
                     " lightmap texels, the section has " + std::to_string(l.texelCount));
    if (!in.scalar(atlases, "lightmap atlas count") ||
        !readAtlases(in, atlases, l.atlases, "lightmap atlas", "lightmap atlases") ||
        !in.array(l.corners, "indirect corners") || !in.scalar(sources, "direct light count") ||
        !in.records(sources, 16, "direct light layers"))  // an array header at least
      return false;
    l.direct.resize(sources);
    for (uint32_t s = 0; s < sources; ++s)
      if (!in.array(l.direct[s], "direct light")) {
        in.why = "source " + std::to_string(s) + ": " + in.why;
        return false;
      }
    return in.array(l.directScale, "direct light scales");
  }
  if (id == kGeometry) {
    if (!in.array(d.clusterPosition, "cluster positions") ||
        !in.array(d.pointPosition, "gather point positions") ||
        !in.array(d.pointNormal, "gather point normals"))
      return false;
    if (count != d.pointPosition.size())
      return in.fail("the table says " + std::to_string(count) + " gather points, the section has " +
                     std::to_string(d.pointPosition.size()));
    return true;
  }
  const std::vector<uint32_t>* rowStart = nullptr;
  if (id == kLinks || id == kSharedFar) {
    SparseLinks& m = id == kLinks ? d.links : d.sharedFar;
    if (!in.scalar(m.targetBits, "target bits") || !in.rowStart(m.rowStart, "row offsets") ||
        !in.array(m.link, "links") || !in.array(m.rowScale, "row scales"))
      return false;
    rowStart = &m.rowStart;
  } else if (id == kFarClusters) {
    if (!readSparse(in, d.farClusters.rowStart, d.farClusters.column, d.farClusters.weight))
      return false;
    rowStart = &d.farClusters.rowStart;
  } else if (id == kClusterGather) {
    if (!readSparse(in, d.clusterGather.rowStart, d.clusterGather.column, d.clusterGather.weight))
      return false;
    rowStart = &d.clusterGather.rowStart;
  } else if (id == kGatherMaps) {
    if (!in.array(d.texelPoint, "texel points") ||
        !in.array(d.texelNeighbours, "texel neighbours"))
      return false;
    if (count != d.texelPoint.size())
      return in.fail("the table says " + std::to_string(count) + " texels, the section has " +
                     std::to_string(d.texelPoint.size()));
    return true;
  }
  if (rowStart) {
    if (count != rowsOf(*rowStart))
      return in.fail("the table says " + std::to_string(count) + " rows, the section has " +
                     std::to_string(rowsOf(*rowStart)));
    return true;
  }
  size_t values = 0;
  if (id == kTexelSky) {
    if (!in.array(d.texelSky, "texel sky transfer")) return false;
    values = d.texelSky.size();
  } else {  // kClusterSky
    if (!in.array(d.clusterSky, "cluster sky transfer")) return false;
    values = d.clusterSky.size();
  }
  if (count != values)
    return in.fail("the table says " + std::to_string(count) + " values, the section has " +
                   std::to_string(values));
  return true;
}

// The section a validate() complaint is about, from how it starts; null when unclear.
const char* sectionOfComplaint(const std::string& why) {
  static const struct {
    const char* prefix;
    const char* id;
  } kPrefixes[] = {{"lightmap layers", kLightmap},
                   {"directions", kGeometry},
                   {"reflection", kReflections},
                   {"probe", kProbes},
                   {"links", kLinks},
                   {"shared far fields", kSharedFar},
                   {"far clusters", kFarClusters},
                   {"cluster gather", kClusterGather},
                   {"gather maps", kGatherMaps},
                   {"gather point filter", kGatherMaps},
                   {"the gather point filter", kGatherMaps},
                   {"texel gather", kGatherMaps},
                   {"texel sky", kTexelSky},
                   {"cluster sky", kClusterSky},
                   {"per-cluster", kClusters},
                   {"cluster ", kClusters},
                   {"source", kSources},
                   {"atlas", kAtlases},
                   {"material", kMaterials}};
  for (const auto& p : kPrefixes)
    if (why.compare(0, std::strlen(p.prefix), p.prefix) == 0) return p.id;
  return nullptr;
}

bool parseImage(const uint8_t* bytes, size_t size, TransportData& d, std::string& why,
                const ParseOptions& options) {
  const std::string sizes = "the file has " + std::to_string(size) + " bytes";
  if (size < 8) {
    if (size > 0 && std::memcmp(bytes, kTransportMagic, size) == 0) {
      why = "truncated: " + sizes + ", its header alone has " +
            std::to_string(kTransportHeaderSize);
      return false;
    }
    why = "not an afterglow transport file";
    return false;
  }
  if (std::memcmp(bytes, kTransportMagic, 8) != 0) {
    why = "not an afterglow transport file";
    return false;
  }
  if (size < 12) {
    why = "truncated: " + sizes + ", its header alone has " + std::to_string(kTransportHeaderSize);
    return false;
  }
  const uint32_t version = read32(bytes + 8);
  if (version != kTransportVersion) {
    why = "version " + std::to_string(version) + "; this runtime reads version " +
          std::to_string(kTransportVersion) + ": re-bake with this afterglow";
    return false;
  }
  if (size < kTransportHeaderSize) {
    why = "truncated: " + sizes + ", its header alone has " + std::to_string(kTransportHeaderSize);
    return false;
  }
  const uint32_t headerSize = read32(bytes + 12);
  const uint64_t fileSize = read64(bytes + 16);
  const uint32_t sections = read32(bytes + 24);
  const uint32_t flags = read32(bytes + 28);
  if (headerSize != kTransportHeaderSize) {
    why = "header size " + std::to_string(headerSize) + ", version 1 has " +
          std::to_string(kTransportHeaderSize) + ": the file is corrupted";
    return false;
  }
  if (fileSize != size) {
    why = std::string(fileSize > size ? "truncated: " : "size mismatch: ") + sizes +
          ", its header says " + std::to_string(fileSize);
    return false;
  }
  if (options.verifyChecksum && transportChecksum(bytes, size) != read64(bytes + kChecksumAt)) {
    why = "checksum mismatch: the file is corrupted";
    return false;
  }
  if (flags != 0) {
    why = "unknown header flags " + std::to_string(flags);
    return false;
  }

  // The section table.
  const uint64_t tableEnd = uint64_t(headerSize) + uint64_t(sections) * kEntrySize;
  if (tableEnd > size) {
    why = "section table: " + std::to_string(sections) + " sections need " +
          std::to_string(tableEnd) + " bytes, " + sizes;
    return false;
  }
  struct Found {
    uint64_t offset = 0, size = 0, count = 0;
    bool present = false;
  } found[kSectionCount];
  uint64_t previousEnd = tableEnd;
  for (uint32_t i = 0; i < sections; ++i) {
    const uint8_t* entry = bytes + headerSize + size_t(i) * kEntrySize;
    const std::string name = "section '" + idText(entry) + "'";
    const uint32_t reserved = read32(entry + 4);
    const uint64_t offset = read64(entry + 8), bytesIn = read64(entry + 16),
                   count = read64(entry + 24);
    if (reserved != 0) {
      why = name + ": reserved table field is " + std::to_string(reserved);
      return false;
    }
    if (offset % 16 != 0) {
      why = name + ": offset " + std::to_string(offset) + " is not a multiple of 16";
      return false;
    }
    if (offset > size || bytesIn > size - offset) {
      why = name + ": bytes " + std::to_string(offset) + " + " + std::to_string(bytesIn) +
            " lie outside the file's " + std::to_string(size);
      return false;
    }
    if (offset < previousEnd) {
      why = name + ": offset " + std::to_string(offset) +
            (i == 0 ? " overlaps the section table" : " overlaps the section before it");
      return false;
    }
    previousEnd = offset + bytesIn;
    for (size_t k = 0; k < kSectionCount; ++k)
      if (std::memcmp(entry, kRequired[k], 4) == 0) {
        if (found[k].present) {
          why = name + " appears twice";
          return false;
        }
        found[k] = {offset, bytesIn, count, true};
      }
    // Any other id: a section of a later writer, skipped.
  }
  for (size_t k = 0; k < kSectionCount; ++k)
    if (!found[k].present) {
      why = "missing section '" + std::string(kRequired[k]) + "'";
      return false;
    }

  // The payloads.
  for (size_t k = 0; k < kSectionCount; ++k) {
    const char* id = kRequired[k];
    In in{bytes, found[k].offset, found[k].offset + found[k].size, {}};
    const std::string name = "section '" + std::string(id) + "'";
    if (id == kInfo && found[k].count != 1) {
      why = name + ": the table says " + std::to_string(found[k].count) + " entries, not 1";
      return false;
    }
    if (!readSection(id, in, d, found[k].count)) {
      why = name + ": " + in.why;
      return false;
    }
    if (in.pos != in.end) {
      why = name + ": " + std::to_string(in.end - in.pos) + " bytes left over";
      return false;
    }
  }

  // The texels' and gather points' maps from their source (as the baker made them), once the
  // source is sound and the gather points are no more than the rows read (which bounds what
  // the maps allocate by the file's size).
  if (std::string bad = checkGatherSource(d); !bad.empty()) {
    why = "section '" + std::string(kGatherMaps) + "': " + bad;
    return false;
  }
  if (d.links.rowStart.empty() || d.links.rows() < d.gatherPointCount) {
    why = "section '" + std::string(kLinks) + "': fewer rows than the " +
          std::to_string(d.gatherPointCount) + " gather points";
    return false;
  }
  buildGatherMaps(d);

  // Every index within its counts.
  const std::string complaint = d.validate();
  if (!complaint.empty()) {
    const char* id = sectionOfComplaint(complaint);
    why = id ? "section '" + std::string(id) + "': " + complaint : "invalid transport: " + complaint;
    return false;
  }
  return true;
}

}  // namespace

uint64_t xxh64(const void* data, size_t size, uint64_t seed) {
  const uint8_t* p = static_cast<const uint8_t*>(data);
  const uint8_t* const end = p + size;
  uint64_t h;
  if (size >= 32) {
    uint64_t v1 = seed + kP1 + kP2, v2 = seed + kP2, v3 = seed, v4 = seed - kP1;
    const uint8_t* const limit = end - 32;
    do {
      v1 = round64(v1, read64(p));
      v2 = round64(v2, read64(p + 8));
      v3 = round64(v3, read64(p + 16));
      v4 = round64(v4, read64(p + 24));
      p += 32;
    } while (p <= limit);
    h = rotl(v1, 1) + rotl(v2, 7) + rotl(v3, 12) + rotl(v4, 18);
    h = merge64(h, v1);
    h = merge64(h, v2);
    h = merge64(h, v3);
    h = merge64(h, v4);
  } else {
    h = seed + kP5;
  }
  h += uint64_t(size);
  for (; end - p >= 8; p += 8) h = rotl(h ^ round64(0, read64(p)), 27) * kP1 + kP4;
  if (end - p >= 4) {
    h = rotl(h ^ (uint64_t(read32(p)) * kP1), 23) * kP2 + kP3;
    p += 4;
  }
  for (; p < end; ++p) h = rotl(h ^ (uint64_t(*p) * kP5), 11) * kP1;
  h ^= h >> 33;
  h *= kP2;
  h ^= h >> 29;
  h *= kP3;
  h ^= h >> 32;
  return h;
}

uint64_t transportChecksum(const uint8_t* bytes, size_t size) {
  const uint64_t seed = xxh64(bytes, kChecksumAt, 0);
  return xxh64(bytes + kTransportHeaderSize, size - kTransportHeaderSize, seed);
}

std::vector<uint8_t> serializeTransport(const TransportData& data) {
  // Measure, then write into one zeroed buffer (padding stays zero).
  struct Placed {
    uint64_t offset, size, count;
  } placed[kSectionCount];
  Out measure;
  measure.pos = kTransportHeaderSize + kSectionCount * kEntrySize;
  for (size_t k = 0; k < kSectionCount; ++k) {
    measure.align();
    const size_t start = measure.pos;
    kWriters[k].write(data, measure);
    placed[k] = {start, measure.pos - start, sectionCount(data, kWriters[k].id)};
  }
  measure.align();

  std::vector<uint8_t> file(measure.pos, 0);
  Out out;
  out.buf = file.data();
  out.put(kTransportMagic, 8);
  out.scalar(kTransportVersion);
  out.scalar(kTransportHeaderSize);
  out.scalar(uint64_t(file.size()));
  out.scalar(uint32_t(kSectionCount));
  out.scalar(uint32_t(0));  // flags
  out.scalar(uint64_t(0));  // checksum, below
  for (size_t k = 0; k < kSectionCount; ++k) {
    out.put(kWriters[k].id, 4);
    out.scalar(uint32_t(0));
    out.scalar(placed[k].offset);
    out.scalar(placed[k].size);
    out.scalar(placed[k].count);
  }
  for (size_t k = 0; k < kSectionCount; ++k) {
    out.pos = size_t(placed[k].offset);
    kWriters[k].write(data, out);
  }
  const uint64_t checksum = transportChecksum(file.data(), file.size());
  std::memcpy(file.data() + kChecksumAt, &checksum, 8);
  return file;
}

bool saveTransport(const TransportData& data, const std::string& path, std::string* error) {
  auto failed = [&](const std::string& why) {
    if (error) *error = path + ": " + why;
    return false;
  };
  std::string complaint = data.validate();
  if (complaint.empty()) complaint = checkGatherSource(data);  // the file stores the maps' source
  if (!complaint.empty()) return failed("not saved, the transport is invalid: " + complaint);
  std::vector<uint8_t> bytes;
  try {
    bytes = serializeTransport(data);
  } catch (const std::bad_alloc&) {
    return failed("out of memory serialising the transport");
  }
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return failed(std::strerror(errno));
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  const int writeErrno = errno;
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed) {
    // What was written stays for the caller to remove (the baker writes a temporary name).
    const int why = !written ? writeErrno : errno;
    return failed(std::string("write failed: ") + std::strerror(why));
  }
  return true;
}

bool parseTransport(const uint8_t* bytes, size_t size, TransportData& out, std::string* error,
                    const ParseOptions& options) {
  out = TransportData{};
  std::string why;
  bool ok = false;
  try {
    TransportData data;
    ok = parseImage(bytes, size, data, why, options);
    if (ok) out = std::move(data);
  } catch (const std::bad_alloc&) {
    why = "out of memory reading the transport";
    ok = false;
  } catch (const std::exception& e) {
    why = std::string("cannot read the transport: ") + e.what();
    ok = false;
  }
  if (!ok && error) *error = why;
  return ok;
}

bool loadTransport(const std::string& path, TransportData& out, std::string* error) {
  out = TransportData{};
  auto failed = [&](const std::string& why) {
    if (error) *error = path + ": " + why;
    return false;
  };
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return failed(ec.message());
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return failed(std::strerror(errno));
  // One read into an uninitialised buffer (an 80 MB file should not be zeroed first).
  std::unique_ptr<uint8_t[]> buffer(size <= SIZE_MAX ? new (std::nothrow) uint8_t[size_t(size)]
                                                     : nullptr);
  if (!buffer) {
    std::fclose(f);
    return failed("out of memory reading " + std::to_string(size) + " bytes");
  }
  const size_t got = std::fread(buffer.get(), 1, size_t(size), f);
  const bool readError = std::ferror(f) != 0;
  const int readErrno = errno;
  std::fclose(f);
  if (readError) return failed(std::string("read failed: ") + std::strerror(readErrno));
  if (got != size)
    return failed("the file changed size while being read (" + std::to_string(got) + " of " +
                  std::to_string(size) + " bytes)");
  std::string why;
  if (!parseTransport(buffer.get(), got, out, &why)) return failed(why);
  return true;
}

}  // namespace afterglow::runtime
