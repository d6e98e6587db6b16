// The sky through glass, sampled through the glass as well as by the rays (glass_sky.h).
#include "precompute/glass_sky.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "afterglow/core/math.h"
#include "afterglow/scenes/material_eval.h"
#include "afterglow/trace/raytracer.h"
#include "shading/light_model.h"
#include "shading/sampling.h"

namespace afterglow::baker {

namespace {

// One point on the glass: the direction to it, and its share of the estimate if the sight
// line is clear (the balance heuristic's f / (n_c p_c + n_g p_g) before the transmittance and
// the SH basis, f's (1/π) cosθ included).
struct GlassSample {
  glm::vec3 direction;
  float weight;
  int triangle;  // of glass, where it lies
};

}  // namespace

GlassSky::GlassSky(const scenes::Scene& scene) {
  for (const scenes::Instance& inst : scene.instances) {
    firstPrimitive_.push_back(uint32_t(firstTriangle_.size()));
    const scenes::Mesh* mesh = scene.meshOf(inst);
    if (!mesh) continue;
    for (const scenes::Primitive& prim : mesh->primitives) {
      firstTriangle_.push_back(-1);
      if (!scenes::transmissive(scene, prim.material)) continue;
      const size_t first = glass_.triangles.size();
      addTriangles(inst, prim, {}, glass_);
      firstTriangle_.back() = int(triangleOf_.size());
      triangleOf_.resize(triangleOf_.size() + prim.triangleCount(), -1);
      for (size_t k = first; k < glass_.triangles.size(); ++k) {
        const EmitterTriangle& t = glass_.triangles[k];
        triangleOf_[size_t(firstTriangle_.back()) + t.triangle] = int(k);
        centres_.push_back(t.p0 + (t.e1 + t.e2) / 3.0f);
      }
    }
  }
}

int GlassSky::triangleOf(const trace::Hit& hit) const {
  if (!hit.valid() || hit.instance >= firstPrimitive_.size()) return -1;
  const size_t primitive = size_t(firstPrimitive_[hit.instance]) + hit.primitive;
  if (primitive >= firstTriangle_.size() || firstTriangle_[primitive] < 0) return -1;
  const size_t at = size_t(firstTriangle_[primitive]) + hit.triangle;
  return at < triangleOf_.size() ? triangleOf_[at] : -1;
}

float GlassSky::chances(glm::vec3 p, glm::vec3 n, std::vector<float>& out) const {
  const std::vector<EmitterTriangle>& tris = glass_.triangles;
  out.resize(tris.size());
  float total = 0.0f;
  for (size_t k = 0; k < tris.size(); ++k) {
    const glm::vec3 w = centres_[k] - p;
    const float d2 = glm::dot(w, w), area = tris[k].area;
    const float cosP = glm::dot(n, w), cosQ = std::abs(glm::dot(tris[k].normal, w));
    // area × cosθ at both ends / d², the cosines of w unnormalised (hence d⁴), softened so a
    // triangle the texel nearly touches still weighs no more than one filling its view.
    out[k] = cosP > 0.0f ? area * cosP * cosQ / (d2 * (d2 + area)) : 0.0f;
    total += out[k];
  }
  if (!(total > 0.0f)) {
    std::fill(out.begin(), out.end(), 0.0f);
    return 0.0f;
  }
  for (float& c : out) c /= total;
  return total;
}

uint32_t GlassSky::samplesFor(float view, float open, uint32_t most) {
  if (!(view > 0.0f) || most == 0) return 0;
  const float glass = view / kPi;  // the glass's share of the hemisphere's cosine-weighted view
  const float wanted = std::ceil(float(most) * glass / (glass + std::max(0.0f, open)));
  return std::clamp(uint32_t(wanted), std::min(4u, most), most);
}

float GlassSky::density(const std::vector<float>& chances, int k, float d, float cosQ) const {
  if (k < 0 || !(cosQ > 0.0f)) return 0.0f;
  return chances[size_t(k)] / glass_.triangles[size_t(k)].area * d * d / cosQ;
}

float GlassSky::rayWeight(const std::vector<float>& chances, glm::vec3 n, glm::vec3 direction,
                          int k, float d, float cosQ, uint32_t rays, uint32_t samples) const {
  const float byRays = float(rays) * std::max(0.0f, glm::dot(n, direction)) / kPi;
  const float byGlass = float(samples) * density(chances, k, d, cosQ);
  return byRays > 0.0f ? byRays / (byRays + byGlass) : 0.0f;
}

void GlassSky::addTo(const trace::RayTracer& tracer, glm::vec3 p, glm::vec3 n, glm::vec3 ng,
                     uint64_t item, uint32_t most, uint32_t rays, float open,
                     double (&sky)[runtime::kShCount]) const {
  if (empty()) return;
  thread_local std::vector<float> chance, cumulative;
  const uint32_t samples = samplesFor(chances(p, n, chance), open, most);
  if (samples == 0) return;
  cumulative.resize(chance.size());
  float total = 0.0f;
  for (size_t k = 0; k < chance.size(); ++k) cumulative[k] = total += chance[k];
  if (!(total > 0.0f)) return;
  thread_local std::vector<GlassSample> chosen;
  thread_local std::vector<trace::Ray> sights, beyond;
  chosen.clear();
  sights.clear();
  beyond.clear();
  const sampling::Stratified strata(samples);
  const sampling::Rng::ItemSeed seed{sampling::Rng::itemSeed(sampling::Stream::GlassSky, item)};
  for (uint32_t s = 0; s < samples; ++s) {
    sampling::Rng rng(seed, s);
    glm::vec2 u = strata.point(rng, s);
    // The triangle along u.x, and what is left of u.x inside its slice places the point on it.
    const float pick = std::min(u.x, 0.99999994f) * total;
    const size_t g = std::min(size_t(std::upper_bound(cumulative.begin(), cumulative.end(), pick) -
                                     cumulative.begin()),
                              chance.size() - 1);
    const float lo = g > 0 ? cumulative[g - 1] : 0.0f;
    if (!(chance[g] > 0.0f)) continue;
    u.x = std::clamp((pick - lo) / chance[g], 0.0f, 0.99999994f);
    const EmitterSample q = pointOnTriangle(glass_.triangles[g], u);
    const glm::vec3 w = q.point - p;
    const float d2 = glm::dot(w, w);
    if (!(d2 > 0.0f)) continue;
    const float d = std::sqrt(d2);
    const glm::vec3 dir = w / d;
    const float cosP = glm::dot(n, dir), cosQ = std::abs(glm::dot(q.normal, dir));
    if (cosP <= 0.0f || glm::dot(ng, dir) <= 0.0f || !(cosQ > 0.0f)) continue;
    // The balance heuristic's weights count `most` samples, as the rays' do (rayWeight).
    const float byGlass = float(most) * density(chance, int(g), d, cosQ);
    chosen.push_back({dir, float(most) * (cosP / kPi) / (float(rays) * cosP / kPi + byGlass),
                      int(g)});
    trace::Ray& sight = sights.emplace_back();
    sight.origin = p;
    sight.direction = dir;
    sight.tfar = d * (1.0f + kShadowShorten);
    trace::Ray& ray = beyond.emplace_back(sight);
    ray.tfar = std::numeric_limits<float>::infinity();
  }
  if (chosen.empty()) return;
  thread_local std::vector<float> through;
  thread_local std::vector<trace::Hit> seen;
  through.resize(beyond.size());
  seen.resize(sights.size());
  tracer.intersect(sights.data(), seen.data(), sights.size());
  tracer.greyTransmittance(beyond.data(), through.data(), beyond.size());
  for (size_t k = 0; k < chosen.size(); ++k) {
    // The point counts where its triangle is what the texel sees first that way (of two
    // coplanar faces of glass, the one the ray tracer reports, as for the rays' weights).
    if (triangleOf(seen[k]) != chosen[k].triangle || !(through[k] > 0.0f)) continue;
    float y[runtime::kShCount];
    sampling::shBasis(chosen[k].direction, y);
    const double value = double(chosen[k].weight) * double(through[k]) / double(samples);
    for (int i = 0; i < runtime::kShCount; ++i) sky[i] += value * double(y[i]);
  }
}

}  // namespace afterglow::baker
