// The radiosity solver shared by the offline bake and the relighting runtime.
//
//   cluster reflected light   R_c = ρ_c · (D_c + S_c + Σ_r A_cr V_r)
//   gathered light per row    V_r = Σ_j F_rj R_j          (rows: gather points, back clusters;
//                                                          j: clusters, then far clusters,
//                                                          R_f = Σ_c M_fc R_c, then shared
//                                                          far fields, R_s = Σ_j G_sj R_j)
//   texel value (E/π)         T_t = D_t + S_t + indirectIntensity · Σ_p B_tp (Φ^n V)_p
//
// D is direct light from punctual lights and emissive surfaces (sampled explicitly, which is why
// emission enters texels and clusters through D and the links carry only R), S is sky light,
// F the form factors (TransportData::links), M the far clusters' mix of clusters (farClusters),
// G the shared far fields' form factors to clusters and far clusters (sharedFar),
// A the clusters' gather (clusterGather), Φ one pass of smoothing between gather points
// (pointFilter, n = filterPasses) and B the texels' interpolation (texelGather). For bounces,
// D_c uses each light's bounceIntensity.
//
// One iterate() is one bounce: the clusters take up what the rows gathered, then every row
// gathers again (the links, the cost of a bounce). After n passes from reset() the texels hold n
// bounces. Each phase reads only what the previous one wrote, so results are identical whatever
// the thread count.
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

struct SolveOptions {
  int maxBounces = 0;             // 0 = iterate until converged (or 1000 passes)
  float tolerance = 1e-3f;        // stop when the largest relative change of R is below this
};

class Solver {
 public:
  // Keeps a reference to `data`: it must outlive the solver, and prepare() must follow any
  // change to its sources, materials or sky. Allocates everything the solver will need; no
  // call below allocates except gatherTexels into vectors too small for the texels.
  explicit Solver(const TransportData& data);

  // How to spread a pass over threads (an engine's job system, the baker's pool); without one
  // everything runs on the calling thread.
  void setParallelFor(ParallelFor parallelFor) { parallelFor_ = std::move(parallelFor); }

  // Recomputes the per-cluster direct and sky terms and the albedos from the data's current
  // source, material and sky settings. The bounced light so far stays (a relit scene converges
  // from the old solution in a few passes). `changed` names what changed since the last
  // prepare (PrepareParts): the clusters' albedos are kept unless materials changed, their sky
  // unless the sky did; the result is the same bits as a full prepare.
  enum PrepareParts : unsigned { kSourcesChanged = 1, kMaterialsChanged = 2, kSkyChanged = 4,
                                 kAllChanged = 7 };
  void prepare(unsigned changed = kAllChanged);
  // Runs one bounce; returns the largest relative change of any cluster's reflected light.
  float iterate();
  // Iterates to convergence or options.maxBounces passes; returns the passes run.
  int solve(const SolveOptions& options = {});
  // Resets the bounced light to zero (direct light only, before any pass).
  void reset();

  // Texel values (E/π, linear RGB) from the current solution, split into light that arrives
  // directly (sources and sky) and bounced light (already scaled by indirectIntensity).
  void gatherTexels(std::vector<glm::vec3>& direct, std::vector<glm::vec3>& indirect) const;
  // Their sum.
  void gatherTexels(std::vector<glm::vec3>& texels) const;

  // The two halves of gatherTexels apart, into arrays of texelCount values, for a runtime that
  // keeps the direct light until a source or the sky changes:
  void directTexels(glm::vec3* direct, bool withSky = true) const;
  void skyTexels(glm::vec3* sky) const;  // S_t alone
  void indirectTexels(glm::vec3* indirect) const;
  // direct[t] + indirectTexels' value into sum[t]: the same bits as the two added afterwards,
  // without a pass over the texels of its own.
  void addIndirectTexels(const glm::vec3* direct, glm::vec3* sum) const;

  // Two resolutions (TransportData::lightmap, lightmap_layers.h), per lightmap texel: the
  // sources' direct light as set now, and the indirect texels' values (grid[t] for indirect
  // texel t: its sky and bounced light, directTexels + indirectTexels) brought up to it. The
  // lightmap is their sum, direct + indirect, in that order; both arrays hold
  // lightmap.texelCount values. Nothing happens with one resolution.
  void lightmapDirect(glm::vec3* direct) const;
  void upsampleIndirect(const glm::vec3* grid, glm::vec3* indirect) const;
  // Their sum without keeping the indirect part: lightmap[t] = direct[t] + upsampled grid.
  void composeLightmap(const glm::vec3* direct, const glm::vec3* grid, glm::vec3* lightmap) const;

  // Light probes (TransportData::probes): the radiance SH of probes [first, first + count) from
  // the current solution, with the texels' bounces (the links read the same R the texels' last
  // rows gathered), into out[0 .. count). Probes out of range are left out.
  void probeRadiance(size_t first, size_t count, ShL2* out) const;
  size_t probeCount() const { return data_.probes.count(); }
  // Per source, what its unit direct light in lightmaps and probes is multiplied by now
  // (directScale: 0 for mixed and realtime lights).
  const std::vector<glm::vec3>& directScales() const { return directScale_; }

  const std::vector<glm::vec3>& clusterReflected() const { return reflected_; }
  const std::vector<glm::vec3>& clusterAlbedo() const { return albedo_; }
  // Per row of the links, what it gathered in the last pass (V).
  const std::vector<glm::vec4>& rowGathered() const { return gathered_; }
  // What the links read, per target (linkTargetCount): R of the clusters, the far clusters and
  // the shared far fields, as the last pass's rows read them.
  const std::vector<glm::vec4>& linkTargetRadiance() const { return reflected4_; }

 private:
  // body(first, last) over fixed blocks of `items` items, through parallelFor_ when set. A
  // template, so the bodies (lambdas capturing more than a std::function holds inline) are
  // never copied to the heap: update() must not allocate. `run` captures two references, which
  // std::function keeps inline.
  template <class Body>
  void forBlocks(size_t items, const Body& body) const {
    const size_t blocks = (items + kBlock - 1) / kBlock;
    auto run = [&](size_t begin, size_t end) {
      for (size_t b = begin; b < end; ++b) body(b * kBlock, std::min(items, (b + 1) * kBlock));
    };
    if (parallelFor_ && blocks > 1) parallelFor_(blocks, run);
    else run(0, blocks);
  }
  static constexpr size_t kBlock = 2048;  // clusters, rows or texels per block of work
  // out[row] = Σ link weight × R[target] over every row of m (the hot loop of a bounce).
  void gatherRows(const SparseLinks& m, glm::vec4* out);
  // The gathered values after the smoothing passes over the gather points (filtered_, or
  // gathered_ itself without passes).
  const glm::vec4* filteredPoints() const;
  // store(t, indirect light of texel t) for every texel.
  template <class Store>
  void mixTexels(const Store& store) const;

  const TransportData& data_;
  ParallelFor parallelFor_;
  std::vector<float> blockChange_;          // iterate(): largest change per block
  std::vector<glm::vec3> albedo_;           // boosted diffuse albedo per cluster
  std::vector<glm::vec3> clusterDirect_;    // D_c (with bounceIntensity) + S_c
  std::vector<glm::vec3> clusterSky_;       // S_c alone (kept while the sky does not change)
  std::vector<glm::vec3> reflected_;        // R_c
  std::vector<glm::vec4> reflected4_;       // R_c padded to 16 bytes for the links' inner
                                            //   loop, then the far clusters' R_f and
                                            //   the shared far fields' R_s
  std::vector<glm::vec4> gathered_;         // V_r
  mutable std::vector<glm::vec4> filtered_; // smoothing passes over the gather points
  mutable std::vector<glm::vec4> scratch_;
  std::vector<glm::vec3> sourceScale_;      // per source: colour × intensity (or emission)
  std::vector<glm::vec3> directScale_;      // ... in texels and probes (directScale)
  std::vector<glm::vec4> probeBinSh_;       // the probes' region weights, laid out for
                                            //   probeBounce_ (solver.cpp)
  // One probe's bounced light (the kernel the CPU runs best, picked at construction), with the
  // caller's zeroed scratch `sums` for its regions, which it leaves zeroed.
  std::vector<uint8_t> probeGroupRegion_;   // per group of kLinkGroup probe links, its region
  void (*probeBounce_)(const SparseLinks& links, size_t firstRow, uint32_t bins,
                       const uint8_t* groupRegion, const glm::vec4* binSh, const glm::vec4* r,
                       float* sums, glm::vec4 out[kShCount]) = nullptr;
};

// Unity's albedo boost: pulls albedo toward white as the boost grows (albedo^(1/boost); 1 and
// below leave it unchanged).
glm::vec3 boostAlbedo(glm::vec3 albedo, float boost);

// The sky colour's SH for a constant radiance (only the DC term is non-zero).
void constantSkySh(glm::vec3 radiance, glm::vec3 sh[kShCount]);

}  // namespace afterglow::runtime
