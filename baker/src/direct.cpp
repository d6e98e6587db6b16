// Stage 4 of the precompute: unit direct light per source (punctual light or emissive material)
// with soft shadows, as E/π per texel and per cluster.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "afterglow/baker/raytracer.h"
#include "afterglow/baker/transport_precompute.h"
#include "afterglow/core/parallel.h"
#include "sampling.h"

namespace afterglow::baker {

namespace {

using sampling::kPi;

// Shadow rays stop this fraction short of the light sample so the emitter itself, or geometry
// the light sits on, does not count as a blocker.
constexpr float kShadowShorten = 1e-3f;

// One world-space triangle of an emissive material.
struct EmitterTriangle {
  glm::vec3 p0, e1, e2;     // p0 + u·e1 + v·e2
  glm::vec3 normal;         // front side (glTF winding, flipped for mirroring transforms)
  glm::vec2 uv0, uv1, uv2;  // the emissive texture's UV set at the three corners
};

struct Emitter {
  uint32_t material = 0;
  bool doubleSided = false;
  std::vector<EmitterTriangle> triangles;
  std::vector<float> cdf;  // cumulative area, last entry = total area
  float totalArea = 0.0f;
};

std::vector<Emitter> collectEmitters(const scenes::Scene& scene) {
  std::vector<Emitter> emitters;
  std::vector<int> emitterOfMaterial(scene.materials.size(), -1);
  for (const scenes::Instance& inst : scene.instances) {
    if (inst.mesh < 0 || size_t(inst.mesh) >= scene.meshes.size()) continue;
    const bool mirrored = glm::determinant(glm::mat3(inst.transform)) < 0.0f;
    for (const scenes::Primitive& prim : scene.meshes[size_t(inst.mesh)].primitives) {
      if (prim.material < 0 || size_t(prim.material) >= scene.materials.size()) continue;
      const scenes::Material& m = scene.materials[size_t(prim.material)];
      if (!m.emissive()) continue;
      int& slot = emitterOfMaterial[size_t(prim.material)];
      if (slot < 0) {
        slot = int(emitters.size());
        emitters.emplace_back();
        emitters.back().material = uint32_t(prim.material);
        emitters.back().doubleSided = m.doubleSided;
      }
      Emitter& e = emitters[size_t(slot)];
      const std::vector<glm::vec2>& uvs =
          m.emissiveTexture.texCoord == 1 ? prim.uv1 : prim.uv0;
      for (size_t k = 0; k + 2 < prim.indices.size(); k += 3) {
        const uint32_t i0 = prim.indices[k], i1 = prim.indices[k + 1], i2 = prim.indices[k + 2];
        if (i0 >= prim.positions.size() || i1 >= prim.positions.size() ||
            i2 >= prim.positions.size())
          continue;
        const glm::vec3 a(inst.transform * glm::vec4(prim.positions[i0], 1.0f));
        const glm::vec3 b(inst.transform * glm::vec4(prim.positions[i1], 1.0f));
        const glm::vec3 c(inst.transform * glm::vec4(prim.positions[i2], 1.0f));
        const glm::vec3 cr = glm::cross(b - a, c - a);
        const float area = 0.5f * glm::length(cr);
        if (!(area > 0.0f) || !std::isfinite(area)) continue;
        EmitterTriangle tri;
        tri.p0 = a;
        tri.e1 = b - a;
        tri.e2 = c - a;
        tri.normal = (mirrored ? -cr : cr) / (2.0f * area);
        const bool hasUv = uvs.size() == prim.positions.size();
        tri.uv0 = hasUv ? uvs[i0] : glm::vec2(0.0f);
        tri.uv1 = hasUv ? uvs[i1] : glm::vec2(0.0f);
        tri.uv2 = hasUv ? uvs[i2] : glm::vec2(0.0f);
        e.triangles.push_back(tri);
        e.totalArea += area;
        e.cdf.push_back(e.totalArea);
      }
    }
  }
  emitters.erase(std::remove_if(emitters.begin(), emitters.end(),
                                [](const Emitter& e) { return e.triangles.empty(); }),
                 emitters.end());
  std::sort(emitters.begin(), emitters.end(),
            [](const Emitter& a, const Emitter& b) { return a.material < b.material; });
  return emitters;
}

// The emissive texture's modulation at a UV as one scalar: the Source scales by the material's
// emission() colour, so a coloured texture can only enter as its mean ratio over the lit
// channels (an untextured material gives exactly 1).
float emissionModulation(const scenes::Scene& scene, const scenes::Material& m, glm::vec2 uv) {
  const scenes::TextureRef& ref = m.emissiveTexture;
  if (!ref.valid() || size_t(ref.texture) >= scene.textures.size()) return 1.0f;
  const glm::vec3 tex(scene.textures[size_t(ref.texture)].sample(ref.transform(uv)));
  const glm::vec3 e = m.emission();
  float sum = 0.0f;
  int channels = 0;
  for (int i = 0; i < 3; ++i) {
    if (e[i] > 0.0f) sum += tex[i], ++channels;
  }
  return channels > 0 ? sum / float(channels) : 0.0f;
}

int primitiveMaterial(const scenes::Scene& scene, const Hit& hit) {
  const scenes::Instance& inst = scene.instances[hit.instance];
  return scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
}

struct Receiver {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec3 geometricNormal;
};

bool visible(const RayTracer& tracer, const Receiver& r, glm::vec3 dir, float tfar) {
  if (glm::dot(dir, r.geometricNormal) <= 0.0f) return false;  // behind the surface
  Ray ray;
  ray.origin = r.position;
  ray.direction = dir;
  ray.tfar = tfar;
  ray.mask = kMaskShadowCasters;
  return !tracer.occluded(ray);
}

// glTF's recommended range window and spot cone (KHR_lights_punctual README).
float rangeWindow(float distance, float range) {
  if (range <= 0.0f) return 1.0f;
  const float x = distance / range;
  const float w = std::clamp(1.0f - x * x * x * x, 0.0f, 1.0f);
  return w * w;
}

float spotCone(const scenes::Light& light, glm::vec3 toReceiver) {
  const float cosOuter = std::cos(light.outerConeAngle);
  const float cosInner = std::cos(light.innerConeAngle);
  const float scale = 1.0f / std::max(1e-3f, cosInner - cosOuter);
  const float offset = -cosOuter * scale;
  const float cd = glm::dot(glm::normalize(light.direction), toReceiver);
  const float a = std::clamp(cd * scale + offset, 0.0f, 1.0f);
  return a * a;
}

// E/π at the receiver for a light of colour 1 and intensity 1.
float punctualTransfer(const RayTracer& tracer, const scenes::Light& light, uint32_t lightIndex,
                       const Receiver& r, uint64_t item, int samples) {
  const uint64_t seedBase = uint64_t(lightIndex) << 32;
  if (light.type == scenes::LightType::Directional) {
    const glm::vec3 l = -glm::normalize(light.direction);
    const float cosTheta = glm::dot(r.normal, l);
    if (cosTheta <= 0.0f) return 0.0f;
    const float inf = std::numeric_limits<float>::infinity();
    float vis;
    if (light.angularDiameter > 0.0f && samples > 1) {
      const sampling::Frame frame(l);
      const float cosMax = std::cos(0.5f * light.angularDiameter);
      int seen = 0;
      for (int s = 0; s < samples; ++s) {
        sampling::Rng rng(sampling::Stream::LightVisibility, item, seedBase | uint32_t(s));
        const glm::vec3 dir = frame.toWorld(
            sampling::uniformCone(sampling::stratified2(rng, uint32_t(s), uint32_t(samples)),
                                  cosMax));
        seen += visible(tracer, r, dir, inf) ? 1 : 0;
      }
      vis = float(seen) / float(samples);
    } else {
      vis = visible(tracer, r, l, inf) ? 1.0f : 0.0f;
    }
    return cosTheta / kPi * vis;
  }

  const glm::vec3 d = light.position - r.position;
  const float dist = glm::length(d);
  if (!(dist > 0.0f)) return 0.0f;
  const glm::vec3 l = d / dist;
  const float cosTheta = glm::dot(r.normal, l);
  if (cosTheta <= 0.0f) return 0.0f;
  float falloff = rangeWindow(dist, light.range) / (dist * dist);
  if (light.type == scenes::LightType::Spot) falloff *= spotCone(light, -l);
  if (falloff <= 0.0f) return 0.0f;
  float vis;
  if (light.radius > 0.0f && samples > 1) {
    // Points on the sphere's silhouette disk as seen from the receiver: the sphere's visible
    // extent, which is what decides the penumbra.
    const sampling::Frame frame(-l);
    int seen = 0;
    for (int s = 0; s < samples; ++s) {
      sampling::Rng rng(sampling::Stream::LightVisibility, item, seedBase | uint32_t(s));
      const glm::vec2 disk = sampling::uniformDisk(
          sampling::stratified2(rng, uint32_t(s), uint32_t(samples)));
      const glm::vec3 q = light.position + light.radius * (frame.t * disk.x + frame.b * disk.y);
      const glm::vec3 w = q - r.position;
      const float len = glm::length(w);
      if (!(len > 0.0f)) continue;
      seen += visible(tracer, r, w / len, len * (1.0f - kShadowShorten)) ? 1 : 0;
    }
    vis = float(seen) / float(samples);
  } else {
    vis = visible(tracer, r, l, dist * (1.0f - kShadowShorten)) ? 1.0f : 0.0f;
  }
  return cosTheta / kPi * falloff * vis;
}

// E/π at the receiver from an emissive material of unit radiance, (1/π) ∫ Le cosθ dω over the
// visible emitter. Two strategies combined with the balance heuristic (multiple importance
// sampling): points on the emitters chosen by area (stratified over the area CDF), good for
// small or distant emitters, and cosine-distributed rays that hit them, good for large or near
// ones (a texel next to an emissive wall, a furnace). Each alone is noisy where the other shines.
float emissiveTransfer(const scenes::Scene& scene, const RayTracer& tracer, const Emitter& e,
                       const Receiver& r, uint64_t item, int samples) {
  const scenes::Material& m = scene.materials[e.material];
  const uint64_t seedBase = uint64_t(e.material) << 32;
  const int areaSamples = (samples + 1) / 2;
  const int cosineSamples = samples - areaSamples;
  const double nA = double(areaSamples), nB = double(cosineSamples);
  // Solid-angle pdf of area sampling for a point at distance dist seen at emitter cosine cosEmit.
  auto areaPdf = [&](float dist, float cosEmit) {
    return double(dist) * double(dist) / (double(cosEmit) * double(e.totalArea));
  };
  double sum = 0.0;
  for (int s = 0; s < areaSamples; ++s) {
    sampling::Rng rng(sampling::Stream::Emissive, item, seedBase | uint32_t(s));
    const float pick = (float(s) + rng.next()) / float(areaSamples) * e.totalArea;
    size_t k = size_t(std::upper_bound(e.cdf.begin(), e.cdf.end(), pick) - e.cdf.begin());
    k = std::min(k, e.triangles.size() - 1);
    const EmitterTriangle& tri = e.triangles[k];
    glm::vec2 u = rng.next2();
    if (u.x + u.y > 1.0f) u = glm::vec2(1.0f) - u;
    const glm::vec3 q = tri.p0 + u.x * tri.e1 + u.y * tri.e2;
    const glm::vec3 w = q - r.position;
    const float dist2 = glm::dot(w, w);
    if (!(dist2 > 0.0f)) continue;
    const float dist = std::sqrt(dist2);
    const glm::vec3 dir = w / dist;
    const float cosTheta = glm::dot(r.normal, dir);
    if (cosTheta <= 0.0f) continue;
    float cosEmit = -glm::dot(tri.normal, dir);
    if (e.doubleSided) cosEmit = std::abs(cosEmit);
    if (cosEmit <= 0.0f) continue;
    const float mod = emissionModulation(
        scene, m, (1.0f - u.x - u.y) * tri.uv0 + u.x * tri.uv1 + u.y * tri.uv2);
    if (mod <= 0.0f) continue;
    if (!visible(tracer, r, dir, dist * (1.0f - kShadowShorten))) continue;
    const double g = double(mod) * double(cosTheta) / double(kPi);
    sum += g / (nA * areaPdf(dist, cosEmit) + nB * double(cosTheta) / double(kPi));
  }
  if (cosineSamples > 0) {
    const sampling::Frame frame(r.normal);
    for (int s = 0; s < cosineSamples; ++s) {
      sampling::Rng rng(sampling::Stream::Emissive, item,
                        seedBase | uint32_t(areaSamples + s));
      const glm::vec3 dir = frame.toWorld(sampling::cosineHemisphere(
          sampling::stratified2(rng, uint32_t(s), uint32_t(cosineSamples))));
      if (glm::dot(dir, r.geometricNormal) <= 0.0f) continue;
      Ray ray;
      ray.origin = r.position;
      ray.direction = dir;
      ray.mask = kMaskShadowCasters;
      const Hit hit = tracer.intersect(ray);
      if (!hit.valid() || primitiveMaterial(scene, hit) != int(e.material)) continue;
      if (!hit.frontFace && !e.doubleSided) continue;
      const float cosEmit = std::abs(glm::dot(hit.geometricNormal, dir));
      if (cosEmit <= 0.0f) continue;
      const int set = m.emissiveTexture.texCoord == 1 ? 1 : 0;
      const float mod = emissionModulation(scene, m, tracer.uv(hit, set));
      if (mod <= 0.0f) continue;
      const float cosTheta = glm::dot(r.normal, dir);
      const double g = double(mod) * double(cosTheta) / double(kPi);
      sum += g / (nA * areaPdf(hit.t, cosEmit) + nB * double(cosTheta) / double(kPi));
    }
  }
  return float(sum);
}

}  // namespace

Status computeDirect(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels,
                     const Clusters& clusters, const DirectOptions& options,
                     runtime::TransportData& transport, Progress& progress) {
  if (options.lightSamples <= 0 || options.emissiveSamples <= 0)
    return Status::error("computeDirect: lightSamples and emissiveSamples must be positive");
  const uint32_t texelCount = texels.size();
  const uint32_t clusterCount = clusters.size();
  if (clusterCount > 0 && clusters.firstTexel.size() != size_t(clusterCount) + 1)
    return Status::error("computeDirect: Clusters::firstTexel needs one entry per cluster plus one");

  const std::vector<Emitter> emitters = collectEmitters(scene);
  const size_t lightCount = scene.lights.size();
  transport.texelCount = texelCount;
  transport.clusterCount = clusterCount;
  transport.sources.clear();
  for (const scenes::Light& light : scene.lights) {
    runtime::Source s;
    s.name = light.name;
    s.kind = runtime::SourceKind::Light;
    s.color = light.color;
    s.intensity = light.intensity;
    s.bounceIntensity = light.bounceIntensity;
    transport.sources.push_back(std::move(s));
  }
  for (const Emitter& e : emitters) {
    runtime::Source s;
    s.name = scene.materials[e.material].name;
    s.kind = runtime::SourceKind::Emissive;
    s.material = e.material;
    transport.sources.push_back(std::move(s));
  }
  for (runtime::Source& s : transport.sources) {
    s.texelTransfer.assign(texelCount, 0.0f);
    s.clusterTransfer.assign(clusterCount, 0.0f);
  }

  progress.begin("direct light", texelCount);
  parallelForBlocks(texelCount, [&](size_t begin, size_t end, int) {
    for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
      if (!texels.valid[t]) continue;
      const Receiver r{texels.position[t], texels.normal[t], texels.geometricNormal[t]};
      for (size_t l = 0; l < lightCount; ++l)
        transport.sources[l].texelTransfer[t] = punctualTransfer(
            tracer, scene.lights[l], uint32_t(l), r, t, options.lightSamples);
      for (size_t k = 0; k < emitters.size(); ++k)
        transport.sources[lightCount + k].texelTransfer[t] =
            emissiveTransfer(scene, tracer, emitters[k], r, t, options.emissiveSamples);
    }
    progress.advance(end - begin);
  });
  progress.end();
  if (progress.cancelled()) return Status::error("computeDirect: cancelled");

  // Cluster transfer: area-weighted mean over the cluster's valid texels.
  for (uint32_t c = 0; c < clusterCount; ++c) {
    double areaSum = 0.0;
    for (uint32_t k = clusters.firstTexel[c]; k < clusters.firstTexel[c + 1]; ++k) {
      const uint32_t t = clusters.memberTexels[k];
      if (texels.valid[t]) areaSum += double(texels.area[t]);
    }
    if (!(areaSum > 0.0)) continue;
    for (runtime::Source& s : transport.sources) {
      double sum = 0.0;
      for (uint32_t k = clusters.firstTexel[c]; k < clusters.firstTexel[c + 1]; ++k) {
        const uint32_t t = clusters.memberTexels[k];
        if (texels.valid[t]) sum += double(texels.area[t]) * double(s.texelTransfer[t]);
      }
      s.clusterTransfer[c] = float(sum / areaSum);
    }
  }
  return Status::ok();
}

}  // namespace afterglow::baker
