// The relighting runtime: what an engine links to change lights, sky and materials of a baked
// level and get new lightmaps every frame, without re-baking. GLM and the standard library only.
//
// Typical use:
//
//   std::string error;
//   auto rt = afterglow::runtime::Runtime::load("out/transport.agt", &error);
//   if (!rt) { log(error); return; }
//   int sun = rt->findLight("Sun");
//   ...each frame:
//   rt->setLightColor(sun, {1.0f, 0.8f, 0.6f});   // any thread
//   rt->update({/*maxBounces=*/1});                 // update thread: one bounce a frame
//   rt->readAtlas(0, pixels);                       // render thread: upload to the GPU
//
// How it works: setters only record the new value. update() applies everything recorded since
// the last update to the transport, re-runs the solver's per-cluster setup when anything that
// affects light changed, runs bounce passes starting from the previous solution (a small
// change converges in a few passes; Enlighten runs one a frame), and produces new texel values
// and atlases. Values are E/π (the outgoing radiance of a white Lambertian surface), linear RGB,
// exactly the units of the baked lightmaps.
//
// Threads. These calls may run at the same time as each other and as update():
//   - every setter and getter of settings (light, sky, material, indirect intensity);
//   - readAtlas() and readTexels(), which always see one whole completed update (the outputs
//     are double-buffered; a read copies under a lock that update() holds only for a pointer
//     swap, so neither waits on the other's real work);
//   - the constant queries (counts, names, find*, atlas sizes, canSetEmission).
// update() calls are serialised (a second caller waits), and so is setParallelFor(). data() is
// the one exception: read it only while no update() runs.
//
// Allocation: load() and fromData() allocate everything up front; update(), the settings calls
// and the reads do not (readAtlas into a std::vector only if the vector is too small), except
// for reflection probes, whose capture passes and prefilter build new cubemaps. Caveat:
// the Solver calls inside update() currently heap-allocate a few small closures each (its block
// loop takes a std::function); the test UpdateDoesNotAllocate tracks that.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/directional.h"
#include "afterglow/runtime/probe_lights.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/reflection_capture.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

struct UpdateOptions {
  // Bounce passes this call:
  //   > 0  exactly this many (like SolveOptions::maxBounces; the tolerance does not stop them),
  //   0    until the largest relative change falls below `tolerance`, or 1000 passes,
  //   < 0  none: only apply new settings and recompute the texels (e.g. after
  //        setIndirectIntensity, or to see a light change's direct part at once).
  int maxBounces = 0;
  float tolerance = 1e-3f;  // as SolveOptions::tolerance
  // > 0: the whole call should take at most this long. Before each pass after the first, the
  // call stops if the time so far plus the last pass's time plus the previous update's texel
  // output time would exceed it. The first pass always runs (when maxBounces >= 0), so a budget
  // smaller than one pass still makes progress.
  double timeBudgetMs = 0.0;
  // Reset the bounced light to zero first, as a fresh bake does: with the same settings,
  // tolerance and maxBounces the atlases equal the baker's bit for bit. Off (default): start from
  // the last solution, which converges much faster after small changes.
  bool fromScratch = false;
  // Refresh every light probe from the new solution (after the lightmaps), published with
  // them. Off: the probes keep their last values; updateProbes() refreshes them on its own.
  bool probes = true;
  // Reflection probes, after the light probes. Their unit of work is one capture pass of one
  // probe (reflection_capture.h: pass 0 shows the diffuse part, then the transport's reflection
  // bounces each light the specular part with the pass before), taken pass by pass and probe by
  // probe, round robin. A full round, (bounces + 1) × probes units, reproduces the bake from the
  // current lightmaps, materials and sky exactly (the same function, the same order).
  //   < 0  a full round, from the first unit (default)
  //   0    none: the cubemaps keep their last values
  //   n    at most n units, carrying on where the previous call stopped (an engine spreads a
  //        round over frames: one unit a frame is one 128² probe's capture and prefilter)
  // The sky's cubemap (probe 0) is recomputed when the sky changed, before the units. With a
  // timeBudgetMs, the units stop before one that would overrun the whole call's budget (the
  // first always runs, when any is asked for).
  int reflectionPasses = -1;
  // Two resolutions (TransportData::lightmap): compose the lightmap's texels and atlases on the
  // CPU, each source's direct layer × its colour and intensity plus the indirect grid's light
  // brought up to the lightmap's texels. Off: only the indirect grid's atlases are refreshed
  // (readIndirectAtlas), for an engine that composes in its shader from them, the direct layers
  // (data().lightmap) and the light colours; readAtlas and readTexels keep their last values,
  // and so do the reflection probes' views of the lightmap. No effect with one resolution.
  bool composeLightmap = true;
  // Directional lightmaps (directional.h): refresh the bounced light's gradient atlases
  // (readDirectionalAtlas) from the new solution. The first such update works out the links'
  // directions once (memory: 12 bytes a link). No effect on a transport without directions.
  bool directional = false;
};

struct UpdateStats {
  int bounces = 0;          // passes run
  bool converged = false;   // the last pass changed the solution by less than the tolerance
  float change = 0.0f;      // the last pass's largest relative change (0 when no pass ran)
  double milliseconds = 0;  // wall time of the whole call
  double prepareMilliseconds = 0;  // of which taking changed lights, materials or sky took
  double bounceMilliseconds = 0;   // of which the bounces took
  double outputMilliseconds = 0;   // of which the lightmap's (or grid's) atlases took
  int probes = 0;                // light probes refreshed
  double probeMilliseconds = 0;  // of which the probes took (their share of the call)
  int reflectionPasses = 0;           // reflection probe capture passes run (units, above)
  double reflectionMilliseconds = 0;  // of which the reflection probes took
  double composeMilliseconds = 0;     // of which composing the lightmap took (two resolutions)
};

class Runtime {
 public:
  // Loads a transport file (OUT/transport.agt). On failure returns nullptr and sets *error
  // (when not null) to one line starting with the path.
  static std::unique_ptr<Runtime> load(const std::string& path, std::string* error);
  // From a transport already in memory (the baker and tests). Takes ownership. Returns nullptr
  // and sets *error when data.validate() rejects it.
  static std::unique_ptr<Runtime> fromData(TransportData data, std::string* error);

  Runtime(const Runtime&) = delete;
  Runtime& operator=(const Runtime&) = delete;
  ~Runtime();

  // Spreads the solver's work over an engine's job system (see solver.h). Waits for a running
  // update(). Without it everything runs on the thread calling update(). Results do not depend
  // on it.
  void setParallelFor(ParallelFor parallelFor);

  // ---- Lights ---------------------------------------------------------------------------------
  // The transport's sources of kind Light (punctual lights), numbered 0..lightCount()-1 in
  // transport order. Emissive surfaces are driven through their material (setEmission).
  int lightCount() const;
  const std::string& lightName(int light) const;  // empty for an invalid index
  int findLight(const std::string& name) const;   // the first light of that name, or -1

  // Setters return false (and change nothing) for an invalid index, an unknown name or a
  // non-finite value (NaN or infinity would poison the warm-started solution for good).
  bool setLightColor(int light, glm::vec3 linearRgb);
  bool setLightColor(const std::string& name, glm::vec3 linearRgb);
  bool setLightIntensity(int light, float intensity);  // lux or candela, as in glTF
  bool setLightIntensity(const std::string& name, float intensity);
  // Scales the light in bounced light only (1 = physical, 0 = direct light only).
  bool setBounceIntensity(int light, float scale);
  bool setBounceIntensity(const std::string& name, float scale);
  // A disabled light contributes exactly what intensity 0 would.
  bool setLightEnabled(int light, bool enabled);
  bool setLightEnabled(const std::string& name, bool enabled);

  // The current settings (the latest set, applied or not); zero/false for an invalid index.
  glm::vec3 lightColor(int light) const;
  float lightIntensity(int light) const;
  float bounceIntensity(int light) const;
  bool lightEnabled(int light) const;

  // ---- Sky ------------------------------------------------------------------------------------
  // Sky radiance as SH L2 (kShCount RGB coefficients), or a constant radiance. Non-finite
  // values are ignored (returns false).
  bool setSky(glm::vec3 constantRadiance);
  bool setSkySh(const glm::vec3 sh[kShCount]);
  void skySh(glm::vec3 sh[kShCount]) const;

  // ---- Materials ------------------------------------------------------------------------------
  int materialCount() const;
  const std::string& materialName(int material) const;  // empty for an invalid index
  int findMaterial(const std::string& name) const;       // first of that name, or -1

  // Diffuse albedo factor used for bounces (multiplied by each cluster's texture mean). Keep it
  // below 1: an albedo of 1 or more in a closed room never converges.
  bool setAlbedo(int material, glm::vec3 linearRgb);
  bool setAlbedo(const std::string& name, glm::vec3 linearRgb);
  // Emitted radiance. Only for materials that were emissive at bake time: the transfer from
  // their surfaces was computed only for those. Returns false for any other material (including
  // one baked with zero emission); canSetEmission() says which.
  bool setEmission(int material, glm::vec3 linearRgb);
  bool setEmission(const std::string& name, glm::vec3 linearRgb);
  bool canSetEmission(int material) const;
  glm::vec3 albedo(int material) const;
  glm::vec3 emission(int material) const;

  // Scales all bounced light reaching the texels (Unity's indirect intensity; 1 = physical).
  // Cheap: needs no bounce pass, only update() (maxBounces < 0 suffices).
  bool setIndirectIntensity(float scale);
  float indirectIntensity() const;

  // ---- Solving --------------------------------------------------------------------------------
  // Applies the settings set since the last call and runs bounce passes (see UpdateOptions),
  // then publishes new texel values and atlases to readAtlas()/readTexels().
  UpdateStats update(const UpdateOptions& options = {});

  // ---- Output ---------------------------------------------------------------------------------
  // From the last completed update(); all black before the first.
  int atlasCount() const;
  int atlasWidth(int atlas) const;   // 0 for an invalid index
  int atlasHeight(int atlas) const;
  // Linear float RGB, width*height*3 floats, row 0 at v = 0, pixels exactly as the baker
  // resolves them (padding, seams). False for an invalid index.
  bool readAtlas(int atlas, float* rgb) const;
  bool readAtlas(int atlas, std::vector<glm::vec3>& image) const;  // resized to width*height
  // Two resolutions: the indirect grid's atlases (its sky and bounced light, E/π, resolved as
  // the baker resolves them), which an engine reads at the indirect UVs (TEXCOORD_2 of the
  // baked glTF). None with one resolution.
  int indirectAtlasCount() const;
  int indirectAtlasWidth(int atlas) const;
  int indirectAtlasHeight(int atlas) const;
  bool readIndirectAtlas(int atlas, std::vector<glm::vec3>& image) const;
  // Directional lightmaps (directional.h, UpdateOptions::directional): per atlas of the
  // transport's own texels (the indirect grid's with two resolutions, read at TEXCOORD_2; else
  // the lightmap's), the gradient ∂(E/π)/∂n of its bounced light along world axis `axis` (0 x,
  // 1 y, 2 z), resolved as its light is. Black until a directional update; none without
  // directions in the transport.
  int directionalAtlasCount() const;
  bool readDirectionalAtlas(int atlas, int axis, std::vector<glm::vec3>& image) const;
  // Per texel (direct + indirect), texelCount() values.
  int texelCount() const;
  void readTexels(glm::vec3* texels) const;
  void readTexels(float* rgb) const;  // texelCount()*3 floats

  // ---- Light probes ---------------------------------------------------------------------------
  // The baked light probes (TransportData::probes), relit with the lightmaps. A probe holds the
  // radiance arriving at its position as SH L2 (ShL2, probe_sh.h: L_i = ∫ L(ω) Y_i(ω) dω, RGB,
  // the project's world axes); evaluateIrradiance turns it into E/π for a normal, the lightmaps'
  // unit (shade a diffuse surface with albedo × that).
  int probeCount() const;
  glm::vec3 probePosition(int probe) const;  // (0, 0, 0) for an invalid index
  // From the last published probe update; false (and *sh untouched) for an invalid index.
  bool probeSh(int probe, ShL2* sh) const;
  // The probes' SH at any point: tetrahedral interpolation (barycentric weights of the
  // tetrahedron holding it, found by walking from *hint, which receives the tetrahedron found:
  // keep one hint per moving object), and outside the probes' hull the nearest hull face's
  // (locateProbe), the weights then multiplied by each probe's visibility of the point
  // (probe_visibility.h: no light through walls) and renormalised. All zero without probes.
  ShL2 sampleProbes(glm::vec3 position, int* hint = nullptr) const;
  // E/π for a unit normal from a probe's (or an interpolated) radiance SH.
  static glm::vec3 evaluateIrradiance(const ShL2& sh, glm::vec3 normal);
  // The same point's SH with its small sources kept as directions (probe_lights.h), for E/π
  // with their clamped cosines exact: beside objects in a room lit by a small lamp, several
  // times closer to the true irradiance than the SH alone. Lights as the probes were published.
  ProbeLighting sampleProbeLighting(glm::vec3 position, int* hint = nullptr) const;
  static glm::vec3 evaluateIrradiance(const ProbeLighting& lighting, glm::vec3 normal);
  // Every probe's lights as last published (a copy; empty without probes).
  ProbeDirectionList probeLights() const;
  // Refreshes the probes alone from the current solution (no setting is applied and no bounce
  // runs: call update() with maxBounces < 0 for that), then publishes them. budgetMs > 0
  // refreshes blocks of probes until the budget is spent, carrying on where the previous call
  // stopped (round robin), and publishes what it has; 0 refreshes them all. Serialised with
  // update().
  UpdateStats updateProbes(double budgetMs = 0.0);

  // ---- Reflection probes ----------------------------------------------------------------------
  // Probe 0 is the sky (the fallback outside every box), probe i + 1 the transport's reflection
  // probe i; no probes at all (0, not even the sky's) when the bake had none. Each holds its
  // prefiltered radiance as a chain of reflectionMipCount() cubemaps (cubemap.h's faces and
  // orientation; mip m for perceptual roughness roughnessOfMip(m), mip 0 the mirror), from the
  // last update that ran its units; all black before the first.
  int reflectionProbeCount() const;
  int reflectionMipCount() const;           // kReflectionMipCount with probes, else 0
  int reflectionFaceSize(int probe, int mip) const;  // texels along an edge; 0 when invalid
  // One face of one mip, faceSize² × 3 floats, rows top to bottom. False for an invalid index.
  bool readCubemap(int probe, int mip, int face, float* rgb) const;
  // The whole chain (a copy); empty for an invalid index.
  CubemapChain reflectionChain(int probe) const;
  // The influence (and projection) box of probe ≥ 1; null for the sky or an invalid index.
  const ReflectionProbeBox* reflectionProbeBox(int probe) const;
  // The probes lighting a point and their weights (reflection_probes.h: importance, fades, the
  // sky taking the rest), with the probe numbering above. Only the sky without probes.
  std::vector<ProbeWeight> reflectionProbesAt(glm::vec3 position) const;
  // The split sum's DFG table the cubemaps were shaded with, kDfgSize² (scale, bias) pairs
  // (reflection_prefilter.h's layout); empty without reflection probes.
  const std::vector<glm::vec2>& dfgTable() const { return dfg_; }
  // Runs reflection units alone (as UpdateOptions::reflectionPasses, with < 0 a full round)
  // from the current lightmaps and settings, and publishes them; budgetMs > 0 stops before a
  // unit that would overrun it (the first always runs). Serialised with update().
  UpdateStats updateReflectionProbes(int passes = -1, double budgetMs = 0.0);

  // The transport, with the settings as of the last update() applied. Only while no update()
  // runs.
  const TransportData& data() const { return data_; }

 private:
  struct LightSettings {
    glm::vec3 color{1.0f};
    float intensity = 1.0f;
    float bounceIntensity = 1.0f;
    bool enabled = true;
  };
  struct MaterialSettings {
    glm::vec3 albedo{0.8f};
    glm::vec3 emission{0.0f};
  };
  // What update() must redo for the settings changed since the last one.
  enum Dirty : unsigned {
    kDirtyLights = 1u,      // copy light settings, prepare(), direct texels
    kDirtyMaterials = 2u,   // copy albedo/emission, prepare() (direct texels: see kDirtyDirect)
    kDirtySky = 4u,         // copy sky, prepare(), direct texels
    kDirtyDirect = 8u,      // direct texels (a light, emission or sky changed)
    kDirtyIndirect = 16u,   // copy indirect intensity
  };

  explicit Runtime(TransportData data);
  bool lightOk(int light) const { return light >= 0 && light < int(lightSource_.size()); }
  bool materialOk(int material) const {
    return material >= 0 && material < int(data_.materials.size());
  }

  TransportData data_;
  std::unique_ptr<Solver> solver_;  // refers to data_
  std::vector<uint32_t> lightSource_;   // light -> index into data_.sources
  std::vector<uint8_t> emissiveMaterial_;  // per material: has an emissive source

  // Pending settings, written by setters, copied into data_ by update().
  mutable std::mutex settingsMutex_;
  std::vector<LightSettings> lights_;
  std::vector<MaterialSettings> materials_;
  glm::vec3 sky_[kShCount] = {};
  float indirectIntensity_ = 1.0f;
  unsigned dirty_ = 0;

  // Serialises update() and setParallelFor(); guards everything below but the outputs.
  std::mutex updateMutex_;
  std::vector<glm::vec3> direct_;    // kept until a light, emission or the sky changes
  // Two resolutions: the grid's values (direct_ + bounced light: sky and bounces) and the sources'
  // direct light per lightmap texel (kept like direct_).
  std::vector<glm::vec3> grid_;
  std::vector<glm::vec3> lightmapDirect_;
  bool pendingLightmapDirect_ = true;  // lightmapDirect_ is behind the sources
  bool firstUpdate_ = true;            // direct_ not computed yet
  double lastOutputMs_ = 0.0;        // texel output time of the last update (for the budget)

  // Double-buffered outputs: update() fills [1 - front_], then flips front_ under outputMutex_.
  mutable std::mutex outputMutex_;
  int front_ = 0;
  std::vector<glm::vec3> texels_[2];
  std::vector<std::vector<glm::vec3>> images_[2];
  // Two resolutions: the grid's atlases, flipped on their own (an update may refresh them
  // alone, UpdateOptions::composeLightmap).
  int gridFront_ = 0;
  std::vector<std::vector<glm::vec3>> gridImages_[2];
  // Directional lightmaps: made at the first directional update; per transport texel and axis
  // the gradient, and the atlases ([atlas * 3 + axis]), flipped on their own.
  ParallelFor parallelFor_;  // the solver's, for the directional light's passes
  std::unique_ptr<DirectionalLight> directional_;
  std::vector<LightGradient> gradient_;
  std::vector<glm::vec3> gradientAxis_[3];
  int directionalFront_ = 0;
  std::vector<std::vector<glm::vec3>> directionalImages_[2];
  void refreshDirectional();
  // Light probes: refreshed in probeWork_ (by range, under updateMutex_), published by copying
  // it into the back buffer and flipping probeFront_ under outputMutex_.
  std::vector<ShL2> probeWork_;
  std::vector<ShL2> probes_[2];
  ProbeDirectionList probeLights_[2];  // with probes_, from the sources' scales at publishing
  std::vector<glm::vec3> probeLightScales_[2];  // ... which were these
  bool probeLightsValid_[2] = {false, false};
  int probeFront_ = 0;
  size_t probeCursor_ = 0;  // where the next budgeted updateProbes() starts
  // Refreshes probes [first, first + count) and returns how many it did.
  size_t refreshProbes(size_t first, size_t count);
  // A point's probes and weights, weighed by their visibility of it (sampleProbes' location).
  ProbeLocation locateSeen(glm::vec3 position, int* hint) const;
  void publishProbes();

  // Reflection probes: per capture pass, every probe's chain ([pass][probe], the transport's
  // numbering), the sky's chain, and the published chains (probe 0 the sky) shared with
  // readers: publishing swaps a pointer under outputMutex_, a read copies it and reads without
  // the lock.
  std::vector<std::vector<CubemapChain>> reflectionPasses_;
  CubemapChain reflectionSky_;
  bool reflectionSkyStale_ = true;
  size_t reflectionCursor_ = 0;  // the next unit: pass · probes + probe
  std::vector<ReflectionProbeBox> reflectionBoxes_;
  std::vector<ReflectionShadingSetup> reflectionSetups_;  // per probe, built on first use
  std::vector<std::vector<ProbeLight>> reflectionLights_;  // [pass][0 sky, i + 1 probe i]
  std::vector<glm::vec2> dfg_;
  std::vector<std::shared_ptr<const CubemapChain>> reflectionOut_;
  // Runs reflection units (as UpdateOptions::reflectionPasses) and publishes; fills stats. A
  // budget > 0 (ms since callStart) stops before a unit that would overrun it.
  using Clock = std::chrono::steady_clock;
  void runReflectionUnits(int passes, double budgetMs, Clock::time_point callStart,
                          UpdateStats& stats);
  std::shared_ptr<const CubemapChain> publishedChain(int probe) const;
};

}  // namespace afterglow::runtime
