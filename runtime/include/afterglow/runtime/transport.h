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

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace afterglow::runtime {

constexpr int kShCount = 9;               // SH L2 coefficients (bands 0..2)
constexpr uint32_t kNoTexel = 0xffffffffu;

// The eight atlas neighbours of a texel, in the bit order of TransportData::texelNeighbours.
constexpr int kNeighbourOffsets[8][2] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0},
                                         {1, 0},   {-1, 1}, {0, 1},  {1, 1}};

// Row-compressed sparse matrix of form factors, stored quantised: row r links to target[k] with
// weight[k] × rowScale[r] for k in [rowStart[r], rowStart[r+1]), targets ascending. A weight is
// the fraction of a point's cosine-weighted hemisphere that sees the target cluster; 16 bits
// against the row's largest weight keep it within 1/65535 of that largest (a row gathers
// `scale × Σ weight[k] R[target[k]]`, one multiply per row), at 6 bytes a link.
struct SparseLinks {
  std::vector<uint32_t> rowStart{0};
  std::vector<uint32_t> target;
  std::vector<uint16_t> weight;
  std::vector<float> rowScale;

  size_t rows() const { return rowStart.size() - 1; }
  size_t size() const { return target.size(); }
  float weightAt(size_t row, size_t k) const { return float(weight[k]) * rowScale[row]; }
  // Appends a row: n (target, form factor) pairs with ascending targets. Weights that round
  // to zero against the row's largest are left out.
  void appendRow(const uint32_t* targets, const float* weights, size_t n);
};

// A source of direct light whose unit transfer was precomputed: a punctual light, or all the
// emissive surfaces of one material (area light, sampled explicitly by the baker).
enum class SourceKind : uint8_t { Light, Emissive };

struct Source {
  std::string name;      // light name, or material name for emissive sources
  SourceKind kind = SourceKind::Light;
  uint32_t material = 0; // for Emissive: the material whose emission drives it
  // Per-light settings as baked (the runtime may change them):
  glm::vec3 color{1.0f};
  float intensity = 1.0f;        // lux or candela, as in glTF
  float bounceIntensity = 1.0f;  // scales this light in bounced light only (Unity's meaning)
  bool enabled = true;
  // Unit transfer (E/π per unit source), dense over texels and over clusters.
  std::vector<float> texelTransfer;
  std::vector<float> clusterTransfer;
};

// The reflective and emissive properties the runtime may change, per material.
struct MaterialParams {
  std::string name;
  glm::vec3 albedo{0.8f};    // diffuse albedo factor (linear RGB) used for bounces
  glm::vec3 emission{0.0f};  // emitted radiance (linear RGB)
};

// Where texels sit in the lightmap atlases, and how texel values become the atlas image: a
// pixel takes its texel's value, except the pixels the baker lists as mixes (texels too
// buried to trust, the padding around charts that bilinear filtering reads, seams), which
// take a weighted sum of texel values. resolveAtlas() applies it; the bake and the runtime
// both go through it, so their lightmaps agree to the bit.
struct AtlasLayout {
  int width = 0;
  int height = 0;
  std::vector<uint32_t> texelOfPixel;  // width*height entries: texel index or kNoTexel
  // Pixel mixPixel[i] = Σ_k mixWeight[k] · value[mixTexel[k]], k in [mixStart[i], mixStart[i+1]).
  std::vector<uint32_t> mixPixel;
  std::vector<uint32_t> mixStart{0};
  std::vector<uint32_t> mixTexel;
  std::vector<float> mixWeight;
};

// The atlas image (width*height, row 0 at v = 0) from per-texel values; pixels without a
// texel or a mix are black.
void resolveAtlas(const AtlasLayout& layout, const std::vector<glm::vec3>& texelValues,
                  std::vector<glm::vec3>& image);

struct TransportData {
  uint32_t texelCount = 0;
  uint32_t clusterCount = 0;
  std::vector<AtlasLayout> atlases;

  std::vector<MaterialParams> materials;
  std::vector<Source> sources;

  // Per cluster: the material, and the cluster's mean texture modulation of that material's
  // albedo and emission (so setAlbedo/setEmission scale textured surfaces correctly).
  std::vector<uint32_t> clusterMaterial;
  std::vector<glm::vec3> clusterAlbedoTexture;
  std::vector<glm::vec3> clusterEmissionTexture;

  SparseLinks texelLinks;    // texel -> clusters it sees
  SparseLinks clusterLinks;  // cluster -> clusters it sees

  // The edge-aware smoothing of texels' bounced light (Monte Carlo gather noise): per texel, a
  // bit per atlas neighbour (kNeighbourOffsets order) that lies on the same surface, close
  // enough for its bounced light to stand in; indirectFilterPasses passes of a 3×3 tent over
  // the marked neighbours. Empty or 0 passes: no smoothing.
  std::vector<uint8_t> texelNeighbours;
  int indirectFilterPasses = 0;

  // Sky transfer: E/π = Σ_i skySh[i] * transfer[i] (per texel / cluster, kShCount floats each).
  std::vector<float> texelSky;
  std::vector<float> clusterSky;

  // Bake-level settings (Unity semantics; 1 is physically correct).
  float indirectIntensity = 1.0f;  // scales all bounced light reaching texels
  float albedoBoost = 1.0f;        // >= 1, pushes albedo toward white for bounces
  glm::vec3 skySh[kShCount] = {};  // sky radiance as SH L2 (RGB)
};

}  // namespace afterglow::runtime
