#include "afterglow/baker/bake.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "afterglow/baker/raytracer.h"
#include "lightmap_post.h"
#include "sky_image.h"

namespace afterglow::baker {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// The factor-only diffuse albedo of a material (DESIGN.md: baseColor × (1 − metallic) plus Unity's
// meta-pass specular share), which the runtime's setAlbedo replaces; the texture's share of each
// cluster goes to clusterAlbedoTexture.
glm::vec3 factorAlbedo(const scenes::Material& m) {
  const glm::vec3 base(m.baseColorFactor);
  const float metallic = std::clamp(m.metallicFactor, 0.0f, 1.0f);
  const glm::vec3 spec = glm::mix(glm::vec3(0.04f), base, metallic);
  const float roughness = std::clamp(m.roughnessFactor, 0.0f, 1.0f);
  return base * (1.0f - metallic) + spec * roughness * roughness * 0.5f;
}

// Fills what the precompute stages leave to the bake: counts, layout, materials and the
// per-cluster material data. Only fields a stage left empty are filled, so what computeLinks
// wrote wins.
void fillTransportLayout(const scenes::Scene& scene, const TexelSet& texels,
                         const Clusters& clusters, runtime::TransportData& tr) {
  tr.texelCount = texels.size();
  tr.clusterCount = clusters.size();
  if (tr.atlases.empty()) tr.atlases = texels.atlases;
  if (tr.materials.empty()) {
    // Material index -1 (glTF's default) has no entry; clusters then carry index 0 of a
    // one-element list holding the default.
    const size_t count = std::max<size_t>(scene.materials.size(), 1);
    for (size_t m = 0; m < count; ++m) {
      const scenes::Material& mat = scene.material(m < scene.materials.size() ? int(m) : -1);
      runtime::MaterialParams p;
      p.name = mat.name;
      p.albedo = factorAlbedo(mat);
      p.emission = mat.emission();
      tr.materials.push_back(p);
    }
  }
  const uint32_t nc = clusters.size();
  if (tr.clusterMaterial.empty()) {
    tr.clusterMaterial.resize(nc);
    for (uint32_t c = 0; c < nc; ++c)
      tr.clusterMaterial[c] = std::min<uint32_t>(clusters.material[c], uint32_t(tr.materials.size() - 1));
  }
  if (tr.clusterAlbedoTexture.empty()) {
    tr.clusterAlbedoTexture.resize(nc);
    for (uint32_t c = 0; c < nc; ++c) {
      runtime::MaterialParams& mp = tr.materials[tr.clusterMaterial[c]];
      glm::vec3 ratio(1.0f);
      for (int k = 0; k < 3; ++k) {
        if (mp.albedo[k] > 1e-6f) {
          ratio[k] = clusters.albedo[c][k] / mp.albedo[k];
        } else if (clusters.albedo[c][k] > 0.0f) {
          // A factor of zero cannot be modulated; keep the cluster's albedo exact instead.
          mp.albedo[k] = 1.0f;
          ratio[k] = clusters.albedo[c][k];
        }
      }
      tr.clusterAlbedoTexture[c] = ratio;
    }
  }
  if (tr.clusterEmissionTexture.empty()) {
    tr.clusterEmissionTexture.resize(nc);
    for (uint32_t c = 0; c < nc; ++c) {
      const glm::vec3 e = tr.materials[tr.clusterMaterial[c]].emission;
      glm::vec3 ratio(1.0f);
      for (int k = 0; k < 3; ++k)
        if (e[k] > 1e-12f) ratio[k] = clusters.emission[c][k] / e[k];
      tr.clusterEmissionTexture[c] = ratio;
    }
  }
}

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

}  // namespace

Result<BakeResult> bake(const scenes::Scene& scene, const BakeOptions& options,
                        Progress& progress) {
  BakeResult result;
  runtime::TransportData& tr = result.transport;
  auto cancelled = [&]() { return progress.cancelled(); };
  auto record = [&](const char* name, Clock::time_point t0) {
    result.stages.push_back({name, secondsSince(t0)});
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

  t0 = Clock::now();
  progress.begin("clusters", 1);
  result.clusters = computeClusters(scene, result.texels, options.clusters);
  progress.advance();
  progress.end();
  record("clusters", t0);
  if (cancelled()) return Status::error("cancelled");

  t0 = Clock::now();
  Status st = computeLinks(scene, tracer, result.texels, result.clusters, options.links, tr,
                           progress);
  if (cancelled()) return Status::error("cancelled");
  if (!st) return st;
  record("links", t0);

  t0 = Clock::now();
  st = computeDirect(scene, tracer, result.texels, result.clusters, options.direct, tr, progress);
  if (cancelled()) return Status::error("cancelled");
  if (!st) return st;
  record("direct", t0);
  result.raysTraced = tracer.raysTraced();

  fillTransportLayout(scene, result.texels, result.clusters, tr);
  applyLightSettings(scene, tr);
  // Bake-level settings last: the stages may have reset them to their defaults.
  tr.indirectIntensity = options.indirectIntensity;
  tr.albedoBoost = options.albedoBoost;
  std::copy(sky, sky + runtime::kShCount, tr.skySh);
  // The solver indexes these without checks; a stage that filled them inconsistently is a bug
  // to report, not a crash.
  if (tr.clusterMaterial.size() != tr.clusterCount ||
      tr.clusterAlbedoTexture.size() != tr.clusterCount ||
      tr.texelLinks.rows() != tr.texelCount || tr.clusterLinks.rows() != tr.clusterCount)
    return Status::error(format("internal error: inconsistent transport (%u texels, %u clusters, "
                                "%zu texel link rows, %zu cluster link rows)",
                                tr.texelCount, tr.clusterCount, tr.texelLinks.rows(),
                                tr.clusterLinks.rows()));

  t0 = Clock::now();
  progress.begin("solve", 1);
  std::vector<glm::vec3> values;
  {
    runtime::Solver solver(tr);
    solver.solve(options.solve);
    solver.gatherTexels(values);
  }
  progress.advance();
  progress.end();
  record("solve", t0);
  if (cancelled()) return Status::error("cancelled");

  t0 = Clock::now();
  const TexelSet& ts = result.texels;
  progress.begin("dilate", ts.atlases.size());
  size_t invalidLeft = 0;
  for (const runtime::AtlasLayout& layout : ts.atlases) {
    const size_t pixels = size_t(layout.width) * size_t(layout.height);
    std::vector<glm::vec3> image(pixels, glm::vec3(0.0f));
    std::vector<uint8_t> state(pixels, kPixelEmpty);
    for (size_t p = 0; p < pixels && p < layout.texelOfPixel.size(); ++p) {
      const uint32_t t = layout.texelOfPixel[p];
      if (t == runtime::kNoTexel || t >= values.size()) continue;
      image[p] = values[t];
      state[p] = ts.valid.empty() || ts.valid[t] ? kPixelValid : kPixelInvalid;
    }
    fillInvalidPixels(layout.width, layout.height, image, state);
    invalidLeft += size_t(std::count(state.begin(), state.end(), uint8_t(kPixelInvalid)));
    dilatePixels(layout.width, layout.height, image, state, options.dilation);
    result.lightmaps.push_back(std::move(image));
    progress.advance();
  }
  progress.end();
  record("dilate", t0);
  if (invalidLeft > 0)
    result.warnings.push_back(format(
        "%zu invalid texels had no valid neighbour in their chart and stay black", invalidLeft));
  return result;
}

}  // namespace afterglow::baker
