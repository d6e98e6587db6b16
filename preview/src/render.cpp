#include "afterglow/preview/render.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "afterglow/core/atomic_file.h"
#include "afterglow/preview/exposure.h"
#include "afterglow/runtime/directional.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/material_eval.h"
#include "afterglow/trace/raytracer.h"

namespace afterglow::preview {

namespace {

// Bilinear between texel centres, clamped at the edges (the bake dilated into the padding):
// as the reflection probes' capture reads them.
glm::vec3 fetch(const bakefiles::LightmapImage& lm, glm::vec2 uv) {
  return runtime::sampleClampedBilinear(lm.pixels, lm.width, lm.height, uv);
}

// The lightmap's light at a hit with the directional lightmaps' gradient (directional.h) at
// the normal the material's normal texture gives there: only the bounced light bends.
glm::vec3 directionalLight(const scenes::Scene& scene, const trace::RayTracer& tracer,
                           const bakefiles::BakedDirectional& directional, const trace::Hit& hit,
                           int material, glm::vec2 uv0, glm::vec3 light) {
  const scenes::Instance& inst = scene.instances[hit.instance];
  // One resolution: the lightmap's atlas and UVs; an indirect grid: the grid's.
  const bool grid = directional.texCoord == 2;
  const int atlas = grid ? inst.indirectLightmap.atlas : inst.lightmap.atlas;
  if (!hit.frontFace || atlas < 0 || size_t(atlas) >= directional.atlases.size()) return light;
  const glm::vec3 n0 = tracer.shadingNormal(hit);
  glm::vec3 t, b;
  if (!scenes::triangleTangents(scene, hit.instance, hit.primitive, hit.triangle, n0, &t, &b))
    return light;
  const glm::vec3 n = scenes::normalMapped(scene, material, uv0, n0, t, b);
  if (n == n0) return light;
  runtime::LightGradient g;
  const glm::vec2 uv = tracer.uv(hit, grid ? 2 : 1);
  for (int axis = 0; axis < 3; ++axis)
    g.axis[axis] = fetch(directional.atlases[size_t(atlas)][size_t(axis)], uv);
  return runtime::shadeDirectional(light, g, n, n0);
}

// What the baked render shows at a primary ray's hit: diffuse albedo × lightmap + emission.
// Back faces of single-sided geometry and misses are black; surfaces without a lightmap
// (dynamic instances) show only their emission. With reflection probes, the diffuse colour and
// the probes' specular instead (render.h), as reflection_capture.h shades a probe's hits.
glm::vec3 bakedRadiance(const scenes::Scene& scene, const trace::RayTracer& tracer,
                        const std::vector<bakefiles::LightmapImage>& lightmaps, const trace::Ray& ray, const trace::Hit& hit,
                        const runtime::ReflectionLighting* reflections,
                        const bakefiles::BakedDirectional* directional) {
  if (!hit.valid()) return glm::vec3(0.0f);
  const scenes::Instance& inst = scene.instances[hit.instance];
  const int material = scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
  const scenes::Material& mat = scene.material(material);
  if (!hit.frontFace && !mat.doubleSided) return glm::vec3(0.0f);
  const glm::vec2 uv0 = tracer.uv(hit, 0);
  glm::vec3 light(0.0f);
  const int atlas = inst.lightmap.atlas;
  const bool lightmapped =
      atlas >= 0 && size_t(atlas) < lightmaps.size() && lightmaps[size_t(atlas)].width > 0;
  if (lightmapped) light = fetch(lightmaps[size_t(atlas)], tracer.uv(hit, 1));
  if (lightmapped && directional && !directional->empty())
    light = directionalLight(scene, tracer, *directional, hit, material, uv0, light);
  glm::vec3 radiance(0.0f);
  if (mat.emitsFrom(hit.frontFace)) radiance += emittedRadiance(scene, material, uv0);
  if (!reflections) return radiance + diffuseAlbedo(scene, material, uv0) * light;
  const scenes::SurfaceBrdf brdf = surfaceBrdf(scene, material, uv0);
  glm::vec3 normal = tracer.shadingNormal(hit);
  if (!hit.frontFace) normal = -normal;
  return radiance + brdf.diffuse * light +
         reflections->specular(ray.origin + hit.t * ray.direction, normal, -ray.direction,
                               brdf.f0, brdf.roughness, lightmapped ? &light : nullptr);
}

// Glass in the picture as an engine blends it: a transmissive surface shows (1 − open) of
// itself as baked over open × tint of what lies behind it (scenes::transmission), layer after
// layer, up to kLayers of them. No noise: the light behind a window is its own primary ray.
// Probe spheres are drawn in front of the first surface only.
glm::vec3 blendedRadiance(const scenes::Scene& scene, const trace::RayTracer& tracer,
                          const std::vector<bakefiles::LightmapImage>& lightmaps,
                          trace::Ray ray, const trace::Hit& first,
                          const runtime::ReflectionLighting* reflections,
                          const bakefiles::BakedDirectional* directional) {
  constexpr int kLayers = 8;
  glm::vec3 sum(0.0f), weight(1.0f);
  trace::Hit hit = first;
  for (int layer = 0;; ++layer) {
    const scenes::Transmission t = tracer.transmission(hit);
    sum += weight * (1.0f - t.open) *
           bakedRadiance(scene, tracer, lightmaps, ray, hit, reflections, directional);
    if (!(t.open > 0.0f) || layer + 1 == kLayers) return sum;
    weight *= t.rgb();
    ray.tnear = std::nextafter(hit.t, std::numeric_limits<float>::infinity());
    hit = tracer.intersect(ray);
  }
}

}  // namespace

Result<std::vector<glm::vec3>> renderBaked(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                           const std::vector<bakefiles::LightmapImage>& lightmaps,
                                           const trace::View& view, const RenderOptions& options,
                                           Progress& progress,
                                           const std::vector<ProbeSphere>& spheres,
                                           const bakefiles::BakedReflections* reflections,
                                           const bakefiles::BakedDirectional* directional) {
  const int spa = std::max(1, options.samplesPerAxis);
  const bool reflecting = reflections && !reflections->empty();
  const runtime::ReflectionLighting probes = reflecting ? reflections->lighting()
                                                        : runtime::ReflectionLighting();
  const runtime::ReflectionLighting* lighting = reflecting ? &probes : nullptr;
  ProbeSphereIndex sphereIndex(spheres, view, options.width, options.height);
  sphereIndex.setReflections(lighting);
  return trace::renderPixels(view, options.width, options.height, "render", progress,
                      [&](const trace::PinholeCamera& camera, int px, int py) {
    // A fixed grid: the picture of a bake has no noise of its own.
    glm::vec3 sum(0.0f);
    for (int sy = 0; sy < spa; ++sy)
      for (int sx = 0; sx < spa; ++sx) {
        const trace::Ray ray = camera.ray(float(px) + (float(sx) + 0.5f) / float(spa),
                                   float(py) + (float(sy) + 0.5f) / float(spa));
        const trace::Hit hit = tracer.intersect(ray);
        glm::vec3 sphere;
        if (!sphereIndex.empty() && sphereIndex.shade(ray, px, py, hit.t, &sphere))
          sum += sphere;
        else
          sum += blendedRadiance(scene, tracer, lightmaps, ray, hit, lighting, directional);
      }
    return sum / float(spa * spa);
  });
}

Status writeRenderPng(const std::string& path, int width, int height,
                      const std::vector<glm::vec3>& image, float exposureStops) {
  const float exposure = chooseExposure(image, exposureStops).scale;
  AtomicOutput out;
  if (Status s = bakefiles::writeTonemappedPng(path, width, height, image, exposure, out); !s) return s;
  return out.commit();
}

Status writeRenderExr(const std::string& path, int width, int height,
                      const std::vector<glm::vec3>& image) {
  AtomicOutput out;
  if (Status s = bakefiles::writeExr(path, width, height, image, out, bakefiles::ExrPixels::Float); !s) return s;
  return out.commit();
}

}  // namespace afterglow::preview
