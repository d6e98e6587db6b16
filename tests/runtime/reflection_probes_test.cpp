// Reflection probes' influence boxes: box projection against wall hits computed here with a slab
// test of the test's own, and the blend's guarantees (weights ≥ 0 summing to 1, continuity along
// paths 1 mm at a time, importance, the sky outside, a box alone at its centre) on a scene of
// overlapping boxes, some turned, with different blend distances and importances.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "afterglow/runtime/reflection_probes.h"
#include "test_rng.h"

namespace afterglow::runtime {
namespace {

using glm::dvec3;
using test::Rng;

float uniform(Rng& rng, float lo, float hi) { return lo + (hi - lo) * rng.unit(); }

glm::vec3 uniformIn(Rng& rng, glm::vec3 lo, glm::vec3 hi) {
  return {uniform(rng, lo.x, hi.x), uniform(rng, lo.y, hi.y), uniform(rng, lo.z, hi.z)};
}

glm::vec3 unitVector(Rng& rng) {
  for (;;) {
    const glm::vec3 v = uniformIn(rng, glm::vec3(-1.0f), glm::vec3(1.0f));
    const float l = glm::length(v);
    if (l > 0.1f && l <= 1.0f) return v / l;
  }
}

// A box on a node turned by `degrees` about `axis`, with the node's scale applied to `size`.
ReflectionProbeBox turnedBox(glm::vec3 centre, float degrees, glm::vec3 axis, glm::vec3 size) {
  const glm::mat4 node = glm::rotate(glm::translate(glm::mat4(1.0f), centre), glm::radians(degrees),
                                     glm::normalize(axis));
  return reflectionProbeBoxFromNode(node, size);
}

// Where the ray (o, d) from inside the box leaves it, by the textbook slab test in the box's
// frame (every slab's far crossing; the nearest of those), in double precision.
dvec3 exitPoint(const ReflectionProbeBox& box, glm::vec3 o, glm::vec3 d) {
  const glm::dmat3 axes(box.axes);
  const dvec3 q = glm::transpose(axes) * (dvec3(o) - dvec3(box.centre));
  const dvec3 v = glm::transpose(axes) * dvec3(d);
  double tExit = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (v[i] == 0.0) continue;
    const double t0 = (-double(box.halfSize[i]) - q[i]) / v[i];
    const double t1 = (double(box.halfSize[i]) - q[i]) / v[i];
    tExit = std::min(tExit, std::max(t0, t1));
  }
  return dvec3(o) + tExit * dvec3(d);
}

// A point uniformly inside the box, `margin` (relative) away from its faces.
glm::vec3 pointInside(Rng& rng, const ReflectionProbeBox& box, float margin) {
  const glm::vec3 local =
      uniformIn(rng, -(1.0f - margin) * box.halfSize, (1.0f - margin) * box.halfSize);
  return box.centre + box.axes * local;
}

bool insideBox(const ReflectionProbeBox& box, glm::vec3 p) {
  const glm::vec3 q = glm::transpose(box.axes) * (p - box.centre);
  return std::abs(q.x) < box.halfSize.x && std::abs(q.y) < box.halfSize.y &&
         std::abs(q.z) < box.halfSize.z;
}

std::map<int, float> weightsByProbe(const std::vector<ProbeWeight>& w) {
  std::map<int, float> m;
  for (const ProbeWeight& pw : w) m[pw.probe] += pw.weight;
  return m;
}

float weightOf(const std::vector<ProbeWeight>& w, int probe) {
  for (const ProbeWeight& pw : w)
    if (pw.probe == probe) return pw.weight;
  return 0.0f;
}

// The blend distance the fade really uses (clamped to the smallest half-size).
float effectiveBlend(const ReflectionProbeBox& box) {
  return std::min(box.blendDistance,
                  std::min(box.halfSize.x, std::min(box.halfSize.y, box.halfSize.z)));
}

// The scene for the blend tests: a hall, a turned box of the same importance overlapping it,
// two more important boxes (one turned, one sticking out of the hall), a box whose blend distance
// exceeds its half-size, and a turned box alone outside the hall. boxes[i] is probe i + 1.
std::vector<ReflectionProbeBox> scene() {
  std::vector<ReflectionProbeBox> boxes;
  ReflectionProbeBox hall = reflectionProbeBoxFromNode(glm::mat4(1.0f), glm::vec3(12, 6, 12));
  boxes.push_back(hall);  // 1: importance 1, blend 1

  ReflectionProbeBox side = turnedBox({3, 0, 2}, 30.0f, {0, 1, 0}, {5, 4, 3});
  side.blendDistance = 0.6f;
  boxes.push_back(side);  // 2: importance 1, overlaps the hall

  ReflectionProbeBox alcove = turnedBox({-2, 0.5f, -1}, 50.0f, {1, 1, 0}, {2, 2, 2});
  alcove.blendDistance = 0.5f;
  alcove.importance = 2;
  boxes.push_back(alcove);  // 3: more important, inside the hall

  ReflectionProbeBox bay = turnedBox({5, 1, -3}, -20.0f, {0.3f, 1, 0.2f}, {3, 2, 4});
  bay.blendDistance = 0.25f;
  bay.importance = 3;
  boxes.push_back(bay);  // 4: the most important, partly outside the hall

  ReflectionProbeBox narrow = reflectionProbeBoxFromNode(
      glm::translate(glm::mat4(1.0f), glm::vec3(-4, 0, 4)), glm::vec3(2, 4, 3));
  narrow.blendDistance = 3.0f;  // clamped to its smallest half-size, 1
  boxes.push_back(narrow);      // 5: importance 1, inside the hall's corner

  ReflectionProbeBox shed = turnedBox({12, 0, 9}, 70.0f, {0, 0, 1}, {3, 2, 2});
  shed.blendDistance = 0.5f;
  boxes.push_back(shed);  // 6: alone, outside the hall
  return boxes;
}

void expectNormalised(const std::vector<ProbeWeight>& w, size_t boxCount) {
  ASSERT_FALSE(w.empty());
  double sum = 0.0;
  int previous = -1;
  for (const ProbeWeight& pw : w) {
    EXPECT_GT(pw.weight, 0.0f);
    EXPECT_GT(pw.probe, previous);  // increasing, so no probe twice
    EXPECT_LE(pw.probe, int(boxCount));
    previous = pw.probe;
    sum += pw.weight;
  }
  EXPECT_NEAR(sum, 1.0, 1e-6);
}

TEST(ReflectionProbes, BoxFromANodeTakesItsTranslationTurnAndScale) {
  const glm::mat4 turn =
      glm::rotate(glm::mat4(1.0f), glm::radians(40.0f), glm::normalize(glm::vec3(1, 2, 3)));
  const glm::mat4 node = glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3)) * turn,
                                    glm::vec3(2.0f, 1.0f, 0.5f));
  const ReflectionProbeBox box = reflectionProbeBoxFromNode(node, glm::vec3(2, 4, 6));
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(box.centre[i], float(i + 1), 1e-6f);
    EXPECT_NEAR(box.capturePosition[i], float(i + 1), 1e-6f);
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(box.axes[i][j], turn[i][j], 1e-6f);
  }
  EXPECT_NEAR(box.halfSize.x, 2.0f, 1e-6f);
  EXPECT_NEAR(box.halfSize.y, 2.0f, 1e-6f);
  EXPECT_NEAR(box.halfSize.z, 1.5f, 1e-6f);
  EXPECT_EQ(box.blendDistance, 1.0f);
  EXPECT_EQ(box.importance, 1);
  EXPECT_TRUE(box.boxProjection);
  // A mirrored node still gives a rotation (determinant +1).
  const ReflectionProbeBox mirrored =
      reflectionProbeBoxFromNode(glm::scale(glm::mat4(1.0f), glm::vec3(1, 1, -1)), glm::vec3(1));
  EXPECT_NEAR(glm::determinant(mirrored.axes), 1.0f, 1e-6f);
  EXPECT_NEAR(mirrored.halfSize.z, 0.5f, 1e-6f);
}

TEST(ReflectionProbes, BoxProjectionLooksAtTheWallPointTheRayHits) {
  // An axis-aligned room and a turned, non-uniformly scaled one, each captured off its centre.
  ReflectionProbeBox aligned = reflectionProbeBoxFromNode(
      glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3)), glm::vec3(8, 3, 6));
  aligned.capturePosition = aligned.centre + glm::vec3(1.5f, -0.5f, 0.7f);
  const glm::mat4 turnedNode =
      glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(-5, 1, 4)),
                             glm::radians(37.0f), glm::normalize(glm::vec3(1, 2, 0.5f))),
                 glm::vec3(1.0f, 2.0f, 1.0f));
  ReflectionProbeBox turned = reflectionProbeBoxFromNode(turnedNode, glm::vec3(6, 2, 4));
  turned.capturePosition = turned.centre + turned.axes * glm::vec3(-1.0f, 0.4f, 0.8f);

  Rng rng{15};
  for (const ReflectionProbeBox* room : {&aligned, &turned}) {
    const double roomSize =
        2.0 * std::max(room->halfSize.x, std::max(room->halfSize.y, room->halfSize.z));
    double worst = 0.0, worstUncorrected = 0.0;
    for (int n = 0; n < 4000; ++n) {
      const glm::vec3 p = pointInside(rng, *room, 0.001f);
      const glm::vec3 d = unitVector(rng);
      const glm::vec3 r = boxProject(*room, p, d);
      EXPECT_NEAR(glm::length(r), 1.0f, 1e-6f);
      const dvec3 wall = exitPoint(*room, p, d);
      const dvec3 seen = exitPoint(*room, room->capturePosition, r);
      worst = std::max(worst, glm::distance(wall, seen) / roomSize);
      worstUncorrected =
          std::max(worstUncorrected,
                   glm::distance(wall, exitPoint(*room, room->capturePosition, d)) / roomSize);
    }
    std::printf(
        "[ reflection ] box projection: worst wall miss %.2e of the room (uncorrected %.2f)\n",
        worst, worstUncorrected);
    EXPECT_LE(worst, 1e-4);
    // Without the correction the capture position would see other walls: the test can fail.
    EXPECT_GT(worstUncorrected, 0.1);
  }
}

TEST(ReflectionProbes, BoxProjectionLeavesTheDirectionAloneWhenOffAndClampsOutside) {
  ReflectionProbeBox box = reflectionProbeBoxFromNode(glm::mat4(1.0f), glm::vec3(4));
  box.capturePosition = glm::vec3(0.5f, 0, 0);
  const glm::vec3 d = glm::normalize(glm::vec3(1, 2, -0.5f));
  const glm::vec3 inside(0.2f, -1.0f, 1.0f);
  EXPECT_GT(glm::distance(boxProject(box, inside, d), d), 1e-3f);
  // A point outside looks up as from the nearest point of the box (continuous across a wall).
  EXPECT_EQ(boxProject(box, glm::vec3(2.5f, 0, 0), d), boxProject(box, glm::vec3(2, 0, 0), d));
  EXPECT_LT(glm::distance(boxProject(box, glm::vec3(2.0001f, 0.3f, 0), d),
                          boxProject(box, glm::vec3(1.9999f, 0.3f, 0), d)),
            1e-3f);
  box.boxProjection = false;
  EXPECT_EQ(boxProject(box, inside, d), d);
  box.boxProjection = true;
  EXPECT_EQ(boxProject(box, inside, glm::vec3(0)), glm::vec3(0));
  // A projection box of its own (a fitted room's walls inside a wider influence box) is the
  // one the ray leaves: from (0.5, 0, 0) along (1, 1, 0) it reaches the wall x = 1 at
  // (1, 0.5, 0), level with the capture position, not the influence box's x = 2.
  ReflectionProbeBox fitted = box;
  fitted.capturePosition = glm::vec3(0.0f, 0.5f, 0.0f);
  fitted.projectionCentre = glm::vec3(0.0f);
  fitted.projectionHalfSize = glm::vec3(1.0f);
  const glm::vec3 up = boxProject(fitted, glm::vec3(0.5f, 0, 0), glm::normalize(glm::vec3(1, 1, 0)));
  EXPECT_LT(glm::distance(up, glm::vec3(1.0f, 0.0f, 0.0f)), 1e-6f);
  // Looking from the capture position itself changes nothing.
  const glm::vec3 same = boxProject(box, box.capturePosition, d);
  EXPECT_NEAR(glm::distance(same, d), 0.0f, 1e-6f);
}

TEST(ReflectionProbes, WeightsAreNonNegativeAndSumToOne) {
  const std::vector<ReflectionProbeBox> boxes = scene();
  Rng rng{7};
  int blended = 0;
  for (int n = 0; n < 20000; ++n) {
    const glm::vec3 p = uniformIn(rng, glm::vec3(-8, -4, -8), glm::vec3(15, 4, 12));
    const std::vector<ProbeWeight> w = reflectionProbesAt(boxes, p);
    expectNormalised(w, boxes.size());
    blended += w.size() >= 2;
  }
  EXPECT_GT(blended, 1000);  // the points do land where several probes blend
}

TEST(ReflectionProbes, WeightsMoveLittleAlongPathsMillimetreByMillimetre) {
  const std::vector<ReflectionProbeBox> boxes = scene();
  Rng rng{11};
  const float step = 1e-3f;
  double worstJump = 0.0;     // the largest change of one probe's weight over 1 mm
  double worstOfBound = 0.0;  // that change over its bound
  double worstScaled = 0.0;   // the change in units of step / (smallest blend distance in play)
  int crossings = 0;
  for (int path = 0; path < 48; ++path) {
    // From one box's inside to another's (or to a random point), so paths cross faces and
    // blend regions.
    const glm::vec3 a = pointInside(rng, boxes[rng.below(uint32_t(boxes.size()))], 0.0f);
    const glm::vec3 b = rng.below(4) == 0
                            ? uniformIn(rng, glm::vec3(-8, -4, -8), glm::vec3(15, 4, 12))
                            : pointInside(rng, boxes[rng.below(uint32_t(boxes.size()))], 0.0f);
    const float length = glm::distance(a, b);
    const glm::vec3 dir = (b - a) / length;
    const int steps = int(length / step);
    std::map<int, float> previous = weightsByProbe(reflectionProbesAt(boxes, a));
    std::vector<bool> wasInside(boxes.size());
    for (size_t k = 0; k < boxes.size(); ++k) wasInside[k] = insideBox(boxes[k], a);
    glm::vec3 previousPoint = a;
    for (int s = 1; s <= steps; ++s) {
      const glm::vec3 p = a + (float(s) * step) * dir;
      std::map<int, float> current = weightsByProbe(reflectionProbesAt(boxes, p));
      // Each fade moves by at most 1.5 / b per metre (a smoothstep of a distance to the faces)
      // and each weight by at most the sum of its fades' moves (every partial derivative of a
      // weight by a fade lies in [−1, 1]); rounding adds ~1e-7.
      double slopes = 0.0, smallestBlend = std::numeric_limits<double>::infinity();
      for (size_t k = 0; k < boxes.size(); ++k) {
        const bool in = insideBox(boxes[k], p);
        crossings += in != wasInside[k];
        if (in || wasInside[k]) {
          slopes += 1.5 / effectiveBlend(boxes[k]);
          smallestBlend = std::min(smallestBlend, double(effectiveBlend(boxes[k])));
        }
        wasInside[k] = in;
      }
      const double moved = glm::distance(p, previousPoint);
      const double bound = 1.01 * slopes * moved + 1e-6;
      for (int probe = 0; probe <= int(boxes.size()); ++probe) {
        const double jump = std::abs(double(current[probe]) - double(previous[probe]));
        if (jump > bound) {
          ADD_FAILURE() << "probe " << probe << " jumps " << jump << " > " << bound << " over "
                        << moved << " m at (" << p.x << ", " << p.y << ", " << p.z << ")";
          return;
        }
        worstJump = std::max(worstJump, jump);
        if (slopes > 0.0) {
          worstOfBound = std::max(worstOfBound, (jump - 1e-6) / (slopes * moved));
          worstScaled = std::max(worstScaled, jump * smallestBlend / moved);
        }
      }
      previous = std::move(current);
      previousPoint = p;
    }
  }
  std::printf(
      "[ reflection ] blend: %d face crossings; worst weight jump %.2e per mm, %.2f of "
      "its bound, %.2f x (1 mm / smallest b)\n",
      crossings, worstJump, worstOfBound, worstScaled);
  EXPECT_GT(crossings, 60);
}

TEST(ReflectionProbes, AMoreImportantBoxWinsInsideItsBlendRegion) {
  const std::vector<ReflectionProbeBox> boxes = scene();
  Rng rng{3};
  int checked = 0;
  for (int n = 0; n < 20000; ++n) {
    const glm::vec3 p = uniformIn(rng, glm::vec3(-8, -4, -8), glm::vec3(15, 4, 12));
    const std::vector<ProbeWeight> w = reflectionProbesAt(boxes, p);
    for (size_t k = 0; k < boxes.size(); ++k) {
      if (reflectionProbeFade(boxes[k], p) != 1.0f) continue;
      ++checked;
      EXPECT_EQ(weightOf(w, 0), 0.0f);  // the sky too
      for (size_t j = 0; j < boxes.size(); ++j) {
        if (boxes[j].importance < boxes[k].importance) {
          EXPECT_EQ(weightOf(w, int(j) + 1), 0.0f);
        }
      }
    }
  }
  EXPECT_GT(checked, 1000);

  // The exact shares on a line from the alcove's centre (importance 2) out through its face, all
  // inside the hall (importance 1, fade 1 there): the alcove takes its fade f, the hall the rest.
  const ReflectionProbeBox& alcove = boxes[2];
  for (float s = 0.0f; s <= 1.2f; s += 0.05f) {
    const glm::vec3 p = alcove.centre + alcove.axes * glm::vec3(s * alcove.halfSize.x, 0, 0);
    const float f = reflectionProbeFade(alcove, p);
    ASSERT_EQ(reflectionProbeFade(boxes[0], p), 1.0f);
    const std::vector<ProbeWeight> w = reflectionProbesAt(boxes, p);
    EXPECT_NEAR(weightOf(w, 3), f, 1e-6f) << s;
    EXPECT_NEAR(weightOf(w, 1), 1.0f - f, 1e-6f) << s;
    // Deep inside the alcove it is alone; out of it, the hall is.
    if (s < 0.45f || s > 1.0f) {
      EXPECT_EQ(w.size(), 1u) << s;
    }
  }
}

TEST(ReflectionProbes, BoxesOfOneImportanceShareWhereTheyOverlap) {
  // Two equal boxes overlapping over 2 m: their fades are 1 in the middle of the overlap, so
  // each gets a half; where one fades the other takes over and the sky never shows.
  ReflectionProbeBox left = reflectionProbeBoxFromNode(
      glm::translate(glm::mat4(1.0f), glm::vec3(-2, 0, 0)), glm::vec3(8));
  ReflectionProbeBox right =
      reflectionProbeBoxFromNode(glm::translate(glm::mat4(1.0f), glm::vec3(2, 0, 0)), glm::vec3(8));
  left.blendDistance = right.blendDistance = 0.5f;
  const std::vector<ReflectionProbeBox> boxes = {left, right};
  const std::vector<ProbeWeight> middle = reflectionProbesAt(boxes, glm::vec3(0));
  EXPECT_NEAR(weightOf(middle, 1), 0.5f, 1e-6f);
  EXPECT_NEAR(weightOf(middle, 2), 0.5f, 1e-6f);
  for (float x = -1.9f; x <= 1.9f; x += 0.01f) {
    const std::vector<ProbeWeight> w = reflectionProbesAt(boxes, glm::vec3(x, 0, 0));
    EXPECT_EQ(weightOf(w, 0), 0.0f) << x;
    // Mirror symmetry: the boxes' order does not favour either.
    const std::vector<ProbeWeight> m = reflectionProbesAt(boxes, glm::vec3(-x, 0, 0));
    EXPECT_NEAR(weightOf(w, 1), weightOf(m, 2), 1e-6f) << x;
  }
}

TEST(ReflectionProbes, OutsideEveryBoxTheSkyGetsOne) {
  const std::vector<ReflectionProbeBox> boxes = scene();
  Rng rng{5};
  int outside = 0;
  for (int n = 0; n < 20000; ++n) {
    const glm::vec3 p = uniformIn(rng, glm::vec3(-12, -6, -12), glm::vec3(18, 6, 15));
    bool inAny = false;
    for (const ReflectionProbeBox& box : boxes) inAny = inAny || insideBox(box, p);
    if (inAny) continue;
    ++outside;
    const std::vector<ProbeWeight> w = reflectionProbesAt(boxes, p);
    ASSERT_EQ(w.size(), 1u);
    EXPECT_EQ(w[0].probe, 0);
    EXPECT_EQ(w[0].weight, 1.0f);
  }
  EXPECT_GT(outside, 1000);
  // No boxes, a point that is not finite, and boxes that are ignored: the sky.
  EXPECT_EQ(reflectionProbesAt({}, glm::vec3(0)).size(), 1u);
  const std::vector<ProbeWeight> nan =
      reflectionProbesAt(boxes, glm::vec3(std::numeric_limits<float>::quiet_NaN(), 0, 0));
  ASSERT_EQ(nan.size(), 1u);
  EXPECT_EQ(nan[0].probe, 0);
  ReflectionProbeBox flat = reflectionProbeBoxFromNode(glm::mat4(1.0f), glm::vec3(2, 0, 2));
  const std::vector<ProbeWeight> ignored = reflectionProbesAt({flat}, glm::vec3(0));
  ASSERT_EQ(ignored.size(), 1u);
  EXPECT_EQ(ignored[0].probe, 0);
}

TEST(ReflectionProbes, ABoxAloneGetsOneAtItsCentre) {
  const std::vector<ReflectionProbeBox> boxes = scene();
  // The shed stands alone (blend 0.5 ≤ its half-sizes). The narrow box's blend distance, 3,
  // exceeds its smallest half-size, 1, and is clamped, so it too reaches 1 at its centre: alone
  // it gets 1 there, and in the scene it shares equally with the hall (same importance, fade 1).
  const std::vector<ProbeWeight> shed = reflectionProbesAt(boxes, boxes[5].centre);
  ASSERT_EQ(shed.size(), 1u);
  EXPECT_EQ(shed[0].probe, 6);
  EXPECT_EQ(shed[0].weight, 1.0f);
  EXPECT_EQ(reflectionProbeFade(boxes[4], boxes[4].centre), 1.0f);
  const std::vector<ReflectionProbeBox> narrowAlone = {boxes[4]};
  const std::vector<ProbeWeight> narrow = reflectionProbesAt(narrowAlone, boxes[4].centre);
  ASSERT_EQ(narrow.size(), 1u);
  EXPECT_EQ(narrow[0].probe, 1);
  EXPECT_EQ(narrow[0].weight, 1.0f);
  const std::vector<ProbeWeight> inHall = reflectionProbesAt(boxes, boxes[4].centre);
  EXPECT_NEAR(weightOf(inHall, 1), 0.5f, 1e-6f);
  EXPECT_NEAR(weightOf(inHall, 5), 0.5f, 1e-6f);
  // Half way from the centre to a face along the smallest axis: smoothstep(0.5) = 0.5.
  EXPECT_NEAR(reflectionProbeFade(boxes[4], boxes[4].centre + glm::vec3(0.5f, 0, 0)), 0.5f, 1e-6f);
}

}  // namespace
}  // namespace afterglow::runtime
