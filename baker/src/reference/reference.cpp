// The reference path tracer (reference.h, path_tracer.h).
#include "afterglow/baker/reference.h"
#include "afterglow/core/stages.h"
#include "afterglow/runtime/probe_sh.h"

#include <algorithm>
#include <cmath>

#include "afterglow/core/parallel.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/material_eval.h"
#include "shading/light_model.h"
#include "reference/path_tracer.h"

namespace afterglow::baker {

namespace {


glm::vec3 skyRadiance(const glm::vec3 sh[runtime::kShCount], glm::vec3 direction) {
  float y[runtime::kShCount];
  sampling::shBasis(direction, y);
  glm::vec3 sum(0.0f);
  for (int i = 0; i < runtime::kShCount; ++i) sum += sh[i] * y[i];
  return sum;
}

float maxComponent(glm::vec3 v) { return std::max({v.x, v.y, v.z}); }

int hitMaterial(const scenes::Scene& scene, const trace::Hit& hit) {
  const scenes::Instance& inst = scene.instances[hit.instance];
  return scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
}

}  // namespace

PathTracer::PathTracer(const scenes::Scene& scene, const trace::RayTracer& tracer,
                       const Environment& environment, int maxDepth)
    : scene_(scene), tracer_(tracer), env_(environment), maxDepth_(std::max(1, maxDepth)) {
  emitters_ = collectEmitters(scene);
  emitterOfMaterial_.assign(scene.materials.size(), -1);
  double total = 0.0;
  for (size_t k = 0; k < emitters_.size(); ++k) {
    const Emitter& e = emitters_[k];
    emitterOfMaterial_[e.material] = int(k);
    total += double(e.totalArea) * double(maxComponent(scene.materials[e.material].emission()));
    emitterCdf_.push_back(float(total));
  }
  for (size_t k = 0; k < emitters_.size(); ++k) {
    const float lo = k > 0 ? emitterCdf_[k - 1] : 0.0f;
    emitterPick_.push_back(total > 0.0 ? float((double(emitterCdf_[k]) - lo) / total) : 0.0f);
  }
}

float PathTracer::offset(glm::vec3 p) const {
  const float scale = std::max({1.0f, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  return 2e-5f * scale;
}

float PathTracer::emitterPdf(const trace::Hit& hit, glm::vec3 direction) const {
  const int material = hitMaterial(scene_, hit);
  if (material < 0 || size_t(material) >= emitterOfMaterial_.size()) return 0.0f;
  const int k = emitterOfMaterial_[size_t(material)];
  if (k < 0) return 0.0f;
  const float cosEmit = std::abs(glm::dot(hit.geometricNormal, direction));
  if (!(cosEmit > 0.0f)) return 0.0f;
  return emitterPick_[size_t(k)] / emitters_[size_t(k)].totalArea * hit.t * hit.t / cosEmit;
}

glm::vec3 PathTracer::nextEvent(glm::vec3 p, glm::vec3 n, glm::vec3 ng, bool bounced,
                                sampling::Rng& rng) const {
  glm::vec3 sum(0.0f);
  // What gets through to the light, per channel (glass tints it).
  auto unblocked = [&](glm::vec3 dir, float length) {
    if (glm::dot(dir, ng) <= 0.0f) return glm::vec3(0.0f);
    trace::Ray ray;
    ray.origin = p;
    ray.direction = dir;
    ray.tfar = length;
    ray.mask = trace::kMaskShadowCasters;
    return tracer_.transmittance(ray);
  };
  for (const scenes::Light& light : scene_.lights) {
    const LightView view = viewLight(light, p, n);
    if (!(view.transfer > 0.0f)) continue;
    glm::vec3 dir;
    float length;
    lightShadowRay(light, view, p, rng.next2(), &dir, &length);
    const glm::vec3 through = unblocked(dir, length);
    if (through == glm::vec3(0.0f)) continue;
    const float scale = light.intensity * (bounced ? light.bounceIntensity : 1.0f);
    sum += through * (light.color * scale * view.transfer);
  }
  if (emitters_.empty() || !(emitterCdf_.back() > 0.0f)) return sum;
  // One emissive point, the emitter chosen by power, weighted against the cosine-sampled
  // continuation that could have found the same point (balance heuristic).
  const float pick = rng.next() * emitterCdf_.back();
  size_t k = size_t(std::upper_bound(emitterCdf_.begin(), emitterCdf_.end(), pick) -
                    emitterCdf_.begin());
  k = std::min(k, emitters_.size() - 1);
  const Emitter& e = emitters_[k];
  const EmitterSample q = sampleEmitter(e, rng.next2());
  const glm::vec3 w = q.point - p;
  const float dist2 = glm::dot(w, w);
  if (!(dist2 > 0.0f)) return sum;
  const float dist = std::sqrt(dist2);
  const glm::vec3 dir = w / dist;
  const float cosTheta = glm::dot(n, dir);
  float cosEmit = -glm::dot(q.normal, dir);
  if (e.doubleSided) cosEmit = std::abs(cosEmit);
  if (cosTheta <= 0.0f || cosEmit <= 0.0f) return sum;
  const glm::vec3 through = unblocked(dir, dist * (1.0f - kShadowShorten));
  if (through == glm::vec3(0.0f)) return sum;
  const glm::vec3 le = emittedRadiance(scene_, int(e.material), q.uv);
  const float pdfLight = emitterPick_[k] * q.pdfArea * dist2 / cosEmit;  // solid angle
  const float pdfCosine = cosTheta / kPi;
  // E/π = (1/π) ∫ Le cosθ dω; the estimator Le cosθ / (π pdfLight) times the MIS weight.
  sum += through * (le * (cosTheta / kPi) / (pdfLight + pdfCosine));
  return sum;
}

PathTracer::Estimate PathTracer::irradiance(glm::vec3 p, glm::vec3 n, glm::vec3 ng, glm::vec2 u,
                                            sampling::Rng& rng) const {
  Estimate out;
  glm::vec3 throughput(1.0f);
  for (int depth = 0;; ++depth) {
    glm::vec3& bucket = depth == 0 ? out.direct : out.indirect;
    bucket += throughput * nextEvent(p, n, ng, depth > 0, rng);

    // Continue with a cosine-distributed direction (mirrored above the geometric surface when
    // the shading normal tilts it below, as the precompute's gather rays do).
    const sampling::Frame frame(n);
    glm::vec3 dir = frame.toWorld(sampling::cosineHemisphere(depth == 0 ? u : rng.next2()));
    const float below = glm::dot(dir, ng);
    if (below < 0.0f) dir = glm::normalize(dir - 2.0f * below * ng);
    const float pdfCosine = std::max(0.0f, glm::dot(n, dir)) / kPi;
    trace::Ray ray;
    ray.origin = p;
    ray.direction = dir;
    // Emission, of whatever the ray meets (MIS-weighted against nextEvent's emitter samples).
    auto emission = [&](const trace::Hit& met) {
      if (!scene_.instances[met.instance].isStatic) return;
      const int m = hitMaterial(scene_, met);
      const scenes::Material& mat = scene_.material(m);
      if (!mat.emissive() || !mat.emitsFrom(met.frontFace)) return;
      const float pdfLight = emitterPdf(met, dir);
      const float weight = pdfCosine > 0.0f ? pdfCosine / (pdfCosine + pdfLight) : 1.0f;
      bucket += throughput * emittedRadiance(scene_, m, tracer_.uv(met, 0)) * weight;
    };
    const trace::Hit hit = throughGlass(ray, throughput, rng, emission);
    if (!hit.valid()) {
      bucket += throughput * skyRadiance(env_.skySh, dir);
      break;
    }
    const scenes::Instance& inst = scene_.instances[hit.instance];
    const int material = hitMaterial(scene_, hit);
    const scenes::Material& mat = scene_.material(material);
    if (!inst.isStatic) break;                       // dynamic: blocks, takes no part
    if (!hit.frontFace && !mat.doubleSided) break;   // inside a wall
    const glm::vec2 uv0 = tracer_.uv(hit, 0);
    if (depth + 1 >= maxDepth_) break;
    throughput *= runtime::boostAlbedo(diffuseAlbedo(scene_, material, uv0), env_.albedoBoost);
    if (depth >= 2) {
      const float survive = std::min(0.95f, maxComponent(throughput));
      if (!(survive > 0.0f) || rng.next() >= survive) break;
      throughput /= survive;
    }
    if (maxComponent(throughput) <= 0.0f) break;
    const float side = hit.frontFace ? 1.0f : -1.0f;
    ng = hit.geometricNormal * side;
    n = tracer_.shadingNormal(hit) * side;
    if (glm::dot(n, ng) <= 0.0f) n = ng;
    p = tracer_.position(hit);
    p += ng * offset(p);
  }
  out.indirect *= env_.indirectIntensity;
  return out;
}

glm::vec3 PathTracer::cameraRadiance(const trace::Ray& ray, glm::vec2 u, sampling::Rng& rng) const {
  glm::vec3 throughput(1.0f);
  const trace::Hit hit = throughGlass(ray, throughput, rng, [](const trace::Hit&) {});
  if (!hit.valid()) return glm::vec3(0.0f);
  const scenes::Instance& inst = scene_.instances[hit.instance];
  const int material = hitMaterial(scene_, hit);
  const scenes::Material& mat = scene_.material(material);
  if (!hit.frontFace && !mat.doubleSided) return glm::vec3(0.0f);
  const glm::vec2 uv0 = tracer_.uv(hit, 0);
  const glm::vec3 radiance =
      throughput * (mat.emitsFrom(hit.frontFace) ? emittedRadiance(scene_, material, uv0)
                                                 : glm::vec3(0.0f));
  if (!inst.isStatic || inst.lightmap.atlas < 0) return radiance;
  const float side = hit.frontFace ? 1.0f : -1.0f;
  const glm::vec3 ng = hit.geometricNormal * side;
  glm::vec3 n = tracer_.shadingNormal(hit) * side;
  if (glm::dot(n, ng) <= 0.0f) n = ng;
  glm::vec3 p = tracer_.position(hit);
  p += ng * offset(p);
  const Estimate e = irradiance(p, n, ng, u, rng);
  return radiance + throughput * diffuseAlbedo(scene_, material, uv0) * (e.direct + e.indirect);
}

glm::vec3 PathTracer::probeRadiance(const trace::Ray& ray, int specularDepth, sampling::Rng& rng) const {
  glm::vec3 throughput(1.0f);
  const trace::Hit hit = throughGlass(ray, throughput, rng, [](const trace::Hit&) {});
  if (!hit.valid())
    return throughput * glm::max(skyRadiance(env_.skySh, ray.direction), glm::vec3(0.0f));
  const scenes::Instance& inst = scene_.instances[hit.instance];
  const int material = hitMaterial(scene_, hit);
  const scenes::Material& mat = scene_.material(material);
  if (!hit.frontFace && !mat.doubleSided) return glm::vec3(0.0f);
  const glm::vec2 uv0 = tracer_.uv(hit, 0);
  glm::vec3 radiance =
      throughput * (mat.emitsFrom(hit.frontFace) ? emittedRadiance(scene_, material, uv0)
                                                 : glm::vec3(0.0f));
  const scenes::SurfaceBrdf brdf = surfaceBrdf(scene_, material, uv0);
  const float side = hit.frontFace ? 1.0f : -1.0f;
  const glm::vec3 ng = hit.geometricNormal * side;
  glm::vec3 n = tracer_.shadingNormal(hit) * side;
  if (glm::dot(n, ng) <= 0.0f) n = ng;
  glm::vec3 p = tracer_.position(hit);
  p += ng * offset(p);
  if (inst.isStatic && inst.lightmap.atlas >= 0) {
    const Estimate e = irradiance(p, n, ng, rng.next2(), rng);
    radiance += throughput * brdf.diffuse * (e.direct + e.indirect);
  }
  if (specularDepth <= 0 || brdf.f0 == glm::vec3(0.0f)) return radiance;
  const glm::vec3 v = -ray.direction;
  const float nDotV = glm::dot(n, v);
  if (!(nDotV > 0.0f)) return radiance;
  // A half vector from GGX's D (α = roughness²): cos θh = √((1 − ξ) / (1 + (α² − 1) ξ)).
  const float alpha = std::max(brdf.roughness * brdf.roughness, 1e-4f), a2 = alpha * alpha;
  const glm::vec2 xi = rng.next2();
  const float cosH = std::sqrt((1.0f - xi.x) / (1.0f + (a2 - 1.0f) * xi.x));
  const float sinH = std::sqrt(std::max(0.0f, 1.0f - cosH * cosH)), phi = 2.0f * kPi * xi.y;
  const glm::vec3 t = glm::normalize(std::abs(n.x) > 0.5f ? glm::cross(n, glm::vec3(0, 1, 0))
                                                          : glm::cross(n, glm::vec3(1, 0, 0)));
  const glm::vec3 h = sinH * std::cos(phi) * t + sinH * std::sin(phi) * glm::cross(n, t) + cosH * n;
  const float vDotH = glm::dot(v, h);
  const glm::vec3 l = 2.0f * vDotH * h - v;
  const float nDotL = glm::dot(n, l);
  if (vDotH <= 0.0f || nDotL <= 0.0f) return radiance;
  // f (n·l) / pdf(l), pdf(l) = D (n·h) / (4 (v·h)): D cancels, leaving
  // F · 4 Vis (n·l)(v·h) / (n·h), Vis = 0.5 / ((n·l) Λ(v) + (n·v) Λ(l)) height-correlated.
  const float lv = nDotL * std::sqrt(nDotV * nDotV * (1.0f - a2) + a2);
  const float ll = nDotV * std::sqrt(nDotL * nDotL * (1.0f - a2) + a2);
  const float vis = 0.5f / (lv + ll);
  const glm::vec3 fresnel = brdf.f0 + (1.0f - brdf.f0) * std::pow(1.0f - vDotH, 5.0f);
  trace::Ray next;
  next.origin = p;
  next.direction = l;
  return radiance + throughput * fresnel * (4.0f * vis * nDotL * vDotH / cosH) *
                        probeRadiance(next, specularDepth - 1, rng);
}

glm::vec3 PathTracer::cameraRadianceWithSpecular(const trace::Ray& ray, int specularDepth,
                                                 sampling::Rng& rng) const {
  if (!tracer_.intersect(ray).valid()) return glm::vec3(0.0f);
  return probeRadiance(ray, specularDepth, rng);
}

namespace {

// The mean of a point's path estimates and the variance of that mean as if the paths were
// independent (the stratified first direction makes the true variance smaller, so this is an
// upper bound on the reference's noise).
struct Moments {
  glm::dvec3 sum{0.0}, squares{0.0};
  void add(glm::dvec3 v) {
    sum += v;
    squares += v * v;
  }
  glm::vec3 mean(uint32_t n) const { return glm::vec3(sum / double(n)); }
  glm::vec3 varianceOfMean(uint32_t n) const {
    if (n < 2) return glm::vec3(0.0f);
    const double m = double(n);
    const glm::dvec3 mu = sum / m;
    return glm::vec3(glm::max(squares / m - mu * mu, 0.0) / (m - 1.0));
  }
};

}  // namespace

Result<ReferenceTexels> referenceTexels(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                        const TexelSet& texels, const Environment& environment,
                                        const ReferenceOptions& options,
                                        const std::vector<uint32_t>& which, Progress& progress) {
  if (options.samples <= 0) return Status::error("reference: samples must be positive");
  ReferenceTexels out;
  if (which.empty()) {
    for (uint32_t t = 0; t < texels.size(); ++t)
      if (texels.valid[t]) out.texels.push_back(t);
  } else {
    for (uint32_t t : which)
      if (t >= texels.size()) return Status::error(format("reference: no texel %u", t));
    out.texels = which;
  }
  const size_t count = out.texels.size();
  out.direct.assign(count, glm::vec3(0.0f));
  out.indirect.assign(count, glm::vec3(0.0f));
  out.directVariance.assign(count, glm::vec3(0.0f));
  out.indirectVariance.assign(count, glm::vec3(0.0f));
  const PathTracer pt(scene, tracer, environment, options.maxDepth);
  const uint32_t samples = uint32_t(options.samples);
  progress.begin(stageName(Stage::Reference), count);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    for (size_t i = begin; i < end && !progress.cancelled(); ++i) {
      const uint32_t t = out.texels[i];
      Moments direct, indirect;
      for (uint32_t s = 0; s < samples; ++s) {
        sampling::Rng rng(sampling::Stream::Reference, t, s);
        const glm::vec2 u = sampling::stratified2(rng, s, samples);
        const PathTracer::Estimate e = pt.irradiance(texels.position[t], texels.normal[t],
                                                     texels.geometricNormal[t], u, rng);
        direct.add(glm::dvec3(e.direct));
        indirect.add(glm::dvec3(e.indirect));
      }
      out.direct[i] = direct.mean(samples);
      out.indirect[i] = indirect.mean(samples);
      out.directVariance[i] = direct.varianceOfMean(samples);
      out.indirectVariance[i] = indirect.varianceOfMean(samples);
      progress.advance();
    }
  }, 4);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  return out;
}

Result<ReferencePoints> referenceIrradiance(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                            const Environment& environment,
                                            const std::vector<glm::vec3>& points,
                                            const std::vector<glm::vec3>& normals,
                                            const ReferenceOptions& options, Progress& progress) {
  if (options.samples <= 0) return Status::error("reference: samples must be positive");
  if (points.size() != normals.size())
    return Status::error("reference: as many normals as points are needed");
  const size_t count = points.size();
  ReferencePoints out;
  out.irradiance.assign(count, glm::vec3(0.0f));
  out.variance.assign(count, glm::vec3(0.0f));
  const PathTracer pt(scene, tracer, environment, options.maxDepth);
  const uint32_t samples = uint32_t(options.samples);
  progress.begin(stageName(Stage::Reference), count);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    for (size_t i = begin; i < end && !progress.cancelled(); ++i) {
      const glm::vec3 n = glm::normalize(normals[i]);
      Moments total;
      for (uint32_t s = 0; s < samples; ++s) {
        sampling::Rng rng(sampling::Stream::Reference, (uint64_t(1) << 40) | i, s);
        const glm::vec2 u = sampling::stratified2(rng, s, samples);
        const PathTracer::Estimate e = pt.irradiance(points[i], n, n, u, rng);
        total.add(glm::dvec3(e.direct) + glm::dvec3(e.indirect));
      }
      out.irradiance[i] = total.mean(samples);
      out.variance[i] = total.varianceOfMean(samples);
      progress.advance();
    }
  }, 1);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  return out;
}

Result<std::vector<runtime::ShL2>> referenceRadianceSh(const scenes::Scene& scene,
                                                       const trace::RayTracer& tracer,
                                                       const Environment& environment,
                                                       const std::vector<glm::vec3>& points,
                                                       const ReferenceOptions& options,
                                                       Progress& progress) {
  if (options.samples <= 0) return Status::error("reference: samples must be positive");
  const size_t count = points.size();
  std::vector<runtime::ShL2> out(count);
  const PathTracer pt(scene, tracer, environment, options.maxDepth);
  const uint32_t samples = uint32_t(options.samples);
  progress.begin(stageName(Stage::Reference), count);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    for (size_t i = begin; i < end && !progress.cancelled(); ++i) {
      glm::dvec3 sum[runtime::kShCount] = {};
      for (uint32_t s = 0; s < samples; ++s) {
        sampling::Rng rng(sampling::Stream::Reference, (uint64_t(2) << 40) | i, s);
        const glm::vec2 u = sampling::stratified2(rng, s, samples);
        // Uniform over the sphere: z = 1 − 2u, φ = 2πv (equal areas).
        const float z = 1.0f - 2.0f * u.x, r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        const float phi = 2.0f * kPi * u.y;
        trace::Ray ray;
        ray.origin = points[i];
        ray.direction = glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
        const glm::vec3 radiance = pt.cameraRadiance(ray, rng.next2(), rng);
        float y[runtime::kShCount];
        runtime::shBasis(ray.direction, y);
        for (int k = 0; k < runtime::kShCount; ++k) sum[k] += glm::dvec3(radiance) * double(y[k]);
      }
      for (int k = 0; k < runtime::kShCount; ++k)
        out[i].c[k] = glm::vec3(sum[k] * (4.0 * double(kPi) / double(samples)));
      progress.advance();
    }
  }, 1);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  return out;
}

Result<ReferencePoints> referenceRadiance(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                          const Environment& environment,
                                          const std::vector<trace::Ray>& rays,
                                          const ReferenceOptions& options, Progress& progress) {
  if (options.samples <= 0) return Status::error("reference: samples must be positive");
  const size_t count = rays.size();
  ReferencePoints out;
  out.irradiance.assign(count, glm::vec3(0.0f));
  out.variance.assign(count, glm::vec3(0.0f));
  const PathTracer pt(scene, tracer, environment, options.maxDepth);
  const uint32_t samples = uint32_t(options.samples);
  progress.begin(stageName(Stage::Reference), count);
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    for (size_t i = begin; i < end && !progress.cancelled(); ++i) {
      glm::dvec3 sum(0.0), squares(0.0);
      for (uint32_t s = 0; s < samples; ++s) {
        sampling::Rng rng(sampling::Stream::Reference, (uint64_t(3) << 40) | i, s);
        const glm::dvec3 l(pt.probeRadiance(rays[i], options.specularDepth, rng));
        sum += l;
        squares += l * l;
      }
      const glm::dvec3 mean = sum / double(samples);
      out.irradiance[i] = glm::vec3(mean);
      out.variance[i] = glm::vec3(glm::max(squares / double(samples) - mean * mean, glm::dvec3(0.0)) /
                                  double(samples));
      progress.advance();
    }
  }, 1);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  return out;
}

ReferenceComparison compareToReference(const ReferenceTexels& reference,
                                       const std::vector<glm::vec3>& bakedDirect,
                                       const std::vector<glm::vec3>& bakedIndirect) {
  struct Pair {
    glm::dvec3 baked, ref, variance;
  };
  ReferenceComparison out;
  std::vector<Pair> direct, indirect, total;
  for (size_t i = 0; i < reference.texels.size(); ++i) {
    const uint32_t t = reference.texels[i];
    if (t >= bakedDirect.size() || t >= bakedIndirect.size()) continue;
    direct.push_back({bakedDirect[t], reference.direct[i], reference.directVariance[i]});
    indirect.push_back({bakedIndirect[t], reference.indirect[i], reference.indirectVariance[i]});
    total.push_back({glm::dvec3(bakedDirect[t]) + glm::dvec3(bakedIndirect[t]),
                     glm::dvec3(reference.direct[i]) + glm::dvec3(reference.indirect[i]),
                     glm::dvec3(reference.directVariance[i]) +
                         glm::dvec3(reference.indirectVariance[i])});
  }
  out.texels = direct.size();
  auto stats = [](const std::vector<Pair>& pairs) {
    ErrorStats s;
    if (pairs.empty()) return s;
    double meanNorm = 0.0, meanSum = 0.0;
    for (const Pair& p : pairs) {
      meanNorm += glm::length(p.ref);
      meanSum += p.ref.x + p.ref.y + p.ref.z;
    }
    const double n = double(pairs.size());
    meanNorm /= n;
    s.referenceMean = meanSum / n;
    if (!(meanNorm > 0.0)) return s;
    const double floorNorm = 0.1 * meanNorm, floorSum = 0.1 * s.referenceMean;
    double e2 = 0.0, signedSum = 0.0, noise2 = 0.0;
    for (const Pair& p : pairs) {
      const double scale = std::max(glm::length(p.ref), floorNorm);
      const glm::dvec3 d = p.baked - p.ref;
      e2 += glm::dot(d, d) / (scale * scale);
      noise2 += (p.variance.x + p.variance.y + p.variance.z) / (scale * scale);
      const double refSum = p.ref.x + p.ref.y + p.ref.z;
      signedSum += (d.x + d.y + d.z) / std::max(refSum, floorSum);
    }
    s.relativeRmse = std::sqrt(e2 / n);
    s.bias = signedSum / n;
    s.referenceNoise = std::sqrt(noise2 / n);
    return s;
  };
  out.direct = stats(direct);
  out.indirect = stats(indirect);
  out.total = stats(total);
  return out;
}

Result<std::vector<glm::vec3>> renderReference(const scenes::Scene& scene,
                                               const trace::RayTracer& tracer,
                                               const Environment& environment,
                                               const trace::View& view, int width, int height,
                                               int samplesPerPixel, int specularDepth,
                                               Progress& progress) {
  if (samplesPerPixel <= 0) return Status::error("render: samples per pixel must be positive");
  const PathTracer pathTracer(scene, tracer, environment, ReferenceOptions().maxDepth);
  const uint32_t spp = uint32_t(samplesPerPixel);
  return trace::renderPixels(view, width, height, "reference render", progress,
                             [&](const trace::PinholeCamera& camera, int px, int py) {
    const uint64_t pixel = uint64_t(py) * uint64_t(width) + uint64_t(px);
    glm::dvec3 sum(0.0);  // doubles: up to 2^20 samples of very different sizes
    for (uint32_t s = 0; s < spp; ++s) {
      // Seeded from (pixel, sample) alone, so no thread's schedule changes a path. The pixel
      // position is stratified; the first bounce direction is uniform, independent of it.
      sampling::Rng rng(sampling::Stream::ReferenceView, pixel, s);
      const glm::vec2 jitter = sampling::stratified2(rng, s, spp);
      const trace::Ray ray = camera.ray(float(px) + jitter.x, float(py) + jitter.y);
      const glm::vec2 u = rng.next2();
      sum += glm::dvec3(specularDepth > 0
                            ? pathTracer.cameraRadianceWithSpecular(ray, specularDepth, rng)
                            : pathTracer.cameraRadiance(ray, u, rng));
    }
    return glm::vec3(sum / double(spp));
  });
}

}  // namespace afterglow::baker
