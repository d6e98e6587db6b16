#include "afterglow/baker/reflection_capture.h"
#include "afterglow/core/stages.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "afterglow/core/parallel.h"
#include "afterglow/trace/raytracer.h"
#include "afterglow/scenes/material_eval.h"

namespace afterglow::baker {

namespace {

using runtime::floatToHalf;
using runtime::ReflectionHit;

void putHalves(uint16_t out[3], glm::vec3 v) {
  for (int c = 0; c < 3; ++c) out[c] = floatToHalf(v[c]);
}

glm::vec3 safeRatio(glm::vec3 value, glm::vec3 factor) {
  glm::vec3 r(0.0f);
  for (int i = 0; i < 3; ++i)
    if (factor[i] > 0.0f) r[i] = value[i] / factor[i];
  return r;
}

// The transport's index of a primitive's material: glTF's default material (-1) is appended
// after the scene's materials, as fillMaterials does for the clusters.
uint32_t transportMaterial(const scenes::Scene& scene, int material,
                           runtime::TransportData& transport) {
  if (material >= 0 && size_t(material) < scene.materials.size()) return uint32_t(material);
  const uint32_t index = uint32_t(scene.materials.size());
  if (transport.materials.size() <= index) {
    const scenes::Material& m = scene.material(-1);
    transport.materials.push_back({"default", diffuseAlbedoFactor(m), m.emission()});
  }
  return index;
}

// What one capture ray hit, as the runtime shades it.
ReflectionHit recordHit(const scenes::Scene& scene, const trace::RayTracer& tracer, const trace::Hit& hit,
                        size_t atlasCount, runtime::TransportData& transport) {
  ReflectionHit h;
  if (!hit.valid()) return h;
  const scenes::Instance& inst = scene.instances[hit.instance];
  const int material = scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
  const scenes::Material& mat = scene.material(material);
  h.material = transportMaterial(scene, material, transport);
  h.distance = hit.t;
  // The back of a single-sided surface is black, as in the baked render, and so is a ray the
  // tint of glass absorbed: everything stays 0.
  if ((!hit.frontFace && !mat.doubleSided) || hit.absorbed) return h;
  const glm::vec2 uv0 = tracer.uv(hit, 0);
  const scenes::SurfaceBrdf brdf = surfaceBrdf(scene, material, uv0);
  const int atlas = inst.lightmap.atlas;
  if (inst.isStatic && atlas >= 0 && size_t(atlas) < atlasCount) {
    h.atlas = uint16_t(atlas);
    h.lightmapUv = tracer.uv(hit, 1);
    putHalves(h.diffuse, brdf.diffuse);
  }
  if (mat.emitsFrom(hit.frontFace))
    putHalves(h.emission, safeRatio(emittedRadiance(scene, material, uv0), mat.emission()));
  putHalves(h.f0, brdf.f0);
  h.roughness = floatToHalf(brdf.roughness);
  glm::vec3 normal = tracer.shadingNormal(hit);
  if (!hit.frontFace) normal = -normal;
  putHalves(h.normal, normal);
  return h;
}

// The q-quantile of values (reordered), or `fallback` for none.
float quantile(std::vector<float>& values, float q, float fallback) {
  if (values.empty()) return fallback;
  const size_t k = std::min(values.size() - 1, size_t(q * float(values.size())));
  std::nth_element(values.begin(), values.begin() + long(k), values.end());
  return values[k];
}

// Walls are the farthest surfaces around a probe and furniture stands in front of them, so a
// face of the box sits at this quantile of its rays' distances rather than at their median.
constexpr float kWallQuantile = 0.8f;

}  // namespace

runtime::ReflectionProbeBox fitReflectionProbeBox(const runtime::ReflectionProbeBox& nodeFrame,
                                                  const std::vector<ReflectionHit>& hits,
                                                  const std::vector<glm::vec3>& directions,
                                                  const scenes::Bounds& sceneBounds) {
  runtime::ReflectionProbeBox box = nodeFrame;
  const glm::vec3 origin = nodeFrame.capturePosition;
  const float cos30 = std::cos(30.0f * 3.14159265f / 180.0f);
  float reach[3][2];  // per local axis, toward − and +
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s < 2; ++s) {
      const glm::vec3 axis = nodeFrame.axes[a] * (s == 0 ? -1.0f : 1.0f);
      // Where the scene's bounds end along this axis: the farthest corner's projection.
      float bound = 0.0f;
      for (int corner = 0; corner < 8; ++corner) {
        const glm::vec3 c((corner & 1) ? sceneBounds.max.x : sceneBounds.min.x,
                          (corner & 2) ? sceneBounds.max.y : sceneBounds.min.y,
                          (corner & 4) ? sceneBounds.max.z : sceneBounds.min.z);
        bound = std::max(bound, glm::dot(c - origin, axis));
      }
      std::vector<float> along;
      for (size_t k = 0; k < hits.size(); ++k) {
        const float c = glm::dot(directions[k], axis);
        if (c >= cos30 && hits[k].material != runtime::kReflectionMiss)
          along.push_back(hits[k].distance * c);
      }
      reach[a][s] = std::max(quantile(along, kWallQuantile, bound), 1e-3f);
    }
  glm::vec3 offset(0.0f);
  for (int a = 0; a < 3; ++a) {
    box.projectionHalfSize[a] = 0.5f * (reach[a][0] + reach[a][1]);
    offset += nodeFrame.axes[a] * (0.5f * (reach[a][1] - reach[a][0]));
  }
  box.projectionCentre = origin + offset;
  // The walls take the probe's full weight: the influence fades in over blendDistance beyond
  // them, not inside.
  box.centre = box.projectionCentre;
  box.halfSize = box.projectionHalfSize + glm::vec3(std::max(box.blendDistance, 0.0f));
  return box;
}

Status captureReflectionProbes(const scenes::Scene& scene, const trace::RayTracer& tracer,
                               const ReflectionOptions& options,
                               runtime::TransportData& transport, Progress& progress) {
  runtime::ReflectionTransport& out = transport.reflections;
  out = runtime::ReflectionTransport();
  if (scene.reflectionProbes.empty()) return Status::ok();
  out.bounces = options.bounces;
  const size_t atlasCount = transport.lightmapAtlases().size();
  size_t total = 0;
  for (const scenes::ReflectionProbe& p : scene.reflectionProbes)
    total += size_t(runtime::kCubeFaceCount) * size_t(p.resolution) * size_t(p.resolution);
  progress.begin(stageName(Stage::ReflectionCapture), scene.reflectionProbes.size());
  out.hits.reserve(total);
  for (const scenes::ReflectionProbe& p : scene.reflectionProbes) {
    const int size = p.resolution;
    const size_t texels = size_t(runtime::kCubeFaceCount) * size_t(size) * size_t(size);
    const bool fitted = !(p.size.x != 0.0f && p.size.y != 0.0f && p.size.z != 0.0f);
    runtime::ReflectionProbeBox box =
        runtime::reflectionProbeBoxFromNode(p.transform, fitted ? glm::vec3(1.0f) : p.size);
    box.blendDistance = p.blendDistance;
    box.importance = p.importance;
    box.boxProjection = p.boxProjection;
    if (!fitted) {
      // The projection box: its own size when authored (the walls, the influence box reaching
      // beyond them), else the influence box.
      const glm::vec3 projection = p.projectionSize;
      box.projectionCentre = box.centre;
      box.projectionHalfSize =
          projection.x > 0.0f && projection.y > 0.0f && projection.z > 0.0f
              ? runtime::reflectionProbeBoxFromNode(p.transform, projection).halfSize
              : box.halfSize;
    }
    std::vector<glm::vec3> directions(texels);
    std::vector<trace::Ray> rays(texels);
    for (int face = 0, k = 0; face < runtime::kCubeFaceCount; ++face)
      for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x, ++k) {
          directions[size_t(k)] = runtime::cubemapTexelDirection(face, x, y, size);
          rays[size_t(k)].origin = box.capturePosition;
          rays[size_t(k)].direction = directions[size_t(k)];
        }
    std::vector<trace::Hit> hits(texels);
    constexpr size_t kBatch = 4096;
    parallelFor((texels + kBatch - 1) / kBatch, [&](size_t b) {
      const size_t begin = b * kBatch, n = std::min(kBatch, texels - begin);
      // Through glass by each ray's own chance, as the gather's rays: a texel of the cube
      // shows the glass or what lies beyond it, in the glass's proportions over many texels.
      tracer.intersect(rays.data() + begin, hits.data() + begin, n, trace::Glass::Light);
    }, 1);
    if (progress.cancelled()) return Status::error("cancelled");
    std::vector<ReflectionHit> records(texels);
    // Recorded in order (a hit on the default material may append it to the materials).
    for (size_t k = 0; k < texels; ++k)
      records[k] = recordHit(scene, tracer, hits[k], atlasCount, transport);
    if (fitted) box = fitReflectionProbeBox(box, records, directions, tracer.bounds());
    runtime::ReflectionProbeCapture capture;
    capture.name = p.name;
    capture.box = box;
    capture.resolution = uint32_t(size);
    capture.firstHit = out.hits.size();
    out.probes.push_back(capture);
    out.hits.insert(out.hits.end(), records.begin(), records.end());
    progress.advance();
  }
  progress.end();
  for (const runtime::MaterialParams& m : transport.materials) out.bakedAlbedo.push_back(m.albedo);
  return Status::ok();
}

}  // namespace afterglow::baker
