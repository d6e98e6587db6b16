#include "shading/emitters.h"

#include <algorithm>
#include <cmath>

#include "afterglow/core/math.h"

namespace afterglow::baker {

void addTriangles(const scenes::Instance& inst, const scenes::Primitive& prim,
                  const std::vector<glm::vec2>& uvs, Emitter& e) {
  const bool mirrored = glm::determinant(glm::mat3(inst.transform)) < 0.0f;
  scenes::forEachWorldTriangle(inst, prim, [&](size_t k, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const uint32_t i0 = prim.indices[3 * k], i1 = prim.indices[3 * k + 1],
                   i2 = prim.indices[3 * k + 2];
    const glm::vec3 cr = glm::cross(b - a, c - a);
    const float area = 0.5f * glm::length(cr);
    if (!(area > 0.0f) || !std::isfinite(area)) return;
    EmitterTriangle tri;
    tri.p0 = a;
    tri.e1 = b - a;
    tri.e2 = c - a;
    tri.normal = (mirrored ? -cr : cr) / (2.0f * area);
    tri.area = area;
    const bool hasUv = uvs.size() == prim.positions.size();
    tri.uv0 = hasUv ? uvs[i0] : glm::vec2(0.0f);
    tri.uv1 = hasUv ? uvs[i1] : glm::vec2(0.0f);
    tri.uv2 = hasUv ? uvs[i2] : glm::vec2(0.0f);
    tri.triangle = uint32_t(k);
    e.triangles.push_back(tri);
    e.totalArea += area;
    e.cdf.push_back(e.totalArea);
  });
}

std::vector<Emitter> collectEmitters(const scenes::Scene& scene) {
  std::vector<Emitter> emitters;
  std::vector<int> emitterOfMaterial(scene.materials.size(), -1);
  for (const scenes::Instance& inst : scene.instances) {
    if (inst.mesh < 0 || size_t(inst.mesh) >= scene.meshes.size()) continue;
    for (const scenes::Primitive& prim : scene.meshes[size_t(inst.mesh)].primitives) {
      if (prim.material < 0 || size_t(prim.material) >= scene.materials.size()) continue;
      const scenes::Material& m = scene.materials[size_t(prim.material)];
      if (!m.emissive()) continue;
      int& slot = emitterOfMaterial[size_t(prim.material)];
      if (slot < 0) {
        slot = int(emitters.size());
        emitters.emplace_back();
        emitters.back().material = uint32_t(prim.material);
        emitters.back().doubleSided = m.emitsFromBack();
        emitters.back().textured = m.emissiveTexture.valid() &&
                                   size_t(m.emissiveTexture.texture) < scene.textures.size() &&
                                   scene.textures[size_t(m.emissiveTexture.texture)].loaded();
      }
      addTriangles(inst, prim, m.emissiveTexture.texCoord == 1 ? prim.uv1 : prim.uv0,
                   emitters[size_t(slot)]);
    }
  }
  emitters.erase(std::remove_if(emitters.begin(), emitters.end(),
                                [](const Emitter& e) { return e.triangles.empty(); }),
                 emitters.end());
  std::sort(emitters.begin(), emitters.end(),
            [](const Emitter& a, const Emitter& b) { return a.material < b.material; });
  return emitters;
}

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

float triangleTransfer(const EmitterTriangle& tri, bool doubleSided, glm::vec3 p, glm::vec3 n) {
  const glm::vec3 v0 = tri.p0 - p;
  const float side = glm::dot(tri.normal, -v0);  // > 0: p is in front of the emitter
  if (side == 0.0f || (!doubleSided && side < 0.0f)) return 0.0f;
  // Clip the triangle to the half-space above p's tangent plane (Sutherland-Hodgman).
  const glm::vec3 in[3] = {v0, v0 + tri.e1, v0 + tri.e2};
  glm::vec3 poly[4];
  int count = 0;
  for (int i = 0; i < 3; ++i) {
    const glm::vec3& a = in[i];
    const glm::vec3& b = in[(i + 1) % 3];
    const float da = glm::dot(n, a), db = glm::dot(n, b);
    if (da >= 0.0f) poly[count++] = a;
    if ((da >= 0.0f) != (db >= 0.0f)) poly[count++] = a + (da / (da - db)) * (b - a);
  }
  if (count < 3) return 0.0f;
  // Lambert: the edge (a, b) subtends θ = ∠(a, b) and contributes θ · n·(a×b)/|a×b|.
  double sum = 0.0;
  for (int i = 0; i < count; ++i) {
    const glm::dvec3 a(poly[i]), b(poly[(i + 1) % count]);
    const glm::dvec3 c = glm::cross(a, b);
    const double len = glm::length(c);
    if (!(len > 0.0)) continue;
    const double theta = std::atan2(len, glm::dot(a, b));
    sum += theta * glm::dot(glm::dvec3(n), c) / len;
  }
  return float(std::abs(sum) / (2.0 * double(kPi)));
}

}  // namespace afterglow::baker
