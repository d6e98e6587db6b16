#include "afterglow/baker/bake.h"

#include "filter_light_edges.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "afterglow/baker/raytracer.h"
#include "afterglow/core/parallel.h"
#include "afterglow/core/timer.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "afterglow/baker/reference.h"
#include "filter_light_edges.h"
#include "lightmap_post.h"
#include "sky_image.h"

namespace afterglow::baker {

namespace {

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

// Stages 2 to 5: clusters, form factors, direct light, then one solve with the authored lights.
Status precomputeAndSolve(const scenes::Scene& scene, const RayTracer& tracer,
                          const BakeOptions& options, const glm::vec3 sky[runtime::kShCount],
                          BakeResult& result, Progress& progress) {
  runtime::TransportData& tr = result.transport;
  auto cancelled = [&]() { return progress.cancelled(); };
  uint64_t raysBefore = tracer.raysTraced();
  auto record = [&](const char* name, Clock::time_point t0) {
    const uint64_t rays = tracer.raysTraced();
    result.stages.push_back({name, secondsSince(t0), rays - raysBefore});
    raysBefore = rays;
  };
  auto t0 = Clock::now();
  Result<TexelGather> gather = gatherTexels(scene, tracer, result.texels, options.links, progress);
  if (cancelled()) return Status::error("cancelled");
  if (!gather) return gather.status();
  record("gather", t0);

  t0 = Clock::now();
  progress.begin("clusters", 1);
  result.clusters =
      computeClusters(scene, &tracer, result.texels, &gather.value(), options.clusters);
  std::vector<Clusters> far;
  if (options.clusters.farScale > 1.0f && options.links.farDistance > 0.0f)
    for (int level = 1; level <= options.clusters.farLevels; ++level)
      far.push_back(computeClusters(scene, &tracer, result.texels, &gather.value(),
                                    farClusterOptions(options.clusters, level)));
  progress.advance();
  progress.end();
  record("clusters", t0);
  if (cancelled()) return Status::error("cancelled");

  // The direct light before the links: their far clusters' light check and the smoothing's
  // read it (LinkOptions::farLightRatio, filterLightRatio).
  t0 = Clock::now();
  Status st =
      computeDirect(scene, tracer, result.texels, result.clusters, options.direct, tr, progress);
  if (cancelled()) return Status::error("cancelled");
  if (!st) return st;
  record("direct", t0);

  t0 = Clock::now();
  st = refineGather(scene, tracer, result.texels, result.clusters, tr, options.links,
                    gather.value(), progress);
  if (cancelled()) return Status::error("cancelled");
  if (!st) return st;
  record("refine", t0);

  t0 = Clock::now();
  st = computeLinks(scene, tracer, result.texels, gather.value(), result.clusters, options.links,
                    tr, progress, far);
  if (cancelled()) return Status::error("cancelled");
  if (!st) return st;
  cutSmoothingAcrossLight(result.texels, options.links.filterLightRatio,
                          options.links.filterNoiseSigmas, gather->pointRays(), tr);
  record("links", t0);
  gather = TexelGather();  // the hit codes are the bake's largest buffer

  if (!options.probes.positions.empty()) {
    t0 = Clock::now();
    st = computeProbeTransfer(scene, tracer, result.texels, result.clusters, far,
                              options.links.farDistance, options.links.farLightRatio,
                              options.probes, options.probeOptions, tr, progress);
    if (cancelled()) return Status::error("cancelled");
    if (!st) return st;
    record("probes", t0);
  }
  result.raysTraced = tracer.raysTraced();
  result.raysIntersected = tracer.raysTraced(RayTracer::Query::Intersect);
  result.raysOccluded = tracer.raysTraced(RayTracer::Query::Occluded);

  applyLightSettings(scene, tr);
  tr.indirectIntensity = options.indirectIntensity;
  tr.albedoBoost = options.albedoBoost;
  std::copy(sky, sky + runtime::kShCount, tr.skySh);
  // The solver indexes these without checks; a stage that filled them inconsistently is a bug
  // to report, not a crash.
  if (const std::string why = tr.validate(); !why.empty())
    return Status::error("internal error: inconsistent transport: " + why);

  t0 = Clock::now();
  progress.begin("solve", 1);
  {
    runtime::Solver solver(tr);
    solver.setParallelFor(blockRanges());
    solver.solve(options.solve);
    solver.gatherTexels(result.texelDirect, result.texelIndirect);
    result.probeSh.resize(solver.probeCount());
    solver.probeRadiance(0, result.probeSh.size(), result.probeSh.data());
  }
  progress.advance();
  progress.end();
  record("solve", t0);
  return Status::ok();
}

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

Result<BakeResult> bake(const scenes::Scene& scene, const BakeOptions& options,
                        Progress& progress) {
  BakeResult result;
  auto cancelled = [&]() { return progress.cancelled(); };
  const RayTracer* traced = nullptr;  // once built: a stage's rays are its count since the last
  uint64_t raysBefore = 0;
  auto record = [&](const char* name, Clock::time_point t0) {
    const uint64_t rays = traced ? traced->raysTraced() : 0;
    result.stages.push_back({name, secondsSince(t0), rays - raysBefore});
    raysBefore = rays;
  };

  // The sky first: a bad image path should fail before minutes of precompute.
  glm::vec3 sky[runtime::kShCount];
  if (!options.skyImage.empty()) {
    Status s = projectEquirectSky(options.skyImage, sky);
    if (!s) return s;
  } else {
    runtime::constantSkySh(options.skyColor, sky);
  }

  auto t0 = Clock::now();
  progress.begin("ray tracer", 1);
  Result<std::unique_ptr<RayTracer>> built = RayTracer::build(scene);
  progress.end();
  if (!built) return built.status();
  const RayTracer& tracer = *built.value();
  traced = &tracer;
  record("raytracer", t0);
  const RayTracerStats& stats = tracer.stats();
  if (stats.invalidTriangles > 0)
    result.warnings.push_back(
        format("%zu triangles with bad indices or non-finite vertices were ignored",
               stats.invalidTriangles));
  if (stats.skippedInstances > 0)
    result.warnings.push_back(
        format("%zu instances without a valid mesh were skipped", stats.skippedInstances));
  if (cancelled()) return Status::error("cancelled");

  t0 = Clock::now();
  Result<TexelSet> texels = computeTexels(scene, tracer, options.texels, progress);
  if (cancelled()) return Status::error("cancelled");
  if (!texels) return texels.status();
  result.texels = std::move(texels.value());
  record("texels", t0);
  if (result.texels.size() == 0)
    return Status::error("nothing to bake: no static instance has lightmap texels (run uv first)");

  if (options.reference) {
    // Brute force over the same texels, for validation: no clusters, links or transport.
    t0 = Clock::now();
    Environment env;
    std::copy(sky, sky + runtime::kShCount, env.skySh);
    env.indirectIntensity = options.indirectIntensity;
    env.albedoBoost = options.albedoBoost;
    Result<ReferenceTexels> ref =
        referenceTexels(scene, tracer, result.texels, env, options.referenceOptions, {}, progress);
    if (cancelled()) return Status::error("cancelled");
    if (!ref) return ref.status();
    result.texelDirect.assign(result.texels.size(), glm::vec3(0.0f));
    result.texelIndirect.assign(result.texels.size(), glm::vec3(0.0f));
    for (size_t i = 0; i < ref->texels.size(); ++i) {
      result.texelDirect[ref->texels[i]] = ref->direct[i];
      result.texelIndirect[ref->texels[i]] = ref->indirect[i];
    }
    record("reference", t0);
    result.raysTraced = tracer.raysTraced();
    result.raysIntersected = tracer.raysTraced(RayTracer::Query::Intersect);
    result.raysOccluded = tracer.raysTraced(RayTracer::Query::Occluded);
  } else {
    Status st = precomputeAndSolve(scene, tracer, options, sky, result, progress);
    if (!st) return st;
    raysBefore = tracer.raysTraced();  // counted in the stages it recorded
  }
  if (cancelled()) return Status::error("cancelled");

  t0 = Clock::now();
  progress.begin("dilate", 1);
  PostOptions post;
  post.dilation = options.dilation;
  computeAtlasMixes(result.texels, scene, post);
  {
    // The transport carries the same atlas layouts, so the runtime resolves relit values alike.
    std::vector<glm::vec3> values(result.texelDirect.size());
    for (size_t t = 0; t < values.size(); ++t)
      values[t] = result.texelDirect[t] + result.texelIndirect[t];
    for (const runtime::AtlasLayout& layout : result.texels.atlases) {
      result.lightmaps.emplace_back();
      runtime::resolveAtlas(layout, values, result.lightmaps.back());
    }
    if (!options.reference) result.transport.atlases = result.texels.atlases;
  }
  progress.advance();
  progress.end();
  record("dilate", t0);
  // Texels no valid texel of their instance reaches (a wholly buried object) stay black.
  size_t unreached = 0;
  for (const runtime::AtlasLayout& layout : result.texels.atlases)
    for (size_t i = 0; i + 1 < layout.mixStart.size(); ++i)
      unreached += layout.mixStart[i] == layout.mixStart[i + 1];
  if (unreached > 0)
    result.warnings.push_back(format(
        "%zu invalid texels had no valid texel in their chart to take light from and stay black",
        unreached));

  if (!options.reference && !scene.reflectionProbes.empty()) {
    // Captured from the finished lightmaps, through the runtime's own passes, so a relight
    // from scratch gives these cubemaps bit for bit.
    t0 = Clock::now();
    Status st = captureReflectionProbes(scene, tracer, options.reflections, result.transport,
                                        progress);
    if (cancelled()) return Status::error("cancelled");
    if (!st) return st;
    if (const std::string why = result.transport.validate(); !why.empty())
      return Status::error("internal error: inconsistent transport: " + why);
    record("reflection capture", t0);
    t0 = Clock::now();
    progress.begin("reflection passes", 1);
    result.dfg = runtime::dfgTable(runtime::kDfgSize);
    result.reflectionChains = runtime::solveReflectionProbes(result.transport, result.lightmaps,
                                                             result.dfg, runtime::kDfgSize);
    progress.advance();
    progress.end();
    record("reflection passes", t0);
  }
  return result;
}

}  // namespace afterglow::baker
