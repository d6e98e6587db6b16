// Reflection probes' influence boxes: fades, the blend by importance levels, and box projection,
// all in double precision: the weights then sum to 1 far inside float rounding after the
// products of (1 − fade) and the division by the level's summed fades, and a grazing ray's wall
// hit, which divides by a small direction component, stays on the wall.
#include "afterglow/runtime/reflection_probes.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "afterglow/core/math.h"

namespace afterglow::runtime {
namespace {

using glm::dvec3;

// Whether the box takes part at all: positive half-sizes and finite values. A blend distance
// may be +infinity (clamped to the half-size anyway) but not NaN.
bool usable(const ReflectionProbeBox& box) {
  if (!(box.halfSize.x > 0.0f && box.halfSize.y > 0.0f && box.halfSize.z > 0.0f)) return false;
  if (!finite(box.centre) || !finite(box.halfSize)) return false;
  for (int c = 0; c < 3; ++c)
    if (!finite(box.axes[c])) return false;
  return !std::isnan(box.blendDistance);
}

// p in the box's local frame: the axes are orthonormal, so the transpose undoes them.
dvec3 toLocal(const ReflectionProbeBox& box, const dvec3& p) {
  return glm::transpose(glm::dmat3(box.axes)) * (p - dvec3(box.centre));
}

// The fade of a usable box at the local point q (see the header).
double fadeLocal(const ReflectionProbeBox& box, const dvec3& q) {
  const dvec3 h(box.halfSize);
  const dvec3 inside = h - glm::abs(q);  // distance to each pair's nearer face, inward
  const double d = std::min(inside.x, std::min(inside.y, inside.z));
  if (!(d > 0.0)) return 0.0;
  const double b = std::min(double(box.blendDistance), std::min(h.x, std::min(h.y, h.z)));
  if (!(b > 0.0)) return 1.0;  // a hard edge, as documented
  const double t = std::min(d / b, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace

ReflectionProbeBox reflectionProbeBoxFromNode(const glm::mat4& nodeToWorld, glm::vec3 size) {
  ReflectionProbeBox box;
  const glm::vec3 origin(nodeToWorld[3]);
  box.centre = origin;
  box.capturePosition = origin;
  const glm::vec3 cx(nodeToWorld[0]), cy(nodeToWorld[1]), cz(nodeToWorld[2]);
  box.halfSize =
      0.5f * glm::abs(size) * glm::vec3(glm::length(cx), glm::length(cy), glm::length(cz));
  // Gram–Schmidt on x then y, z from their cross product: a rotation even for a sheared or
  // mirrored node. With a zero column the half-size is zero already (the box is ignored), so the
  // identity axes there only keep the values finite.
  const float tiny = 1e-30f;
  if (glm::length(cx) > tiny && glm::length(cy) > tiny && glm::length(cz) > tiny) {
    const glm::vec3 x = glm::normalize(cx);
    const glm::vec3 yRest = cy - glm::dot(cy, x) * x;
    if (glm::length(yRest) > tiny * glm::length(cy)) {
      const glm::vec3 y = glm::normalize(yRest);
      box.axes = glm::mat3(x, y, glm::cross(x, y));
    }
  }
  return box;
}

float reflectionProbeFade(const ReflectionProbeBox& box, glm::vec3 p) {
  if (!usable(box) || !finite(p)) return 0.0f;
  return float(fadeLocal(box, toLocal(box, dvec3(p))));
}

std::vector<ProbeWeight> reflectionProbesAt(const std::vector<ReflectionProbeBox>& boxes,
                                            glm::vec3 p) {
  struct Faded {
    int box;
    double fade;
  };
  std::vector<Faded> faded;
  if (finite(p)) {
    const dvec3 pd(p);
    for (size_t i = 0; i < boxes.size(); ++i) {
      if (!usable(boxes[i])) continue;
      const double f = fadeLocal(boxes[i], toLocal(boxes[i], pd));
      if (f > 0.0) faded.push_back({int(i), f});
    }
  }
  // Importance from the highest down; within a level the box order only fixes the summation
  // order (the result does not depend on it beyond rounding), kept for determinism.
  std::stable_sort(faded.begin(), faded.end(), [&](const Faded& a, const Faded& b) {
    return boxes[size_t(a.box)].importance > boxes[size_t(b.box)].importance;
  });
  std::vector<double> weight(faded.size(), 0.0);
  double remaining = 1.0;
  for (size_t begin = 0; begin < faded.size();) {
    const int level = boxes[size_t(faded[begin].box)].importance;
    size_t end = begin;
    double sum = 0.0, uncovered = 1.0;
    for (; end < faded.size() && boxes[size_t(faded[end].box)].importance == level; ++end) {
      sum += faded[end].fade;
      uncovered *= 1.0 - faded[end].fade;
    }
    // The level covers 1 − uncovered of the remainder, shared in proportion to the fades
    // (sum > 0: only fades > 0 were kept).
    const double share = remaining * (1.0 - uncovered) / sum;
    for (size_t k = begin; k < end; ++k) weight[k] = share * faded[k].fade;
    remaining *= uncovered;
    begin = end;
  }

  std::vector<ProbeWeight> result;
  result.reserve(faded.size() + 1);
  if (float(remaining) > 0.0f) result.push_back({0, float(remaining)});
  std::vector<size_t> order(faded.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return faded[a].box < faded[b].box; });
  for (size_t k : order)
    if (float(weight[k]) > 0.0f) result.push_back({faded[k].box + 1, float(weight[k])});
  return result;
}

glm::vec3 boxProject(const ReflectionProbeBox& box, glm::vec3 position, glm::vec3 direction) {
  if (!box.boxProjection || !usable(box) || !finite(box.capturePosition) || !finite(position) ||
      !finite(direction))
    return direction;
  const bool ownProjection = box.projectionHalfSize.x > 0.0f && box.projectionHalfSize.y > 0.0f &&
                             box.projectionHalfSize.z > 0.0f && finite(box.projectionHalfSize) &&
                             finite(box.projectionCentre);
  const dvec3 h(ownProjection ? box.projectionHalfSize : box.halfSize);
  const dvec3 centre(ownProjection ? box.projectionCentre : box.centre);
  const dvec3 q = glm::clamp(glm::transpose(glm::dmat3(box.axes)) * (dvec3(position) - centre), -h, h);
  const dvec3 v = glm::transpose(glm::dmat3(box.axes)) * dvec3(direction);
  // The exit distance along the ray: for each axis the ray moves along, the slab face ahead of
  // it; the nearest of those is where the ray leaves the box (q is inside, so each t ≥ 0).
  double t = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (v[i] > 0.0) t = std::min(t, (h[i] - q[i]) / v[i]);
    if (v[i] < 0.0) t = std::min(t, (-h[i] - q[i]) / v[i]);
  }
  if (!std::isfinite(t)) return direction;  // a zero direction
  const dvec3 hit = centre + glm::dmat3(box.axes) * (q + t * v);
  const dvec3 toHit = hit - dvec3(box.capturePosition);
  const double length = glm::length(toHit);
  if (!(length > 0.0) || !finite(toHit)) return direction;
  return glm::vec3(toHit / length);
}

}  // namespace afterglow::runtime
