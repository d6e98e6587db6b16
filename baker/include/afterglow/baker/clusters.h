// Stage 2 of the precompute: texels grouped into clusters, the nodes of the radiosity system.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/texels.h"

namespace afterglow::baker {

struct ClusterOptions {
  float clusterSize = 0.5f;        // metres: target edge length of a cluster
  float maxNormalAngleDeg = 35.0f; // degrees: texels in a cluster stay within this normal cone
  int minTexels = 4;               // count: smaller clusters join a neighbour whose normal agrees
                                   //   (when the merged cluster still fits the cone); <= 1: off
};

struct Clusters {
  std::vector<uint32_t> texelCluster;  // per texel: its cluster (kNoTexel for invalid texels)
  // Per cluster:
  std::vector<glm::vec3> position;     // area-weighted centre
  std::vector<glm::vec3> normal;       // area-weighted mean normal (unit)
  std::vector<float> area;             // m²
  std::vector<uint32_t> material;      // index into Scene::materials (of its texels); ~0u for
                                       //   glTF's default material (primitive material -1)
  std::vector<glm::vec3> albedo;       // mean diffuse albedo (texture × factor), linear
  std::vector<glm::vec3> emission;     // mean emitted radiance, linear
  std::vector<uint32_t> firstTexel;    // texels of cluster c: memberTexels[firstTexel[c] ..
  std::vector<uint32_t> memberTexels;  //   firstTexel[c+1])

  uint32_t size() const { return uint32_t(area.size()); }
};

// Groups texels within one instance and one material into clusters of about clusterSize, each
// within a normal cone. Deterministic.
Clusters computeClusters(const scenes::Scene& scene, const TexelSet& texels,
                         const ClusterOptions& options = {});

// The diffuse albedo the baker uses for a material at a UV (DESIGN.md: baseColor × (1 − metallic)
// plus Unity's meta-pass specular share), linear RGB.
glm::vec3 diffuseAlbedo(const scenes::Scene& scene, int material, glm::vec2 uv0);
// Emitted radiance of a material at a UV, linear RGB.
glm::vec3 emittedRadiance(const scenes::Scene& scene, int material, glm::vec2 uv0);

}  // namespace afterglow::baker
