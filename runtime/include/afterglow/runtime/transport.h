// TransportData: everything the runtime solver needs to re-light a baked level, and nothing that
// depends on light colour, intensity, sky, albedo or emission. The baker's precompute fills it;
// the transport file stores it; engines load it and call the Solver.
//
// Quantities are "E/π" (the outgoing radiance of a white Lambertian surface, the value a lightmap
// texel stores) per unit of source: a light of colour (1,1,1) and intensity 1, an emissive
// material of radiance 1, a sky SH coefficient of 1.
//
// This header depends on GLM and the standard library only, so engines can link it alone.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/atlas_layout.h"
#include "afterglow/runtime/lightmap_layers.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/reflection_capture.h"

namespace afterglow::runtime {

constexpr int kShCount = 9;               // SH L2 coefficients (bands 0..2)

// The eight atlas neighbours of a texel; kNeighbourOffsets[7 - k] is opposite kNeighbourOffsets[k].
constexpr int kNeighbourOffsets[8][2] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0},
                                         {1, 0},   {-1, 1}, {0, 1},  {1, 1}};

// Row-compressed sparse matrix of form factors, stored quantised in 4 bytes a link (the links
// are most of the transport, and streaming them is most of a bounce): a link's low targetBits
// bits are its target cluster, the rest a weight code, so row r links to target(k) with weight
// code(k) × rowScale[r] for k in [rowStart[r], rowStart[r+1]), targets ascending. A weight is
// the fraction of a point's cosine-weighted hemisphere that sees the target cluster; codes are
// relative to the row's largest weight, which takes the largest code (2^w - 1 for w =
// 32 - targetBits weight bits, at most 16), so each weight is within about half a code of that
// largest: 1/65535 of it when targets fit in 16 bits, 1/8191 with 19 (Sponza's clusters, far
// clusters and shared far fields). rowScale makes the codes sum to the row's exact sum, so
// rounding moves light between a row's links but neither adds nor loses any.
//
// Every row holds a multiple of kLinkGroup entries: a row's links are followed by up to three
// padding entries of code 0 (weightless, targeting the row's last target, which the bounce has
// just read). The bounce then reads four links at a time with no tail to finish: rows average
// a few dozen links, and the tail's varying length cost a mispredicted branch a row, about a
// fifth of the bounce.
constexpr uint32_t kLinkGroup = 4;
constexpr uint32_t kMinWeightBits = 10;
constexpr uint32_t kMaxWeightBits = 16;
constexpr uint32_t kMaxLinkTargets = 1u << (32 - kMinWeightBits);

struct SparseLinks {
  // Default: any target below kMaxLinkTargets, with the fewest weight bits.
  uint32_t targetBits = 32 - kMinWeightBits;
  std::vector<uint32_t> rowStart{0};
  std::vector<uint32_t> link;
  std::vector<float> rowScale;

  SparseLinks() = default;
  // Links to targets [0, targets); targets must not exceed kMaxLinkTargets.
  explicit SparseLinks(uint32_t targets) : targetBits(bitsFor(targets)) {}
  // The fewest bits that hold every index below `targets` (at least 1).
  static uint32_t bitsFor(uint32_t targets);

  size_t rows() const { return rowStart.size() - 1; }
  // Entries stored, padding included.
  size_t size() const { return link.size(); }
  // Links, without the padding (entries of code 0).
  size_t linkCount() const;
  static bool isPadding(uint32_t entry, uint32_t targetBits) { return (entry >> targetBits) == 0; }
  uint32_t targetMask() const { return (1u << targetBits) - 1u; }
  uint32_t maxCode() const {
    return targetBits >= 32 - kMaxWeightBits ? 0xffffffffu >> targetBits : (1u << kMaxWeightBits) - 1u;
  }
  uint32_t targetAt(size_t k) const { return link[k] & targetMask(); }
  float weightAt(size_t row, size_t k) const {
    return float(link[k] >> targetBits) * rowScale[row];
  }
  // Appends a row: n (target, form factor) pairs with ascending targets below 2^targetBits.
  // Weights that round to zero against the row's largest are left out (their share goes to
  // the others: the row keeps its sum); the row is padded to a multiple of kLinkGroup.
  void appendRow(const uint32_t* targets, const float* weights, size_t n);
};

// Row-compressed sparse matrix with float weights, for the small linear maps around the links
// (which gather points a cluster or a texel reads, the smoothing between gather points): row r
// is Σ weight[k] · x[column[k]] for k in [rowStart[r], rowStart[r+1]).
struct SparseMatrix {
  std::vector<uint32_t> rowStart{0};
  std::vector<uint32_t> column;
  std::vector<float> weight;

  size_t rows() const { return rowStart.size() - 1; }
  size_t size() const { return column.size(); }
  void appendRow(const uint32_t* columns, const float* weights, size_t n) {
    column.insert(column.end(), columns, columns + n);
    weight.insert(weight.end(), weights, weights + n);
    rowStart.push_back(uint32_t(column.size()));
  }
  // Appends a row of (column, weight) pairs in any order: sorts them (`entries` is left
  // sorted), sums a column's weights (in double) and scales the row to sum to one.
  void appendNormalisedRow(std::vector<std::pair<uint32_t, float>>& entries);
};

// Runs body(begin, end) over consecutive ranges covering [0, count), on as many threads as it
// likes, and returns when every range is done. The runtime splits its work into fixed blocks and
// hands their indices to this, so results never depend on how the ranges are spread.
using ParallelFor =
    std::function<void(size_t count, const std::function<void(size_t begin, size_t end)>& body)>;

// A matrix of `count` rows, row r appendNormalisedRow of the entries fill(r, entries) adds
// (entries arrive empty), built in fixed blocks, on parallelFor's threads when there is one, and
// joined in order: the same matrix either way. fill must be safe to call concurrently.
using NormalisedRowFill =
    std::function<void(size_t row, std::vector<std::pair<uint32_t, float>>& entries)>;
SparseMatrix normalisedRows(size_t count, const NormalisedRowFill& fill,
                            const ParallelFor& parallelFor = {});

// A source of direct light whose unit transfer was precomputed: a punctual light, or all the
// emissive surfaces of one material (area light, sampled explicitly by the baker).
enum class SourceKind : uint8_t { Light, Emissive };

// How a light's direct light is baked (Unity's light modes): Baked into the lightmaps and the
// light probes; Mixed and Realtime left to the engine, which lights with them itself: only their
// bounced light is baked (bounceIntensity applies as ever).
enum class LightMode : uint8_t { Baked, Mixed, Realtime };

struct Source {
  std::string name;      // light name, or material name for emissive sources
  SourceKind kind = SourceKind::Light;
  uint32_t material = 0; // for Emissive: the material whose emission drives it
  // Per-light settings as baked (the runtime may change them):
  glm::vec3 color{1.0f};
  float intensity = 1.0f;        // lux or candela, as in glTF
  float bounceIntensity = 1.0f;  // scales this light in bounced light only (Unity's meaning)
  bool enabled = true;
  LightMode mode = LightMode::Baked;  // emissive sources are always baked
  // Unit transfer (E/π per unit source), dense over texels and over clusters.
  std::vector<float> texelTransfer;
  std::vector<float> clusterTransfer;
  // Light probes: per probe, the radiance SH (kShCount values) this source sends to it
  // directly, per unit source (see ProbeTransport). Empty without probes.
  std::vector<float> probeTransfer;
};

// The reflective and emissive properties the runtime may change, per material.
struct MaterialParams {
  std::string name;
  glm::vec3 albedo{0.8f};    // diffuse albedo factor (linear RGB) used for bounces
  glm::vec3 emission{0.0f};  // emitted radiance (linear RGB)
};

// IEEE half precision, for the bulky per-texel sky transfer (the lightmaps are half floats
// anyway). Round to nearest even; no dependence on F16C.
uint16_t floatToHalf(float value);
// Inline: the reflection probes' capture passes read a few halves for every cubemap texel.
inline float halfToFloat(uint16_t half) {
  const uint32_t sign = uint32_t(half & 0x8000u) << 16;
  const uint32_t exponent = (half >> 10) & 0x1fu;
  uint32_t mantissa = half & 0x3ffu;
  uint32_t f;
  if (exponent == 0) {
    if (mantissa == 0) {
      f = sign;
    } else {  // subnormal: normalise
      int e = -1;
      do {
        ++e;
        mantissa <<= 1;
      } while (!(mantissa & 0x400u));
      f = sign | (uint32_t(127 - 15 - e) << 23) | ((mantissa & 0x3ffu) << 13);
    }
  } else if (exponent == 31) {
    f = sign | 0x7f800000u | (mantissa << 13);
  } else {
    f = sign | ((exponent + 127 - 15) << 23) | (mantissa << 13);
  }
  float out;
  std::memcpy(&out, &f, 4);
  return out;
}

// The sky transfer of a probe is a symmetric kShCount × kShCount matrix; its upper triangle
// (row-major, i <= j) is stored.
constexpr int kProbeSkyCount = kShCount * (kShCount + 1) / 2;
constexpr int probeSkyIndex(int i, int j) {
  return i <= j ? i * kShCount - i * (i - 1) / 2 + (j - i) : probeSkyIndex(j, i);
}

// Light probes (issue 14): each probe's radiance SH L2 (ShL2 in probe_sh.h: L_i = ∫ L(ω) Y_i(ω)
// dω) from the same solution as the lightmaps:
//
//   L_i(p) = Σ_s scale_s · probeTransfer_s[p][i]                   sources seen directly
//          + Σ_j K_p[i][j] · skySh_j                                 the sky through the gaps
//          + indirectIntensity · Σ_b binSh[b][i] · W_{p,b}            bounced light
//   W_{p,b} = Σ_j links[p·bins + b][j] · R_j                         (R as the lightmaps' rows read)
//
// The baker casts each probe's rays over the whole sphere, stratified in `bins` regions of
// equal solid angle; W_{p,b} is the mean reflected radiance its rays in region b reached
// (clusters, or far clusters seen from far enough; misses and absorbed rays count as 0), and
// binSh[b][i] = ∫_b Y_i dω, so bounced light enters as piecewise constant over the regions:
// one row of ordinary links a region instead of nine SH-weighted links a cluster, and the
// bounce's own inner loop. Direct light (lights, emissive surfaces) and the sky are projected
// ray by ray, exactly.
// The most regions a probe's rays are stratified in (the runtime numbers them in a byte).
constexpr uint32_t kMaxProbeRegions = 255;

struct ProbeTransport {
  ProbeTetrahedra mesh;        // positions, Delaunay tetrahedra, their neighbours
  uint32_t bins = 0;           // regions per probe (0 without probes)
  std::vector<float> binSh;    // bins × kShCount: ∫_b Y_i dω
  SparseLinks links;           // rows: probe × bins + region; targets as TransportData::links
                               //   (clusters and far clusters, no shared far fields)
  std::vector<uint16_t> sky;   // probes × kProbeSkyCount half floats: K_p's upper triangle
  // Per probe, the distances its rays hit (probe_visibility.h: 2 × 64 half floats), which keep
  // interpolation from carrying light through walls; empty: probes weighed as located.
  std::vector<uint16_t> depth;

  size_t count() const { return mesh.positions.size(); }
};

// How bounced light is gathered (Enlighten's output pixels): at gather points, one per block of
// up to 2×2 texels on one surface, or one per texel where other geometry is near and bounced
// light changes fast. Each gather point pools its texels' rays into one row of links; a bounce
// pass computes every row (the cost of a bounce), the clusters take their incident light from
// the rows of their texels' gather points, and the texels interpolate theirs from the gather
// points around them after a few smoothing passes.
struct TransportData {
  uint32_t texelCount = 0;
  uint32_t clusterCount = 0;
  uint32_t gatherPointCount = 0;
  std::vector<AtlasLayout> atlases;

  std::vector<MaterialParams> materials;
  std::vector<Source> sources;

  // Per cluster: the material, and the cluster's mean texture modulation of that material's
  // albedo and emission (so setAlbedo/setEmission scale textured surfaces correctly).
  std::vector<uint32_t> clusterMaterial;
  std::vector<glm::vec3> clusterAlbedoTexture;
  std::vector<glm::vec3> clusterEmissionTexture;

  // Far clusters: coarser clusters (a few clusters' worth of surface each) that stand in for
  // their clusters where a row sees them from far away, as in hierarchical radiosity: a far
  // ray lands in a far cluster, whose reflected light is the area-weighted mean of the
  // clusters under it, so the rays of a gather point that reach distant surfaces share links
  // instead of each making one. Far cluster f -> clusters (weights sum to 1); its rows are the
  // far clusters, so their count is farClusters.rows().
  SparseMatrix farClusters;
  // Shared far fields: neighbouring gather points on one surface see nearly the same distant
  // surfaces, so their far-cluster rays are pooled into one row here instead of each making
  // links of its own (a point near other geometry gathers alone with a full set of rays, and
  // most of its links went to far clusters seen by its neighbours too). A shared row's weights
  // sum to 1 and its targets are clusters and far clusters (below sharedFarBase()); a gather
  // point's row links it with the share of its own rays that reached far clusters, so each
  // point keeps its own visibility and only the far light's distribution is shared. Computed
  // once per bounce, after the far clusters, before the links.
  SparseLinks sharedFar;
  // Form factors, a row per gather point (rows 0 .. gatherPointCount-1) and then a row per
  // back-side cluster of double-sided geometry (which has no texels, and gathers with rays of
  // its own): row -> what it sees, clusters (targets below clusterCount), far clusters
  // (target clusterCount + f) and shared far fields (target sharedFarBase() + s).
  SparseLinks links;
  // Cluster -> rows: a cluster's incident bounced light, the area-weighted mean of its texels'
  // gather points' rows (weights sum to 1), or its own row for a back-side cluster.
  SparseMatrix clusterGather;
  // Gather point -> gather points: one pass of edge-aware smoothing of the gathered light (Monte
  // Carlo noise), over neighbours on the same surface close enough to stand in; applied
  // filterPasses times before the texels read them. Empty or 0 passes: no smoothing.
  SparseMatrix pointFilter;
  int filterPasses = 0;
  // Texel -> gather points: each texel's bounced light, a tent-weighted mix of the gather
  // points of the texels around it on the same surface (weights sum to 1). Invalid texels have
  // empty rows.
  SparseMatrix texelGather;
  // The source of pointFilter and texelGather, which buildGatherMaps() makes from it (the
  // transport file stores this, five bytes a texel, instead of the maps): per texel its gather
  // point (kNoTexel for invalid texels), and the atlas neighbours it smooths with (bit k: the
  // neighbour at kNeighbourOffsets[k]). Both empty when the maps were made some other way
  // (such a transport solves, but cannot be saved).
  std::vector<uint32_t> texelPoint;
  std::vector<uint8_t> texelNeighbours;

  // Sky transfer: E/π = Σ_i skySh[i] * transfer[i] (per texel / cluster, kShCount values each,
  // half floats: a transfer is a fraction of the hemisphere, well inside their range).
  std::vector<uint16_t> texelSky;
  std::vector<uint16_t> clusterSky;

  // Light probes (empty without): their transfer; the sources' part is in Source::probeTransfer.
  ProbeTransport probes;

  // Reflection probes (empty without): every cubemap texel's capture hit (reflection_capture.h).
  ReflectionTransport reflections;

  // Two resolutions (lightmap_layers.h): when active, the texels above (texelCount, atlases, the
  // sky and gather maps) are the indirect grid's, and these are the lightmap's own texels with
  // each source's direct light; the sources' texelTransfer is then empty.
  LightmapLayers lightmap;

  // Where the clusters and gather points lie, for directional lightmaps (directional.h): a
  // link's direction is its target's position seen from its gather point (a far cluster's:
  // the mix of its clusters', a shared far field's: from the mean of its points). All three
  // empty: the transport gives no directional lightmaps.
  std::vector<glm::vec3> clusterPosition;  // per cluster, world, its texels' area-weighted centre
  std::vector<glm::vec3> pointPosition;    // per gather point, world, its texels' centre
  std::vector<glm::vec3> pointNormal;      // per gather point, unit
  bool hasDirections() const { return !pointPosition.empty(); }

  // Bake-level settings (Unity semantics; 1 is physically correct).
  float indirectIntensity = 1.0f;  // scales all bounced light reaching texels
  float albedoBoost = 1.0f;        // >= 1, pushes albedo toward white for bounces
  glm::vec3 skySh[kShCount] = {};  // sky radiance as SH L2 (RGB)

  // What links may target: the clusters, the far clusters, then the shared far fields (whose
  // own rows target only the first two).
  uint32_t sharedFarBase() const { return clusterCount + uint32_t(farClusters.rows()); }
  uint32_t linkTargetCount() const { return sharedFarBase() + uint32_t(sharedFar.rows()); }
  // Links a bounce computes: the rows' and the shared far fields'.
  size_t linkCount() const { return links.linkCount() + sharedFar.linkCount(); }
  // The number of rows of `links` that belong to back-side clusters.
  uint32_t backRowCount() const { return uint32_t(links.rows()) - gatherPointCount; }
  // The lightmap's atlases and texels, whichever resolution the transport was solved at.
  const std::vector<AtlasLayout>& lightmapAtlases() const {
    return lightmap.active() ? lightmap.atlases : atlases;
  }
  uint32_t lightmapTexelCount() const {
    return lightmap.active() ? lightmap.texelCount : texelCount;
  }
  // Empty when every array agrees with the counts (what the solver indexes without checks),
  // else what is wrong.
  std::string validate() const;
  // Bytes its arrays hold (a Solver's own buffers come on top: a few floats a texel and a
  // cluster).
  size_t memoryBytes() const;
  // Of which the light probes' (their mesh and transfer, the sources' probe transfer).
  size_t probeBytes() const;
  // Of which the reflection probes' (their hits).
  size_t reflectionBytes() const;
};

// What a source's unit transfer is multiplied by as set now: its colour × intensity (a light)
// or its material's emission (emissive surfaces); 0 when disabled.
glm::vec3 sourceScale(const TransportData& data, const Source& source);
// What its direct light in the lightmaps and light probes is multiplied by: sourceScale for a
// baked source, 0 for a mixed or realtime light (the engine adds that light itself).
glm::vec3 directScale(const TransportData& data, const Source& source);

// texelGather and pointFilter (smoothing only with filterPasses > 0) from texelPoint,
// texelNeighbours and the atlases: a texel mixes its own gather point (weight 4) with those of
// its marked neighbours (2 along the axes, 1 on the diagonals), normalised; a gather point's
// smoothing row is the mean of its texels' mixes, its own weight counted once per texel.
// Requires checkGatherSource() to be empty.
// With `parallelFor`, the rows are built in fixed blocks on its threads (the same maps).
void buildGatherMaps(TransportData& data, const ParallelFor& parallelFor = {});
// Empty when texelPoint and texelNeighbours have an entry per texel and every gather point
// exists, else what is wrong.
std::string checkGatherSource(const TransportData& data);

}  // namespace afterglow::runtime
