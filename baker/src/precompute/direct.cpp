// Stage 4 of the precompute: unit direct light per source (punctual light or emissive material)
// with soft shadows, as E/π per texel and per cluster.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "afterglow/trace/raytracer.h"
#include "afterglow/baker/direct.h"
#include "afterglow/core/stages.h"
#include "afterglow/core/parallel.h"
#include "shading/emitters.h"
#include "shading/light_model.h"
#include "shading/sampling.h"

namespace afterglow::baker {

namespace {


int primitiveMaterial(const scenes::Scene& scene, const trace::Hit& hit) {
  const scenes::Instance& inst = scene.instances[hit.instance];
  return scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
}

struct Receiver {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec3 geometricNormal;
};

// The share of light that reaches the receiver along dir: 0 below its surface or behind
// anything opaque, what the glass in between lets through (its grey transmittance), else 1.
float through(const trace::RayTracer& tracer, const Receiver& r, glm::vec3 dir, float tfar) {
  if (glm::dot(dir, r.geometricNormal) <= 0.0f) return 0.0f;  // behind the surface
  trace::Ray ray;
  ray.origin = r.position;
  ray.direction = dir;
  ray.tfar = tfar;
  ray.mask = trace::kMaskShadowCasters;
  float out;
  tracer.greyTransmittance(&ray, &out, 1);
  return out;
}

// A receiver's shadow rays toward one source, queued and traced together: they share an origin
// and nearly a direction, so Embree's packet traversal runs them about twice as fast as one by
// one (RayTracer::greyTransmittance over an array). Each queued sample carries a weight;
// samples whose direction points below the surface are queued untraced and get nothing
// through, as through() would have it. One per block of receivers: its arrays are too big to
// set up per receiver.
class ShadowRays {
 public:
  static constexpr int kBatch = 32;  // a multiple of the tracer's packet width

  // Starts the rays of a receiver (the previous one's must have been flushed).
  void begin(const Receiver& r) { receiver_ = &r; }

  // A ray along dir (not necessarily of unit length) to tfar, in units of dir.
  void add(glm::vec3 dir, float tfar, double weight = 1.0) {
    weight_[size_] = weight;
    below_[size_] = glm::dot(dir, receiver_->geometricNormal) <= 0.0f;
    if (!below_[size_]) {
      trace::Ray& ray = rays_[traced_];
      ray.origin = receiver_->position;
      ray.direction = dir;
      ray.tfar = tfar;
      ray.mask = trace::kMaskShadowCasters;
      ++traced_;
    }
    ++size_;
  }
  bool full() const { return size_ == kBatch; }

  // Traces the queued rays and calls seen(weight, through) per sample in the order queued,
  // `through` the share of the light that gets through (0 or 1 without glass).
  template <class Seen>
  void flush(const trace::RayTracer& tracer, Seen&& seen) {
    tracer.greyTransmittance(rays_, through_, size_t(traced_));
    for (int i = 0, k = 0; i < size_; ++i) seen(weight_[i], below_[i] ? 0.0f : through_[k++]);
    size_ = traced_ = 0;
  }

 private:
  const Receiver* receiver_ = nullptr;
  trace::Ray rays_[kBatch];
  float through_[kBatch];
  double weight_[kBatch];
  bool below_[kBatch];
  int size_ = 0, traced_ = 0;
};

// What a pass's shadow rays saw: none got the light through, all got it whole, or else
// (Partial: also where glass let part of it through, so the edges of a window's light get
// refined as an opaque shadow's are).
enum class Shade : uint8_t { Dark, Lit, Partial };
struct ShadeCount {
  int rays = 0, whole = 0, none = 0;
  void add(float through) {
    ++rays;
    whole += through == 1.0f ? 1 : 0;
    none += through == 0.0f ? 1 : 0;
  }
  Shade shade() const {
    return none == rays ? Shade::Dark : whole == rays ? Shade::Lit : Shade::Partial;
  }
};

// One shadow estimate at a receiver: E/π for a source of unit strength, and what the rays saw.
struct Shadowed {
  float transfer = 0.0f;
  Shade shade = Shade::Dark;  // Dark: no light or every ray blocked; Lit: none blocked
  bool refinable = false;     // the source has an extent, so more rays would change the answer
};

// E/π at the receiver for a light of colour 1 and intensity 1: the unshadowed transfer times
// the fraction of `rays` stratified shadow rays over the light's extent that get through.
// Samples are numbered from `first`, so a refinement draws fresh ones.
Shadowed punctualPass(const trace::RayTracer& tracer, const scenes::Light& light, uint32_t lightIndex,
                      const Receiver& r, uint64_t item, int rays, uint32_t first,
                      ShadowRays& batch) {
  Shadowed out;
  const LightView view = viewLight(light, r.position, r.normal);
  if (!(view.transfer > 0.0f)) return out;
  if (!view.hasExtent) rays = 1;
  const uint64_t seedBase = uint64_t(lightIndex) << 32;
  float seen = 0.0f;  // sums of 0 and 1 are exact: without glass, the count of rays through
  ShadeCount shade;
  batch.begin(r);
  auto count = [&](double, float through) {
    seen += through;
    shade.add(through);
  };
  const sampling::Stratified strata{uint32_t(rays)};
  const sampling::Rng::ItemSeed seed{
      sampling::Rng::itemSeed(sampling::Stream::LightVisibility, item)};
  for (int s = 0; s < rays; ++s) {
    sampling::Rng rng(seed, seedBase | (first + uint32_t(s)));
    glm::vec3 dir;
    float length;
    lightShadowRay(light, view, r.position,
                   strata.point(rng, uint32_t(s)), &dir, &length);
    batch.add(dir, length);
    if (batch.full()) batch.flush(tracer, count);
  }
  batch.flush(tracer, count);
  out.transfer = view.transfer * seen / float(rays);
  out.shade = shade.shade();
  out.refinable = view.hasExtent;
  return out;
}

// Emitters up to this many triangles get the closed-form transfer; larger ones (an emissive
// mesh of thousands of triangles) are sampled, since the closed form costs a pass over every
// triangle per texel.
constexpr size_t kClosedFormTriangles = 64;

// E/π at the receiver from an untextured emitter of unit radiance: the unoccluded transfer in
// closed form, times the visible fraction estimated with shadow rays to stratified points on
// the emitter, each weighted by its unoccluded contribution (the ratio estimator of Heitz et
// al. 2018). Fully lit and fully shadowed texels come out exact, without noise; only the
// penumbra carries sampling error.
Shadowed closedFormEmissivePass(const trace::RayTracer& tracer, const Emitter& e, const Receiver& r,
                                uint64_t item, int samples, uint32_t first, ShadowRays& batch) {
  Shadowed out;
  double unoccluded = 0.0;
  for (const EmitterTriangle& tri : e.triangles)
    unoccluded += double(triangleTransfer(tri, e.doubleSided, r.position, r.normal));
  if (!(unoccluded > 0.0)) return out;
  const uint64_t seedBase = uint64_t(e.material) << 32;
  double weightSum = 0.0, visibleSum = 0.0;
  ShadeCount shade;
  batch.begin(r);
  auto count = [&](double weight, float through) {
    weightSum += weight;
    if (through > 0.0f) visibleSum += weight * double(through);
    shade.add(through);
  };
  const sampling::Stratified strata{uint32_t(samples)};
  const sampling::Rng::ItemSeed seed{sampling::Rng::itemSeed(sampling::Stream::Emissive, item)};
  for (int s = 0; s < samples; ++s) {
    sampling::Rng rng(seed, seedBase | (first + uint32_t(s)));
    const EmitterSample q = sampleEmitter(e, strata.point(rng, uint32_t(s)));
    // The ray runs along w itself (Embree needs no unit direction), and the cosines are
    // scaled by |w|: no square root or division per ray, only one for the weight.
    const glm::vec3 w = q.point - r.position;
    const float dist2 = glm::dot(w, w);
    if (!(dist2 > 0.0f)) continue;
    const float cosTheta = glm::dot(r.normal, w);  // × |w|
    float cosEmit = -glm::dot(q.normal, w);        // × |w|
    if (e.doubleSided) cosEmit = std::abs(cosEmit);
    if (cosTheta <= 0.0f || cosEmit <= 0.0f) continue;
    batch.add(w, 1.0f - kShadowShorten,
              double(cosTheta) * double(cosEmit) / (double(dist2) * double(dist2)));
    if (batch.full()) batch.flush(tracer, count);
  }
  batch.flush(tracer, count);
  out.refinable = true;
  // No sample landed on the visible part (a sliver above the horizon): too small to matter.
  if (!(weightSum > 0.0)) return out;
  out.transfer = float(unoccluded * visibleSum / weightSum);
  out.shade = shade.shade();
  return out;
}

// E/π at the receiver from a textured or large emitter of unit radiance, (1/π) ∫ Le cosθ dω over
// the visible emitter. Two strategies combined with the balance heuristic (multiple importance
// sampling): points on the emitters chosen by area (stratified), good for small or distant
// emitters, and cosine-distributed rays that hit them, good for large or near ones (a texel next
// to an emissive wall, a furnace). Each alone is noisy where the other shines.
float sampledEmissiveTransfer(const scenes::Scene& scene, const trace::RayTracer& tracer,
                              const Emitter& e, const Receiver& r, uint64_t item, int samples) {
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
    const EmitterSample q =
        sampleEmitter(e, sampling::stratified2(rng, uint32_t(s), uint32_t(areaSamples)));
    const glm::vec3 w = q.point - r.position;
    const float dist2 = glm::dot(w, w);
    if (!(dist2 > 0.0f)) continue;
    const float dist = std::sqrt(dist2);
    const glm::vec3 dir = w / dist;
    const float cosTheta = glm::dot(r.normal, dir);
    if (cosTheta <= 0.0f) continue;
    float cosEmit = -glm::dot(q.normal, dir);
    if (e.doubleSided) cosEmit = std::abs(cosEmit);
    if (cosEmit <= 0.0f) continue;
    const float mod = emissionModulation(scene, m, q.uv);
    if (mod <= 0.0f) continue;
    const float share = through(tracer, r, dir, dist * (1.0f - kShadowShorten));
    if (share == 0.0f) continue;
    const double g = double(share) * double(mod) * double(cosTheta) / double(kPi);
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
      trace::Ray ray;
      ray.origin = r.position;
      ray.direction = dir;
      ray.mask = trace::kMaskShadowCasters;
      // Through glass by the ray's own chance, as the gather's rays go.
      const trace::Hit hit = tracer.intersect(ray, trace::Glass::Light);
      if (!hit.valid() || hit.absorbed || primitiveMaterial(scene, hit) != int(e.material))
        continue;
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

// Source k of the transport (lights first, then emitters) at a receiver, with `samples` rays
// numbered from `first`.
struct SourceSet {
  const scenes::Scene& scene;
  const trace::RayTracer& tracer;
  const std::vector<Emitter>& emitters;
  const DirectOptions& options;

  size_t size() const { return scene.lights.size() + emitters.size(); }

  // Whether more shadow rays can change source k's answer: it has an extent (soft shadows).
  bool refinable(size_t k) const {
    if (k < scene.lights.size()) {
      const scenes::Light& l = scene.lights[k];
      return l.type == scenes::LightType::Directional ? l.angularDiameter > 0.0f : l.radius > 0.0f;
    }
    const Emitter& e = emitters[k - scene.lights.size()];
    return !e.textured && e.triangles.size() <= kClosedFormTriangles;
  }

  Shadowed pass(size_t k, const Receiver& r, uint64_t item, bool refine,
                ShadowRays& batch) const {
    const size_t lights = scene.lights.size();
    if (k < lights) {
      const int rays = refine ? options.penumbraSamples : options.lightSamples;
      return punctualPass(tracer, scene.lights[k], uint32_t(k), r, item, std::max(1, rays),
                          refine ? uint32_t(options.lightSamples) : 0u, batch);
    }
    const Emitter& e = emitters[k - lights];
    if (!e.textured && e.triangles.size() <= kClosedFormTriangles) {
      const int samples = refine ? options.penumbraSamples : options.emissiveSamples;
      return closedFormEmissivePass(tracer, e, r, item, std::max(1, samples),
                                    refine ? uint32_t(options.emissiveSamples) : 0u, batch);
    }
    Shadowed out;  // sampled with MIS, no shadow classification to refine
    out.transfer = sampledEmissiveTransfer(scene, tracer, e, r, item, options.emissiveSamples);
    out.shade = Shade::Lit;
    return out;
  }

  // A pass, and a refined one when its rays disagreed (for receivers without neighbours).
  float transfer(size_t k, const Receiver& r, uint64_t item, ShadowRays& batch) const {
    const Shadowed first = pass(k, r, item, false, batch);
    if (first.refinable && first.shade == Shade::Partial && options.penumbraSamples > 0)
      return pass(k, r, item, true, batch).transfer;
    return first.transfer;
  }
};

// Every texel once with a few shadow rays per source, then again with many where the first
// rays disagreed or a neighbour's did not agree with its own (the penumbra, and a texel's
// width around it: a texel that saw all of a lamp with 16 rays may still be 3% shadowed):
// transfer[k][t], E/π per unit source. `step` names the work in the progress.
Status texelPasses(const TexelSet& texels, const SourceSet& sources, const DirectOptions& options,
                   std::vector<std::vector<float>>& transfer, const std::string& step,
                   Progress& progress) {
  const uint32_t texelCount = texels.size();
  const size_t sourceCount = sources.size();
  std::vector<uint8_t> shade(size_t(texelCount) * sourceCount, uint8_t(Shade::Dark));
  std::vector<uint8_t> refinable(sourceCount, 0);
  for (size_t k = 0; k < sourceCount; ++k) refinable[k] = sources.refinable(k) ? 1 : 0;
  // Small blocks: penumbrae and back-side clusters take most of the rays and sit together, so
  // a few big blocks would leave a thread idle at the end.
  constexpr size_t kTexelsPerBlock = 256;
  progress.begin(step, texelCount);
  parallelForBlocks(texelCount, [&](size_t begin, size_t end, int) {
    ShadowRays batch;
    for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
      if (!texels.valid[t]) continue;
      const Receiver r{texels.position[t], texels.normal[t], texels.geometricNormal[t]};
      for (size_t k = 0; k < sourceCount; ++k) {
        const Shadowed s = sources.pass(k, r, t, false, batch);
        transfer[k][t] = s.transfer;
        shade[t * sourceCount + k] = uint8_t(s.shade);
      }
    }
    progress.advance(end - begin);
  }, kTexelsPerBlock);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  if (options.penumbraSamples > 0) {
    progress.begin(step + ": penumbrae", texelCount);
    parallelForBlocks(texelCount, [&](size_t begin, size_t end, int) {
    ShadowRays batch;
      for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
        if (!texels.valid[t]) continue;
        const runtime::AtlasLayout& layout = texels.atlases[texels.atlas[t]];
        const Receiver r{texels.position[t], texels.normal[t], texels.geometricNormal[t]};
        for (size_t k = 0; k < sourceCount; ++k) {
          if (!refinable[k]) continue;
          const uint8_t own = shade[t * sourceCount + k];
          bool refine = own == uint8_t(Shade::Partial);
          for (int n = 0; n < 8 && !refine; ++n) {
            const int x = texels.pixel[t].x + runtime::kNeighbourOffsets[n][0];
            const int y = texels.pixel[t].y + runtime::kNeighbourOffsets[n][1];
            if (x < 0 || y < 0 || x >= layout.width || y >= layout.height) continue;
            const uint32_t o = layout.texelOfPixel[size_t(y) * size_t(layout.width) + size_t(x)];
            if (o == runtime::kNoTexel || !texels.valid[o]) continue;
            refine = shade[size_t(o) * sourceCount + k] != own;
          }
          if (refine)
            transfer[k][t] = sources.pass(k, r, t, true, batch).transfer;
        }
      }
      progress.advance(end - begin);
    }, kTexelsPerBlock);
    progress.end();
    if (progress.cancelled()) return Status::error("cancelled");
  }

  return Status::ok();
}

}  // namespace

Status computeDirect(const scenes::Scene& scene, const trace::RayTracer& tracer, const TexelSet& texels,
                     const Clusters& clusters, const DirectOptions& options,
                     runtime::TransportData& transport, Progress& progress) {
  if (options.lightSamples <= 0 || options.emissiveSamples <= 0 || options.penumbraSamples < 0)
    return Status::error("computeDirect: lightSamples and emissiveSamples must be positive");
  const uint32_t texelCount = texels.size();
  const uint32_t clusterCount = clusters.size();
  if (clusterCount > 0 && clusters.firstTexel.size() != size_t(clusterCount) + 1)
    return Status::error("computeDirect: Clusters::firstTexel needs one entry per cluster plus one");

  const std::vector<Emitter> emitters = collectEmitters(scene);
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
    s.mode = lightMode(light.mode);
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

  const SourceSet sources{scene, tracer, emitters, options};
  const size_t sourceCount = sources.size();
  {
    std::vector<std::vector<float>> transfer(sourceCount);
    for (size_t k = 0; k < sourceCount; ++k) transfer[k].swap(transport.sources[k].texelTransfer);
    const Status st =
        texelPasses(texels, sources, options, transfer, stageName(Stage::Direct), progress);
    for (size_t k = 0; k < sourceCount; ++k) transfer[k].swap(transport.sources[k].texelTransfer);
    if (!st) return Status::error("computeDirect: " + st.message());
  }

  constexpr size_t kTexelsPerBlock = 256, kClustersPerBlock = 32;
  // What a front cluster reflects of a punctual light: its texels' light averaged over their
  // footprints (one shadow ray from each of up to 16 points a texel), not at their samples. A
  // sunlit sliver thinner than a texel between two shaded samples (the sun through a gap
  // between a drape and a column) lights what sees it, though no texel's own value shows it: on
  // Sponza-sun at 4 texels/m walls that see such slivers were 97% too dark (issue 16). The
  // texels' own values, what the lightmap shows, stay at their samples.
  const size_t lightCount = scene.lights.size();
  std::vector<std::vector<float>> footprint(lightCount);
  for (size_t k = 0; k < lightCount; ++k) footprint[k] = transport.sources[k].texelTransfer;
  constexpr uint32_t kFootprintSamples = 1u << 20;  // sample numbers apart from the passes'
  if (lightCount > 0) progress.begin(stageStep(Stage::Direct, "footprints"), texelCount);
  if (lightCount > 0) parallelForBlocks(texelCount, [&](size_t begin, size_t end, int) {
    // A texel's rays, all lights' together, traced as one stream (one by one they ran at half
    // Embree's rate). Sample i of light k is the one punctualPass would draw as its
    // (kFootprintSamples + i)-th.
    glm::vec3 points[16];
    glm::vec2 jitter[16];
    std::vector<trace::Ray> rays;
    std::vector<float> transfer;  // per ray: its point's unshadowed transfer
    std::vector<uint32_t> lightOf;
    std::unique_ptr<float[]> through(new float[16 * lightCount]);
    const sampling::Stratified one{1};
    for (size_t t = begin; t < end && !progress.cancelled(); ++t) {
      if (!texels.valid[t]) continue;
      const sampling::Rng::ItemSeed seed{
          sampling::Rng::itemSeed(sampling::Stream::LightVisibility, t)};
      // The points multi-jittered: at the cells' centres a shadow edge along the grid (a 20 cm
      // sunlit strip under a slit, two texel columns lit 40% each) came out lit 50%.
      sampling::Rng place(seed, ~uint64_t(0));  // apart from every light's samples
      sampling::multiJittered16(place, jitter);
      const int n = footprintPoints(scene, texels, uint32_t(t), points, jitter);
      if (n == 0) continue;
      rays.clear();
      transfer.clear();
      lightOf.clear();
      for (size_t k = 0; k < lightCount; ++k) {
        const scenes::Light& light = scene.lights[k];
        for (int i = 0; i < n; ++i) {
          const LightView view = viewLight(light, points[i], texels.normal[t]);
          if (!(view.transfer > 0.0f)) continue;
          sampling::Rng rng(seed, (uint64_t(k) << 32) | (kFootprintSamples + uint32_t(i)));
          trace::Ray ray;
          lightShadowRay(light, view, points[i], one.point(rng, 0), &ray.direction, &ray.tfar);
          if (glm::dot(ray.direction, texels.geometricNormal[t]) <= 0.0f) continue;  // below
          ray.origin = points[i];
          ray.mask = trace::kMaskShadowCasters;
          rays.push_back(ray);
          transfer.push_back(view.transfer);
          lightOf.push_back(uint32_t(k));
        }
      }
      tracer.greyTransmittance(rays.data(), through.get(), rays.size());
      std::vector<double> sum(lightCount, 0.0);
      for (size_t j = 0; j < rays.size(); ++j)
        if (through[j] > 0.0f) sum[lightOf[j]] += double(transfer[j]) * double(through[j]);
      for (size_t k = 0; k < lightCount; ++k) footprint[k][t] = float(sum[k] / double(n));
    }
    progress.advance(end - begin);
  }, kTexelsPerBlock);
  if (lightCount > 0) progress.end();
  if (progress.cancelled()) return Status::error("computeDirect: cancelled");

  // Cluster transfer: area-weighted mean over the cluster's valid texels. A back-side cluster
  // of a double-sided surface has no texels of its own facing its way, so its members are
  // evaluated again from behind the surface (seeded apart from their front samples).
  std::vector<std::vector<float>> backTransfer(transport.sources.size());
  for (std::vector<float>& b : backTransfer) b.assign(clusterCount, 0.0f);
  progress.begin(stageStep(Stage::Direct, "clusters"), clusterCount);
  parallelForBlocks(clusterCount, [&](size_t begin, size_t end, int) {
    ShadowRays batch;
    std::vector<double> sums(transport.sources.size());
    for (size_t c = begin; c < end && !progress.cancelled(); ++c) {
      double areaSum = 0.0;
      std::fill(sums.begin(), sums.end(), 0.0);
      for (uint32_t k = clusters.firstTexel[c]; k < clusters.firstTexel[c + 1]; ++k) {
        const uint32_t t = clusters.memberTexels[k];
        if (!texels.valid[t]) continue;
        const double a = double(texels.area[t]);
        areaSum += a;
        if (!clusters.back[c]) {
          for (size_t i = 0; i < sums.size(); ++i)
            sums[i] += a * double(i < lightCount ? footprint[i][t]
                                                 : transport.sources[i].texelTransfer[t]);
          continue;
        }
        const Receiver r{texels.backPosition(t), -texels.normal[t], -texels.geometricNormal[t]};
        const uint64_t item = uint64_t(texelCount) + uint64_t(c) * 0x10000ull + (k & 0xffffu);
        for (size_t k = 0; k < sourceCount; ++k)
          sums[k] += a * double(sources.transfer(k, r, item, batch));
      }
      if (areaSum > 0.0)
        for (size_t i = 0; i < sums.size(); ++i) backTransfer[i][c] = float(sums[i] / areaSum);
    }
    progress.advance(end - begin);
  }, kClustersPerBlock);
  progress.end();
  if (progress.cancelled()) return Status::error("computeDirect: cancelled");
  for (size_t i = 0; i < transport.sources.size(); ++i)
    transport.sources[i].clusterTransfer = std::move(backTransfer[i]);
  return Status::ok();
}

Status computeLightmapDirect(const scenes::Scene& scene, const trace::RayTracer& tracer,
                             const TexelSet& lightmapTexels, const DirectOptions& options,
                             runtime::TransportData& transport, Progress& progress) {
  const std::vector<Emitter> emitters = collectEmitters(scene);
  const SourceSet sources{scene, tracer, emitters, options};
  if (sources.size() != transport.sources.size())
    return Status::error("computeLightmapDirect: the transport's sources are not the scene's");
  std::vector<std::vector<float>> transfer(sources.size());
  for (std::vector<float>& t : transfer) t.assign(lightmapTexels.size(), 0.0f);
  const Status st = texelPasses(lightmapTexels, sources, options, transfer,
                                stageStep(Stage::Direct, "lightmap texels"), progress);
  if (!st) return Status::error("computeLightmapDirect: " + st.message());
  runtime::LightmapLayers& layers = transport.lightmap;
  layers.direct.assign(sources.size(), {});
  layers.directScale.assign(sources.size(), 1.0f);
  for (size_t k = 0; k < sources.size(); ++k)
    layers.directScale[k] = runtime::encodeDirectLayer(transfer[k], layers.direct[k]);
  return Status::ok();
}

}  // namespace afterglow::baker
