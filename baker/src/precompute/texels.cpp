// Texels: conservative rasterisation of TEXCOORD_1, one sample point per texel, and the
// "push out" of samples that sit inside or behind nearby geometry.
#include "afterglow/baker/texels.h"
#include "afterglow/core/stages.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "afterglow/trace/raytracer.h"
#include "afterglow/core/math.h"
#include "afterglow/core/parallel.h"

// The uv module's rasteriser, so texels cover exactly the footprint the packer reserved.
#include "afterglow/uv/texel_raster.h"

namespace afterglow::baker {
namespace {

using runtime::kNoTexel;


// One triangle touching one pixel.
struct Touch {
  uint32_t pixel = 0;     // y * width + x
  uint32_t primitive = 0;
  uint32_t triangle = 0;
  double dist2 = 0.0;     // squared UV distance (texels²) from the texel centre to the triangle
  glm::dvec2 bary{0.0};   // Embree u, v of the triangle point closest to the texel centre
  double area = 0.0;      // world area of triangle ∩ texel square
  double texelSize = 0.0; // world length of one texel edge on this triangle
};

// What one pixel ends up with: the best-placed triangle and the summed area.
struct PixelRecord {
  uint32_t instance = 0;
  Touch touch;
};

// Ericson's closest point on a triangle, as barycentric weights (w0, w1, w2).
glm::dvec3 closestBarycentric(const glm::dvec2& p, const glm::dvec2& a, const glm::dvec2& b,
                              const glm::dvec2& c) {
  const glm::dvec2 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {1.0, 0.0, 0.0};
  const glm::dvec2 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return {0.0, 1.0, 0.0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {1.0 - v, v, 0.0};
  }
  const glm::dvec2 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return {0.0, 0.0, 1.0};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {1.0 - w, 0.0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0.0, 1.0 - w, w};
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {1.0 - v - w, v, w};
}

// Area of the triangle clipped to the square [x0, x0+1] × [y0, y0+1] (Sutherland-Hodgman).
double clippedArea(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c, int x0, int y0) {
  glm::dvec2 bufA[9], bufB[9];
  int n = 3;
  bufA[0] = a;
  bufA[1] = b;
  bufA[2] = c;
  glm::dvec2* in = bufA;
  glm::dvec2* out = bufB;
  for (int edge = 0; edge < 4; ++edge) {
    const int axis = edge / 2;
    const bool keepAbove = edge % 2 == 0;
    const double bound = axis == 0 ? (keepAbove ? x0 : x0 + 1.0) : (keepAbove ? y0 : y0 + 1.0);
    auto inside = [&](const glm::dvec2& p) { return keepAbove ? p[axis] >= bound : p[axis] <= bound; };
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const glm::dvec2& p = in[i];
      const glm::dvec2& q = in[(i + 1) % n];
      const bool pin = inside(p), qin = inside(q);
      if (pin) out[m++] = p;
      if (pin != qin) {
        const double t = (bound - p[axis]) / (q[axis] - p[axis]);
        out[m++] = p + t * (q - p);
      }
    }
    n = m;
    std::swap(in, out);
    if (n < 3) return 0.0;
  }
  double twice = 0.0;
  for (int i = 0; i < n; ++i) {
    const glm::dvec2& p = in[i];
    const glm::dvec2& q = in[(i + 1) % n];
    twice += p.x * q.y - q.x * p.y;
  }
  return 0.5 * std::abs(twice);
}

bool usableInstance(const scenes::Scene& scene, const scenes::Instance& inst, UvSet uvs) {
  const scenes::LightmapLocation& lm = scenes::lightmapOf(inst, uvs);
  return inst.isStatic && lm.atlas >= 0 && lm.width > 0 && lm.height > 0 && inst.mesh >= 0 &&
         size_t(inst.mesh) < scene.meshes.size();
}

bool validTriangle(const scenes::Primitive& prim, size_t t, UvSet uvs) {
  const size_t n = prim.positions.size();
  if (scenes::lightmapUvs(prim, uvs).size() != n) return false;
  return prim.indices[3 * t] < n && prim.indices[3 * t + 1] < n && prim.indices[3 * t + 2] < n;
}

// Every (pixel, triangle) touch of one instance, reduced to the best triangle per pixel and
// sorted by pixel.
std::vector<Touch> rasterizeInstance(const scenes::Scene& scene, const scenes::Instance& inst,
                                     UvSet uvs) {
  std::vector<Touch> touches;
  const scenes::Mesh& mesh = scene.meshes[size_t(inst.mesh)];
  const scenes::LightmapLocation& lm = scenes::lightmapOf(inst, uvs);
  const int width = lm.width, height = lm.height;
  const glm::dvec2 size(width, height);
  const glm::dmat4 xf(inst.transform);
  for (size_t p = 0; p < mesh.primitives.size(); ++p) {
    const scenes::Primitive& prim = mesh.primitives[p];
    for (size_t t = 0; t < prim.triangleCount(); ++t) {
      if (!validTriangle(prim, t, uvs)) continue;
      const std::vector<glm::vec2>& uv = scenes::lightmapUvs(prim, uvs);
      const uint32_t i0 = prim.indices[3 * t], i1 = prim.indices[3 * t + 1],
                     i2 = prim.indices[3 * t + 2];
      const glm::dvec2 a = glm::dvec2(uv[i0]) * size, b = glm::dvec2(uv[i1]) * size,
                       c = glm::dvec2(uv[i2]) * size;
      const double uvArea = 0.5 * std::abs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
      const glm::dvec3 q0(xf * glm::dvec4(glm::dvec3(prim.positions[i0]), 1.0));
      const glm::dvec3 q1(xf * glm::dvec4(glm::dvec3(prim.positions[i1]), 1.0));
      const glm::dvec3 q2(xf * glm::dvec4(glm::dvec3(prim.positions[i2]), 1.0));
      const double worldArea = 0.5 * glm::length(glm::cross(q1 - q0, q2 - q0));
      // A triangle without UV area has no texels of its own to spread its world area over.
      if (!(uvArea > 1e-12) || !std::isfinite(uvArea) || !std::isfinite(worldArea)) continue;
      const double ratio = worldArea / uvArea;
      const double texelSize = std::sqrt(ratio);
      uv::rasterizeTriangle(a, b, c, uv::kPackGrow, width, height,
                                    [&](int x, int y) {
        Touch touch;
        touch.pixel = uint32_t(y) * uint32_t(width) + uint32_t(x);
        touch.primitive = uint32_t(p);
        touch.triangle = uint32_t(t);
        const glm::dvec2 centre(x + 0.5, y + 0.5);
        const glm::dvec3 w = closestBarycentric(centre, a, b, c);
        const glm::dvec2 closest = w.x * a + w.y * b + w.z * c;
        touch.dist2 = glm::dot(closest - centre, closest - centre);
        touch.bary = glm::dvec2(w.y, w.z);
        touch.area = clippedArea(a, b, c, x, y) * ratio;
        touch.texelSize = texelSize;
        touches.push_back(touch);
      });
    }
  }
  // Rasterisation visits triangles in order, so a stable sort keeps (primitive, triangle) order
  // within a pixel and the first closest triangle wins ties.
  std::stable_sort(touches.begin(), touches.end(),
                   [](const Touch& l, const Touch& r) { return l.pixel < r.pixel; });
  std::vector<Touch> reduced;
  for (const Touch& t : touches) {
    if (reduced.empty() || reduced.back().pixel != t.pixel) {
      reduced.push_back(t);
      continue;
    }
    Touch& best = reduced.back();
    const double area = best.area + t.area;
    if (t.dist2 < best.dist2) best = t;
    best.area = area;
  }
  return reduced;
}

// Orthonormal tangents of a unit normal (Duff et al. 2017).
void tangentFrame(const glm::vec3& n, glm::vec3& t, glm::vec3& b) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float bb = n.x * n.y * a;
  t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
  b = glm::vec3(bb, sign + n.y * n.y * a, -n.y);
}

// A uniform [0, 1) number from a texel index and a stream, so rays do not depend on threads.
float hashUnit(uint32_t index, uint32_t stream) {
  uint32_t h = index * 0x9E3779B1u ^ (stream + 0x7F4A7C15u) * 0x85EBCA77u;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return float(h >> 8) * (1.0f / 16777216.0f);
}

bool backFaceOfSingleSided(const trace::RayTracer& tracer, const trace::Hit& hit) {
  return hit.valid() && !hit.frontFace && !tracer.material(hit).doubleSided;
}

glm::vec3 normalizedOr(const glm::vec3& v, const glm::vec3& fallback) {
  const float length = glm::length(v);
  if (!(length > 1e-12f) || !std::isfinite(length)) return fallback;
  return v / length;
}

}  // namespace

Result<TexelSet> computeTexels(const scenes::Scene& scene, const trace::RayTracer& tracer,
                               const TexelOptions& options, Progress& progress,
                               UvSet uvs) {
  TexelSet set;
  set.uvSet = uvs;

  // Atlas sizes, which every instance in an atlas must agree on.
  int atlasCount = 0;
  for (const scenes::Instance& inst : scene.instances)
    if (usableInstance(scene, inst, uvs))
      atlasCount = std::max(atlasCount, scenes::lightmapOf(inst, uvs).atlas + 1);
  if (atlasCount > 65535) return Result<TexelSet>::error("more than 65535 lightmap atlases");
  set.atlases.resize(size_t(atlasCount));
  for (const scenes::Instance& inst : scene.instances) {
    if (!usableInstance(scene, inst, uvs)) continue;
    const scenes::LightmapLocation& lm = scenes::lightmapOf(inst, uvs);
    runtime::AtlasLayout& layout = set.atlases[size_t(lm.atlas)];
    if (layout.width == 0) {
      layout.width = lm.width;
      layout.height = lm.height;
    } else if (layout.width != lm.width || layout.height != lm.height) {
      return Result<TexelSet>::error("instance '" + inst.name + "': lightmap atlas " +
                                     std::to_string(lm.atlas) +
                                     " has a different size than other instances in it");
    }
    if (lm.width > 65536 || lm.height > 65536)
      return Result<TexelSet>::error("instance '" + inst.name + "': atlas larger than 65536");
  }
  for (runtime::AtlasLayout& layout : set.atlases)
    layout.texelOfPixel.assign(size_t(layout.width) * size_t(layout.height), kNoTexel);

  // 1. Rasterise every instance on its own (in parallel), then merge per atlas in instance order.
  progress.begin(stageStep(Stage::Texels, "rasterise"), scene.instances.size());
  std::vector<std::vector<Touch>> perInstance(scene.instances.size());
  parallelFor(scene.instances.size(), [&](size_t i) {
    const scenes::Instance& inst = scene.instances[i];
    if (usableInstance(scene, inst, uvs) && !progress.cancelled())
      perInstance[i] = rasterizeInstance(scene, inst, uvs);
    progress.advance();
  }, 1);
  progress.end();
  if (progress.cancelled()) return Result<TexelSet>::error("cancelled");

  // Pixels hold indices into `records` until texel indices are assigned.
  std::vector<PixelRecord> records;
  for (size_t i = 0; i < perInstance.size(); ++i) {
    if (perInstance[i].empty()) continue;
    runtime::AtlasLayout& layout =
        set.atlases[size_t(scenes::lightmapOf(scene.instances[i], uvs).atlas)];
    for (const Touch& t : perInstance[i]) {
      uint32_t& slot = layout.texelOfPixel[t.pixel];
      if (slot == kNoTexel) {
        slot = uint32_t(records.size());
        records.push_back({uint32_t(i), t});
        continue;
      }
      // Charts of two instances overlap only without padding; the closer triangle still wins.
      PixelRecord& r = records[slot];
      const double area = r.touch.area + t.area;
      if (t.dist2 < r.touch.dist2) r = {uint32_t(i), t};
      r.touch.area = area;
    }
    std::vector<Touch>().swap(perInstance[i]);
  }

  // 2. Texel order: atlas, row, column.
  std::vector<uint32_t> texelRecord;
  texelRecord.reserve(records.size());
  for (size_t a = 0; a < set.atlases.size(); ++a) {
    runtime::AtlasLayout& layout = set.atlases[a];
    for (uint32_t& slot : layout.texelOfPixel) {
      if (slot == kNoTexel) continue;
      texelRecord.push_back(slot);
      slot = uint32_t(texelRecord.size() - 1);
    }
  }
  const size_t count = texelRecord.size();
  set.position.resize(count);
  set.normal.resize(count);
  set.geometricNormal.resize(count);
  set.area.resize(count);
  set.instance.resize(count);
  set.primitive.resize(count);
  set.triangle.resize(count);
  set.uv0.resize(count);
  set.atlas.resize(count);
  set.pixel.resize(count);
  set.offset.resize(count);
  set.edge.resize(count);
  set.nearGeometry.resize(count);
  set.valid.resize(count);

  // 3. Sample points, then push out of geometry. Each texel reads only its own record and seeds
  // its rays from its index, so the result does not depend on the thread count.
  const int leakRays = std::max(0, options.leakRays);
  progress.begin(stageStep(Stage::Texels, "place samples"), count);
  // In two steps per block: every texel's surface point and tangent rays, then, once the
  // block's rays are traced together (a coherent stream, RayTracer::intersect over an array:
  // rays of neighbouring texels at the same angle run nearly parallel), where each sample goes.
  struct Surface {
    glm::vec3 point, normal;
    float offset, texelSize;
  };
  parallelForBlocks(count, [&](size_t begin, size_t end, int) {
    std::vector<Surface> surfaces(end - begin);
    std::vector<trace::Ray> rays((end - begin) * size_t(leakRays));
    std::vector<trace::Hit> hits(rays.size());
    for (size_t ti = begin; ti < end; ++ti) {
      const PixelRecord& r = records[texelRecord[ti]];
      const scenes::Instance& inst = scene.instances[r.instance];
      const scenes::Primitive& prim = scene.meshes[size_t(inst.mesh)].primitives[r.touch.primitive];
      const uint32_t* idx = &prim.indices[3 * size_t(r.touch.triangle)];
      const glm::vec3 p0 = inst.toWorld(prim.positions[idx[0]]);
      const glm::vec3 p1 = inst.toWorld(prim.positions[idx[1]]);
      const glm::vec3 p2 = inst.toWorld(prim.positions[idx[2]]);
      const float texelSize = float(r.touch.texelSize);
      // A texel centre outside its triangle gets the closest point of the triangle, which lies
      // on an edge, often where two walls meet; rays from exactly there see through the corner.
      // The point moves a tenth of a texel toward the triangle's centroid instead.
      float u = float(r.touch.bary.x), v = float(r.touch.bary.y);
      {
        const glm::vec3 onEdge = (1.0f - u - v) * p0 + u * p1 + v * p2;
        const glm::vec3 toCentre = (p0 + p1 + p2) / 3.0f - onEdge;
        const float distance = glm::length(toCentre);
        if (distance > 0.0f && r.touch.dist2 > 0.0) {
          const float f = std::min(1.0f, 0.1f * texelSize / distance);
          u += f * (1.0f / 3.0f - u);
          v += f * (1.0f / 3.0f - v);
        }
      }
      const float w = 1.0f - u - v;
      const glm::vec3 surface = w * p0 + u * p1 + v * p2;
      const glm::mat3 linear(inst.transform);
      // glTF's front side flips with a mirroring transform.
      const float mirror = glm::determinant(linear) < 0.0f ? -1.0f : 1.0f;
      const glm::vec3 geo = normalizedOr(mirror * glm::cross(p1 - p0, p2 - p0), glm::vec3(0, 1, 0));
      glm::vec3 shading = geo;
      if (prim.normals.size() == prim.positions.size()) {
        const glm::mat3 normalMatrix = glm::transpose(glm::inverse(linear));
        shading = normalizedOr(
            normalMatrix * (w * prim.normals[idx[0]] + u * prim.normals[idx[1]] +
                            v * prim.normals[idx[2]]),
            geo);
      }
      glm::vec2 uv0(0.0f);
      if (prim.uv0.size() == prim.positions.size())
        uv0 = w * prim.uv0[idx[0]] + u * prim.uv0[idx[1]] + v * prim.uv0[idx[2]];

      const float offset = std::max(options.offsetFraction * texelSize, options.minOffset);

      // Tangent rays just above the surface: the nearest back face of a single-sided surface
      // means the sample is behind it, so it moves through to that surface's front.
      glm::vec3 t, b;
      tangentFrame(geo, t, b);
      const glm::vec3 origin = surface + geo * offset;
      const float phase = hashUnit(uint32_t(ti), 0);
      for (int k = 0; k < leakRays; ++k) {
        const float angle = 2.0f * kPi * (float(k) + phase) / float(leakRays);
        trace::Ray& ray = rays[(ti - begin) * size_t(leakRays) + size_t(k)];
        ray.origin = origin;
        ray.direction = std::cos(angle) * t + std::sin(angle) * b;
        ray.tfar = 1.5f * texelSize;
      }
      surfaces[ti - begin] = {surface, geo, offset, texelSize};

      set.normal[ti] = shading;
      set.geometricNormal[ti] = geo;
      set.area[ti] = float(r.touch.area);
      set.instance[ti] = r.instance;
      set.primitive[ti] = r.touch.primitive;
      set.triangle[ti] = r.touch.triangle;
      set.uv0[ti] = uv0;
      const scenes::LightmapLocation& lm = scenes::lightmapOf(inst, uvs);
      set.atlas[ti] = uint16_t(lm.atlas);
      set.pixel[ti] = glm::u16vec2(r.touch.pixel % uint32_t(lm.width),
                                   r.touch.pixel / uint32_t(lm.width));
      set.offset[ti] = offset;
      set.edge[ti] = texelSize;
    }
    tracer.intersect(rays.data(), hits.data(), rays.size());
    for (size_t ti = begin; ti < end; ++ti) {
      const Surface& s = surfaces[ti - begin];
      glm::vec3 sample = s.point;
      float nearest = std::numeric_limits<float>::infinity();
      bool nearGeometry = false;
      for (int k = 0; k < leakRays; ++k) {
        const size_t j = (ti - begin) * size_t(leakRays) + size_t(k);
        const trace::Hit& hit = hits[j];
        // Geometry within the texel's footprint (its half-diagonal) may split it in two.
        if (hit.valid() && hit.t < 0.75f * s.texelSize) nearGeometry = true;
        if (backFaceOfSingleSided(tracer, hit) && hit.t < nearest) {
          nearest = hit.t;
          sample = s.point + rays[j].direction * hit.t + hit.geometricNormal * s.offset;
        }
      }
      set.position[ti] = sample + s.normal * s.offset;
      set.nearGeometry[ti] = nearGeometry ? 1 : 0;
      // Whether the sample is buried inside geometry is the gather's call (gatherTexels): its
      // rays see the backs of single-sided walls from inside.
      set.valid[ti] = 1;
    }
    progress.advance(end - begin);
  }, 256);
  progress.end();
  if (progress.cancelled()) return Result<TexelSet>::error("cancelled");
  return set;
}

int texelMaterial(const scenes::Scene& scene, const TexelSet& texels, uint32_t t) {
  const scenes::Instance& inst = scene.instances[texels.instance[t]];
  return scene.meshes[size_t(inst.mesh)].primitives[texels.primitive[t]].material;
}

bool texelDoubleSided(const scenes::Scene& scene, const TexelSet& texels, uint32_t t) {
  return scene.material(texelMaterial(scene, texels, t)).doubleSided;
}

uint32_t texelAt(const scenes::Scene& scene, const TexelSet& texels, uint32_t instance,
                 uint32_t primitive, uint32_t triangle, glm::vec2 barycentric) {
  if (instance >= scene.instances.size()) return kNoTexel;
  const scenes::Instance& inst = scene.instances[instance];
  if (!usableInstance(scene, inst, texels.uvSet)) return kNoTexel;
  const scenes::Mesh& mesh = scene.meshes[size_t(inst.mesh)];
  if (primitive >= mesh.primitives.size()) return kNoTexel;
  const scenes::Primitive& prim = mesh.primitives[primitive];
  if (triangle >= prim.triangleCount() || !validTriangle(prim, triangle, texels.uvSet))
    return kNoTexel;
  const std::vector<glm::vec2>& uv = scenes::lightmapUvs(prim, texels.uvSet);
  const uint32_t* idx = &prim.indices[3 * size_t(triangle)];
  const float u = barycentric.x, v = barycentric.y;
  const glm::vec2 uv1 = (1.0f - u - v) * uv[idx[0]] + u * uv[idx[1]] + v * uv[idx[2]];
  return texelAtUv(scene, texels, instance, uv1);
}

uint32_t texelAtUv(const scenes::Scene& scene, const TexelSet& texels, uint32_t instance,
                   glm::vec2 uv1) {
  if (instance >= scene.instances.size()) return kNoTexel;
  const scenes::LightmapLocation& where =
      scenes::lightmapOf(scene.instances[instance], texels.uvSet);
  if (where.atlas < 0 || size_t(where.atlas) >= texels.atlases.size()) return kNoTexel;
  const runtime::AtlasLayout& layout = texels.atlases[size_t(where.atlas)];
  const glm::vec2 pixel = uv1 * glm::vec2(layout.width, layout.height);
  if (!std::isfinite(pixel.x) || !std::isfinite(pixel.y)) return kNoTexel;
  const int px = std::clamp(int(std::floor(pixel.x)), 0, layout.width - 1);
  const int py = std::clamp(int(std::floor(pixel.y)), 0, layout.height - 1);
  auto usable = [&](int x, int y) -> uint32_t {
    if (x < 0 || y < 0 || x >= layout.width || y >= layout.height) return kNoTexel;
    const uint32_t t = layout.texelOfPixel[size_t(y) * size_t(layout.width) + size_t(x)];
    if (t == kNoTexel || !texels.valid[t] || texels.instance[t] != instance) return kNoTexel;
    return t;
  };
  if (const uint32_t t = usable(px, py); t != kNoTexel) return t;
  // Rays may land in a texel that is unused or buried; its nearest valid neighbour stands in.
  uint32_t best = kNoTexel;
  float bestDist = std::numeric_limits<float>::infinity();
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const uint32_t t = usable(px + dx, py + dy);
      if (t == kNoTexel) continue;
      const glm::vec2 d = glm::vec2(px + dx + 0.5f, py + dy + 0.5f) - pixel;
      const float dist = glm::dot(d, d);
      if (dist < bestDist) {
        bestDist = dist;
        best = t;
      }
    }
  return best;
}

int footprintPoints(const scenes::Scene& scene, const TexelSet& texels, uint32_t t,
                    glm::vec3 out[16], const glm::vec2* jitter) {
  const scenes::Instance& inst = scene.instances[texels.instance[t]];
  const scenes::Primitive& prim =
      scene.meshes[size_t(inst.mesh)].primitives[texels.primitive[t]];
  const size_t first = size_t(texels.triangle[t]) * 3;
  const std::vector<glm::vec2>& uv = scenes::lightmapUvs(prim, texels.uvSet);
  const scenes::LightmapLocation& lm = scenes::lightmapOf(inst, texels.uvSet);
  if (uv.size() != prim.positions.size() || first + 2 >= prim.indices.size() || lm.width <= 0)
    return 0;
  const glm::dvec2 size(lm.width, lm.height);
  glm::dvec2 px[3];
  glm::dvec3 q[3];
  for (int k = 0; k < 3; ++k) {
    const uint32_t v = prim.indices[first + size_t(k)];
    px[k] = glm::dvec2(uv[v]) * size;
    q[k] = glm::dvec3(inst.toWorld(prim.positions[v]));
  }
  const glm::dmat2 pixels(px[1] - px[0], px[2] - px[0]);
  if (!(std::abs(glm::determinant(pixels)) > 1e-12)) return 0;
  const glm::dmat2 toBarycentric = glm::inverse(pixels);
  const glm::dvec3 lift = glm::dvec3(texels.geometricNormal[t]) * double(texels.offset[t]);
  const glm::dvec2 centre = glm::dvec2(texels.pixel[t]) + 0.5;
  constexpr int kSide = 4;
  constexpr double kInside = -1e-3;  // barycentric tolerance
  int n = 0;
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x) {
      const glm::dvec2 d =
          (jitter ? glm::dvec2(jitter[y * kSide + x])
                  : glm::dvec2((double(x) + 0.5) / kSide, (double(y) + 0.5) / kSide)) - 0.5;
      const glm::dvec2 b = toBarycentric * (centre + d - px[0]);
      if (b.x < kInside || b.y < kInside || 1.0 - b.x - b.y < kInside) continue;
      out[n++] = glm::vec3(q[0] + b.x * (q[1] - q[0]) + b.y * (q[2] - q[0]) + lift);
    }
  return n;
}


}  // namespace afterglow::baker
