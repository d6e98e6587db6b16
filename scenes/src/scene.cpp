#include "afterglow/scenes/scene.h"

#include <cmath>

#include "afterglow/core/math.h"

namespace afterglow::scenes {

glm::vec2 TextureRef::transform(glm::vec2 uv) const {
  if (!hasTransform) return uv;
  // KHR_texture_transform's T * R * S as the sample viewers and Cesium implement it: with v
  // pointing down the image, a positive rotation turns the texture counter-clockwise on screen.
  const glm::vec2 s = uv * scale;
  const float c = std::cos(rotation), n = std::sin(rotation);
  return glm::vec2(c * s.x + n * s.y, -n * s.x + c * s.y) + offset;
}

glm::vec4 Texture::sample(glm::vec2 uv) const {
  if (!loaded() || texels.size() < size_t(width) * size_t(height)) return glm::vec4(1.0f);
  // Repeat wrapping: reduce to [0, 1) first so huge or negative UVs cannot overflow an int.
  auto wrapCoord = [](float t) {
    if (!std::isfinite(t)) return 0.0f;
    return t - std::floor(t);
  };
  const float x = wrapCoord(uv.x) * float(width) - 0.5f;
  const float y = wrapCoord(uv.y) * float(height) - 0.5f;
  const float fx0 = std::floor(x), fy0 = std::floor(y);
  const float fx = x - fx0, fy = y - fy0;
  // i is within [-1, n - 1] here (x, y in [-0.5, n - 0.5]): no division on that path, which
  // the lightmap's footprint albedo runs 16 times a texel.
  auto wrapIndex = [](int i, int n) {
    if (i >= 0 && i < n) return i;
    if (i == -1 || i == n) return i == -1 ? n - 1 : 0;
    return ((i % n) + n) % n;
  };
  const int x0 = wrapIndex(int(fx0), width), x1 = wrapIndex(int(fx0) + 1, width);
  const int y0 = wrapIndex(int(fy0), height), y1 = wrapIndex(int(fy0) + 1, height);
  auto at = [&](int xi, int yi) { return texels[size_t(yi) * size_t(width) + size_t(xi)]; };
  const glm::vec4 top = glm::mix(at(x0, y0), at(x1, y0), fx);
  const glm::vec4 bottom = glm::mix(at(x0, y1), at(x1, y1), fx);
  return glm::mix(top, bottom, fy);
}

const glm::vec4* Texture::texelAt(glm::vec2 uv) const {
  if (!loaded() || texels.size() < size_t(width) * size_t(height)) return nullptr;
  auto index = [](float t, int n) {
    if (!std::isfinite(t)) return 0;
    const int i = int((t - std::floor(t)) * float(n));
    return std::min(std::max(i, 0), n - 1);
  };
  return &texels[size_t(index(uv.y, height)) * size_t(width) + size_t(index(uv.x, width))];
}

glm::vec4 Texture::fetch(glm::vec2 uv) const {
  const glm::vec4* texel = texelAt(uv);
  return texel ? *texel : glm::vec4(1.0f);
}

size_t Mesh::triangleCount() const {
  size_t count = 0;
  for (const Primitive& p : primitives) count += p.triangleCount();
  return count;
}

const Material& Scene::material(int index) const {
  // glTF's default material: white, fully metallic and rough, opaque, single-sided.
  static const Material kDefault = [] {
    Material m;
    m.name = "default";
    return m;
  }();
  if (index < 0 || size_t(index) >= materials.size()) return kDefault;
  return materials[size_t(index)];
}

Bounds Scene::bounds() const {
  Bounds b;
  for (const Instance& inst : instances) {
    if (inst.mesh < 0 || size_t(inst.mesh) >= meshes.size()) continue;
    for (const Primitive& p : meshes[size_t(inst.mesh)].primitives)
      for (const glm::vec3& v : p.positions) b.extend(inst.toWorld(v));
  }
  return b;
}

Bounds Scene::staticBounds() const {
  Bounds b;
  for (const Instance& inst : instances) {
    const Mesh* mesh = meshOf(inst);
    if (!inst.isStatic || !mesh) continue;
    for (const Primitive& p : mesh->primitives)
      for (const glm::vec3& v : p.positions)
        if (const glm::vec3 w = inst.toWorld(v); finite(w)) b.extend(w);
  }
  return b;
}

size_t Scene::instancedTriangleCount() const {
  size_t count = 0;
  for (const Instance& inst : instances)
    if (inst.mesh >= 0 && size_t(inst.mesh) < meshes.size())
      count += meshes[size_t(inst.mesh)].triangleCount();
  return count;
}

size_t Scene::meshTriangleCount() const {
  size_t count = 0;
  for (const Mesh& m : meshes) count += m.triangleCount();
  return count;
}

}  // namespace afterglow::scenes
