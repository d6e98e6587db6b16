// bake(): the precompute's stages in stages.h's order, from one table (kStages), each timed and
// its rays counted as it runs.
#include "afterglow/baker/bake.h"

#include <algorithm>
#include <memory>

#include "afterglow/baker/direct.h"
#include "afterglow/baker/gather.h"
#include "afterglow/baker/links.h"
#include "afterglow/baker/probe_transfer.h"
#include "afterglow/baker/reference.h"
#include "afterglow/baker/reflection_capture.h"
#include "afterglow/baker/shadowmask.h"
#include "afterglow/baker/sky.h"
#include "afterglow/core/parallel.h"
#include "afterglow/core/timer.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/runtime/directional.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/trace/raytracer.h"
#include "post/lightmap_post.h"
#include "precompute/burial.h"
#include "precompute/filter_light_edges.h"

namespace afterglow::baker {

namespace {

// What the stages hand each other.
struct Bake {
  Bake(const scenes::Scene& s, const BakeOptions& o, Progress& p)
      : scene(s), options(o), progress(p) {}
  const scenes::Scene& scene;
  const BakeOptions& options;
  Progress& progress;
  glm::vec3 sky[runtime::kShCount] = {};
  std::unique_ptr<trace::RayTracer> tracer;
  TexelGather gather;            // from gather to links (the bake's largest buffer)
  std::vector<Clusters> far;     // far cluster levels, finest first
  BakeResult result;
  bool twoResolutions = false;   // hasIndirectGrid(scene)
  std::vector<glm::vec3> grid;   // two resolutions: the grid texels' sky and bounced light
  std::vector<runtime::LightGradient> gradient;  // directional: per transport texel
  // The texels the transport is solved on: the indirect grid's, or the lightmap's.
  TexelSet& solveTexels() { return twoResolutions ? result.indirectTexels : result.texels; }
};

// The authored light settings the solve uses: light sources follow Scene::lights in order
// (matched by name when the counts differ).
void applyLightSettings(const scenes::Scene& scene, runtime::TransportData& tr) {
  std::vector<runtime::Source*> lights;
  for (runtime::Source& s : tr.sources)
    if (s.kind == runtime::SourceKind::Light) lights.push_back(&s);
  auto apply = [](runtime::Source& s, const scenes::Light& l) {
    s.color = l.color;
    s.intensity = l.intensity;
    s.bounceIntensity = l.bounceIntensity;
    s.mode = lightMode(l.mode);
  };
  if (lights.size() == scene.lights.size()) {
    for (size_t i = 0; i < lights.size(); ++i) apply(*lights[i], scene.lights[i]);
    return;
  }
  for (runtime::Source* s : lights)
    for (const scenes::Light& l : scene.lights)
      if (l.name == s->name) {
        apply(*s, l);
        break;
      }
}

Status buildTracer(Bake& b) {
  b.progress.begin(stageName(Stage::RayTracer), 1);
  // The gather's hits find their texels through the lightmap UVs of the texels it solves on.
  trace::RayTracerOptions options;
  if (b.twoResolutions) options.lightmapUvSet = UvSet::Indirect;
  Result<std::unique_ptr<trace::RayTracer>> built = trace::RayTracer::build(b.scene, options);
  b.progress.end();
  if (!built) return built.status();
  b.tracer = std::move(built.value());
  const trace::RayTracerStats& stats = b.tracer->stats();
  if (stats.invalidTriangles > 0)
    b.result.warnings.push_back(
        format("%zu triangles with bad indices or non-finite vertices were ignored",
               stats.invalidTriangles));
  if (stats.skippedInstances > 0)
    b.result.warnings.push_back(
        format("%zu instances without a valid mesh were skipped", stats.skippedInstances));
  return Status::ok();
}

Status placeTexels(Bake& b) {
  Result<TexelSet> texels = computeTexels(b.scene, *b.tracer, b.options.texels, b.progress);
  if (!texels) return texels.status();
  b.result.texels = std::move(texels.value());
  if (b.result.texels.size() == 0)
    return Status::error("nothing to bake: no static instance has lightmap texels (run uv first)");
  if (!b.twoResolutions) return Status::ok();
  texels = computeTexels(b.scene, *b.tracer, b.options.texels, b.progress, UvSet::Indirect);
  if (!texels) return texels.status();
  b.result.indirectTexels = std::move(texels.value());
  if (b.result.indirectTexels.size() == 0)
    return Status::error("nothing to bake: the indirect grid has no texels");
  return Status::ok();
}

// Brute force over the same texels, for validation: no clusters, links or transport.
Status traceReference(Bake& b) {
  Environment env;
  std::copy(b.sky, b.sky + runtime::kShCount, env.skySh);
  env.indirectIntensity = b.options.indirectIntensity;
  env.albedoBoost = b.options.albedoBoost;
  BakeResult& r = b.result;
  Result<ReferenceTexels> ref = referenceTexels(b.scene, *b.tracer, r.texels, env,
                                                b.options.referenceOptions, {}, b.progress);
  if (!ref) return ref.status();
  r.texelDirect.assign(r.texels.size(), glm::vec3(0.0f));
  r.texelIndirect.assign(r.texels.size(), glm::vec3(0.0f));
  for (size_t i = 0; i < ref->texels.size(); ++i) {
    r.texelDirect[ref->texels[i]] = ref->direct[i];
    r.texelIndirect[ref->texels[i]] = ref->indirect[i];
  }
  return Status::ok();
}

Status traceGather(Bake& b) {
  Result<TexelGather> gather =
      gatherTexels(b.scene, *b.tracer, b.solveTexels(), b.options.links, b.progress);
  if (!gather) return gather.status();
  b.gather = std::move(gather.value());
  return Status::ok();
}

Status groupClusters(Bake& b) {
  const ClusterOptions& o = b.options.clusters;
  b.progress.begin(stageName(Stage::Clusters), 1);
  b.result.clusters = computeClusters(b.scene, b.tracer.get(), b.solveTexels(), &b.gather, o);
  if (o.farScale > 1.0f && b.options.links.farDistance > 0.0f)
    for (int level = 1; level <= o.farLevels; ++level)
      b.far.push_back(computeClusters(b.scene, b.tracer.get(), b.solveTexels(), &b.gather,
                                      farClusterOptions(o, level)));
  b.progress.advance();
  b.progress.end();
  return Status::ok();
}

// Before the links: their far clusters' light check and the smoothing's read it
// (LinkOptions::farLightRatio, filterLightRatio). With two resolutions, also which lightmap
// texels are buried, where the rest read the indirect grid (after the gather, which found the
// grid's buried texels) and each source's direct light at them.
Status traceDirect(Bake& b) {
  runtime::TransportData& tr = b.result.transport;
  Status st = computeDirect(b.scene, *b.tracer, b.solveTexels(), b.result.clusters,
                            b.options.direct, tr, b.progress);
  if (!st || !b.twoResolutions) return st;
  TexelSet& lightmap = b.result.texels;
  buryLightmapTexels(*b.tracer, lightmap, b.options.links, b.progress);
  if (b.progress.cancelled()) return Status::error("cancelled");
  tr.lightmap.texelCount = lightmap.size();
  tr.lightmap.corners =
      indirectCorners(b.scene, *b.tracer, lightmap, b.result.indirectTexels, b.progress);
  if (b.progress.cancelled()) return Status::error("cancelled");
  // A texel with no grid texel of its instance anywhere near sits where the grid found
  // everything buried: buried too, the lightmap fills it from its neighbours.
  for (uint32_t t = 0; t < lightmap.size(); ++t)
    if (tr.lightmap.corners[t].mask == 0) lightmap.valid[t] = 0;
  return computeLightmapDirect(b.scene, *b.tracer, lightmap, b.options.direct, tr, b.progress);
}

Status refine(Bake& b) {
  return refineGather(b.scene, *b.tracer, b.solveTexels(), b.result.clusters,
                      b.result.transport, b.options.links, b.gather, b.progress);
}

Status link(Bake& b) {
  const LinkOptions& o = b.options.links;
  Status st = computeLinks(b.scene, *b.tracer, b.solveTexels(), b.gather, b.result.clusters, o,
                           b.result.transport, b.progress, b.far);
  if (!st) return st;
  cutSmoothingAcrossLight(b.solveTexels(), o.filterLightRatio, o.filterNoiseSigmas,
                          b.gather.pointRays(), b.result.transport);
  b.gather = TexelGather();  // the hit codes are the bake's largest buffer
  return Status::ok();
}

Status traceProbes(Bake& b) {
  const LinkOptions& o = b.options.links;
  return computeProbeTransfer(b.scene, *b.tracer, b.solveTexels(), b.result.clusters, b.far,
                              o.farDistance, o.farLightRatio, b.options.probes,
                              b.options.probeOptions, b.result.transport, b.progress);
}

// One solve with the authored lights, sky and intensities.
Status solve(Bake& b) {
  b.far = {};  // they served the links and the probes
  runtime::TransportData& tr = b.result.transport;
  applyLightSettings(b.scene, tr);
  tr.indirectIntensity = b.options.indirectIntensity;
  tr.albedoBoost = b.options.albedoBoost;
  std::copy(b.sky, b.sky + runtime::kShCount, tr.skySh);
  // The indirect grid's own direct light served the stages above (clusters, light checks); the
  // lightmap's layers carry the sources' direct light from here on.
  if (b.twoResolutions)
    for (runtime::Source& s : tr.sources) s.texelTransfer = {};
  // The solver indexes these without checks; a stage that filled them inconsistently is a bug
  // to report, not a crash.
  if (const std::string why = tr.validate(); !why.empty())
    return Status::error("internal error: inconsistent transport: " + why);
  b.progress.begin(stageName(Stage::Solve), 1);
  {
    runtime::Solver solver(tr);
    solver.setParallelFor(blockRanges());
    solver.solve(b.options.solve);
    solver.gatherTexels(b.result.texelDirect, b.result.texelIndirect);
    if (b.twoResolutions) {
      // The runtime's composition, to the bit: the grid's light (sky and bounces) brought up to
      // the lightmap's texels beside the sources' direct light.
      std::vector<glm::vec3>& grid = b.grid;
      grid.resize(b.result.texelDirect.size());
      for (size_t t = 0; t < grid.size(); ++t)
        grid[t] = b.result.texelDirect[t] + b.result.texelIndirect[t];
      const uint32_t texels = tr.lightmap.texelCount;
      b.result.texelDirect.assign(texels, glm::vec3(0.0f));
      b.result.texelIndirect.assign(texels, glm::vec3(0.0f));
      solver.lightmapDirect(b.result.texelDirect.data());
      solver.upsampleIndirect(grid.data(), b.result.texelIndirect.data());
    }
    if (b.options.directional && tr.hasDirections()) {
      runtime::DirectionalLight directional(tr);
      directional.setParallelFor(blockRanges());
      b.gradient.resize(tr.texelCount);
      directional.texels(solver, b.gradient.data());
    }
    b.result.probeSh.resize(solver.probeCount());
    solver.probeRadiance(0, b.result.probeSh.size(), b.result.probeSh.data());
  }
  b.progress.advance();
  b.progress.end();
  return Status::ok();
}

Status dilate(Bake& b) {
  BakeResult& r = b.result;
  b.progress.begin(stageName(Stage::Dilate), 1);
  PostOptions post;
  post.dilation = b.options.dilation;
  computeAtlasMixes(r.texels, b.scene, post);
  {
    // The transport carries the same atlas layouts, so the runtime resolves relit values alike.
    std::vector<glm::vec3> values(r.texelDirect.size());
    for (size_t t = 0; t < values.size(); ++t) values[t] = r.texelDirect[t] + r.texelIndirect[t];
    for (const runtime::AtlasLayout& layout : r.texels.atlases) {
      r.lightmaps.emplace_back();
      runtime::resolveAtlas(layout, values, r.lightmaps.back());
    }
    if (b.twoResolutions) {
      // The grid's atlases for engines, filled like the lightmap's, dilated by the one pixel a
      // bilinear read at TEXCOORD_2 reaches beyond a chart (every pixel more is work for the
      // runtime each frame: half the grid atlas's pixels are padding), no seams stitched
      // (bounced light is smooth across them anyway).
      PostOptions gridPost = post;
      gridPost.dilation = std::min(post.dilation, 1);
      gridPost.stitchSeams = false;
      computeAtlasMixes(r.indirectTexels, b.scene, gridPost);
      for (const runtime::AtlasLayout& layout : r.indirectTexels.atlases) {
        r.indirectLightmaps.emplace_back();
        runtime::resolveAtlas(layout, b.grid, r.indirectLightmaps.back());
      }
      r.transport.atlases = r.indirectTexels.atlases;
      r.transport.lightmap.atlases = r.texels.atlases;
    } else if (!b.options.reference) {
      r.transport.atlases = r.texels.atlases;
    }
  }
  if (!b.gradient.empty()) {
    // The gradients through the transport's atlases (the grid's or the lightmap's), as its
    // light: the runtime resolves its own alike.
    std::vector<glm::vec3> axis(b.gradient.size());
    for (const runtime::AtlasLayout& layout : r.transport.atlases) {
      std::array<std::vector<glm::vec3>, 3>& images = r.directionalLightmaps.emplace_back();
      for (int a = 0; a < 3; ++a) {
        for (size_t t = 0; t < axis.size(); ++t) axis[t] = b.gradient[t].axis[a];
        runtime::resolveAtlas(layout, axis, images[size_t(a)]);
      }
    }
    b.gradient = {};
  }
  if (!b.options.reference) {
    std::vector<std::string> overflow;
    r.shadowmaskChannel = shadowmaskChannels(b.scene.lights, &overflow);
    for (const std::string& name : overflow)
      r.warnings.push_back(format("mixed light '%s' overlaps %d other mixed lights: no shadowmask "
                                  "channel is left for it, its static shadow is not baked",
                                  name.c_str(), kShadowmaskChannels));
    if (std::any_of(r.shadowmaskChannel.begin(), r.shadowmaskChannel.end(),
                    [](int c) { return c >= 0; })) {
      // Through the lightmaps' own layouts (fill and dilation), as three channels and one:
      // resolveAtlas mixes vec3 values.
      const std::vector<glm::vec4> mask =
          shadowmaskTexels(b.scene, r.texels, r.transport, r.shadowmaskChannel);
      std::vector<glm::vec3> rgb(mask.size()), a(mask.size());
      for (size_t t = 0; t < mask.size(); ++t)
        rgb[t] = glm::vec3(mask[t]), a[t] = glm::vec3(mask[t].w);
      for (const runtime::AtlasLayout& layout : r.texels.atlases) {
        std::vector<glm::vec3> first, second;
        runtime::resolveAtlas(layout, rgb, first);
        runtime::resolveAtlas(layout, a, second);
        std::vector<glm::vec4>& image = r.shadowmasks.emplace_back(first.size());
        for (size_t p = 0; p < first.size(); ++p) image[p] = glm::vec4(first[p], second[p].x);
      }
      if (r.transport.probes.count() > 0)
        r.probeOcclusion = probeOcclusion(b.scene, *b.tracer, r.transport.probes.mesh.positions,
                                          r.shadowmaskChannel);
    }
  }
  b.progress.advance();
  b.progress.end();
  // Texels no valid texel of their instance reaches (a wholly buried object) stay black.
  size_t unreached = 0;
  for (const runtime::AtlasLayout& layout : r.texels.atlases)
    for (size_t i = 0; i + 1 < layout.mixStart.size(); ++i)
      unreached += layout.mixStart[i] == layout.mixStart[i + 1];
  if (unreached > 0)
    r.warnings.push_back(format(
        "%zu invalid texels had no valid texel in their chart to take light from and stay black",
        unreached));
  return Status::ok();
}

// Captured from the finished lightmaps, through the runtime's own passes, so a relight from
// scratch gives these cubemaps bit for bit.
Status captureReflections(Bake& b) {
  Status st = captureReflectionProbes(b.scene, *b.tracer, b.options.reflections,
                                      b.result.transport, b.progress);
  if (!st) return st;
  if (const std::string why = b.result.transport.validate(); !why.empty())
    return Status::error("internal error: inconsistent transport: " + why);
  return Status::ok();
}

Status reflectionPasses(Bake& b) {
  BakeResult& r = b.result;
  b.progress.begin(stageName(Stage::ReflectionPasses), 1);
  r.dfg = runtime::dfgTable(runtime::kDfgSize);
  r.reflectionChains =
      runtime::solveReflectionProbes(r.transport, r.lightmaps, r.dfg, runtime::kDfgSize);
  b.progress.advance();
  b.progress.end();
  return Status::ok();
}

bool always(const Bake&) { return true; }
bool reference(const Bake& b) { return b.options.reference; }
bool precompute(const Bake& b) { return !b.options.reference; }
bool probes(const Bake& b) { return precompute(b) && !b.options.probes.positions.empty(); }
bool reflections(const Bake& b) { return precompute(b) && !b.scene.reflectionProbes.empty(); }

// The precompute's part of stages.h's list, in its order.
struct StageEntry {
  Stage stage;
  bool (*runs)(const Bake&);
  Status (*run)(Bake&);
};
constexpr StageEntry kStages[] = {
    {Stage::RayTracer, always, buildTracer},
    {Stage::Texels, always, placeTexels},
    {Stage::Reference, reference, traceReference},
    {Stage::Gather, precompute, traceGather},
    {Stage::Clusters, precompute, groupClusters},
    {Stage::Direct, precompute, traceDirect},
    {Stage::Refine, precompute, refine},
    {Stage::Links, precompute, link},
    {Stage::Probes, probes, traceProbes},
    {Stage::Solve, precompute, solve},
    {Stage::Dilate, always, dilate},
    {Stage::ReflectionCapture, reflections, captureReflections},
    {Stage::ReflectionPasses, reflections, reflectionPasses},
};

}  // namespace

BakeOptions bakePreset(Quality quality) {
  BakeOptions o;  // the defaults are the default preset
  if (quality == Quality::Draft) {
    o.links.texelRays = 64;
    o.links.clusterRays = 128;
    o.links.filterPasses = 3;
    o.direct.lightSamples = 8;
    o.direct.emissiveSamples = 8;
    o.direct.penumbraSamples = 64;
  } else if (quality == Quality::High) {
    o.links.texelRays = 512;
    o.links.clusterRays = 1024;
    o.links.filterPasses = 1;
    o.direct.lightSamples = 32;
    o.direct.emissiveSamples = 32;
    o.direct.penumbraSamples = 512;
  }
  return o;
}

bool hasIndirectGrid(const scenes::Scene& scene) {
  for (const scenes::Instance& inst : scene.instances)
    if (inst.isStatic && inst.lightmap.atlas >= 0 && inst.indirectLightmap.atlas >= 0) return true;
  return false;
}

Result<BakeResult> bake(const scenes::Scene& scene, const BakeOptions& options,
                        Progress& progress) {
  Bake b(scene, options, progress);
  b.twoResolutions = hasIndirectGrid(scene) && !options.reference;
  // The sky first: a bad image path should fail before minutes of precompute.
  if (!options.skyImage.empty()) {
    if (Status s = projectEquirectSky(options.skyImage, b.sky); !s) return s;
  } else {
    runtime::constantSkySh(options.skyColor, b.sky);
  }
  uint64_t raysBefore = 0;
  for (const StageEntry& entry : kStages) {
    if (!entry.runs(b)) continue;
    const Clock::time_point t0 = Clock::now();
    const Status st = entry.run(b);
    if (progress.cancelled()) return Status::error("cancelled");
    if (!st) return st;
    const uint64_t rays = b.tracer ? b.tracer->raysTraced() : 0;
    b.result.stages.push_back({entry.stage, secondsSince(t0), rays - raysBefore});
    raysBefore = rays;
  }
  b.result.raysTraced = b.tracer->raysTraced();
  b.result.raysIntersected = b.tracer->raysTraced(trace::RayTracer::Query::Intersect);
  b.result.raysOccluded = b.tracer->raysTraced(trace::RayTracer::Query::Occluded);
  return std::move(b.result);
}

}  // namespace afterglow::baker
