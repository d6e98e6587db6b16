// The radiosity solver shared by the offline bake and the relighting runtime.
//
//   cluster reflected light  R_c = ρ_c · (D_c + Σ_j F_cj R_j + S_c)
//   cluster exitance         M_c = R_c + Le_c
//   texel value (E/π)        T_t = D_t + indirectIntensity · Σ_j F_tj R_j + S_t
//
// D is direct light from punctual lights and emissive surfaces (sampled explicitly, which is why
// emission enters texels and clusters through D and the links carry only R), S is sky light.
// For bounces, D_c uses each light's bounceIntensity. Jacobi iteration with a double buffer keeps
// results identical whatever the thread count.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

struct SolveOptions {
  int maxBounces = 0;             // 0 = iterate until converged (or 1000 passes)
  float tolerance = 1e-3f;        // stop when the largest relative change of R is below this
};

// Runs body(begin, end) over consecutive ranges covering [0, count), on as many threads as it
// likes, and returns when every range is done. The solver splits its work into fixed blocks and
// hands their indices to this, so results never depend on how the ranges are spread.
using ParallelFor =
    std::function<void(size_t count, const std::function<void(size_t begin, size_t end)>& body)>;

class Solver {
 public:
  explicit Solver(const TransportData& data);

  // How to spread a pass over threads (an engine's job system, the baker's pool); without one
  // everything runs on the calling thread.
  void setParallelFor(ParallelFor parallelFor) { parallelFor_ = std::move(parallelFor); }

  // Recomputes the per-cluster direct and sky terms and the albedos from the data's current
  // source, material and sky settings. Call after changing any of them.
  void prepare();
  // Runs one Jacobi pass over the cluster links; returns the largest relative change.
  float iterate();
  // Iterates to convergence or options.maxBounces passes; returns the passes run.
  int solve(const SolveOptions& options = {});
  // Gathers the texel values (E/π, linear RGB) from the current cluster solution.
  void gatherTexels(std::vector<glm::vec3>& texels) const;
  // The same split in two: light that arrives directly (sources and sky) and bounced light
  // (already scaled by indirectIntensity); their sum is gatherTexels'.
  void gatherTexels(std::vector<glm::vec3>& direct, std::vector<glm::vec3>& indirect) const;
  // Resets the bounced light to zero (direct light only, before any pass).
  void reset();

  const std::vector<glm::vec3>& clusterReflected() const { return reflected_; }
  const std::vector<glm::vec3>& clusterAlbedo() const { return albedo_; }

 private:
  // Smooths bounced light over the texelNeighbours marks, indirectFilterPasses times.
  void filterIndirect(std::vector<glm::vec3>& indirect) const;

  // body(first, last) over fixed blocks of `items` items, through parallelFor_ when set.
  void forBlocks(size_t items, const std::function<void(size_t first, size_t last)>& body) const;

  const TransportData& data_;
  ParallelFor parallelFor_;
  mutable std::vector<float> blockChange_;  // iterate(): largest change per block
  // The indirect filter's neighbours as a sparse matrix (texel rows, tent weights that sum to
  // one), built once from the atlas layout and the marks.
  std::vector<uint32_t> filterStart_;
  std::vector<uint32_t> filterTexel_;
  std::vector<float> filterWeight_;
  mutable std::vector<glm::vec3> filterScratch_;
  std::vector<glm::vec3> albedo_;       // boosted diffuse albedo per cluster
  std::vector<glm::vec3> clusterDirect_;  // D_c (with bounceIntensity) + S_c
  std::vector<glm::vec3> reflected_;    // R_c
  std::vector<glm::vec3> next_;
};

// Unity's albedo boost: pulls albedo toward white as the boost grows (albedo^(1/boost); 1 and
// below leave it unchanged).
glm::vec3 boostAlbedo(glm::vec3 albedo, float boost);

// The sky colour's SH for a constant radiance (only the DC term is non-zero).
void constantSkySh(glm::vec3 radiance, glm::vec3 sh[kShCount]);

}  // namespace afterglow::runtime
