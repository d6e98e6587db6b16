// Whether a point lies inside geometry, by what its rays see first (past dynamic objects, which
// are no walls), whatever the surfaces' sidedness:
//   - the backs of single-sided surfaces in more than `backFraction` of the directions (25% by
//     default, DDGI's and Unity's probe validity): inside a wall, or outside a level's shell;
//   - a double-sided object (shells.h: a shell that holds no other geometry) winding around it
//     more than half (its generalised winding number), which the backs a ray sees cannot tell
//     where the object's bottom lies on the floor: a closed box, or a block open only where it
//     stands on the floor. Curtains, leaves and single-plane walls stay thin (an open sheet
//     never winds half around a point), and a double-sided room (a shop around its furniture)
//     is no object.
// Shared by the light probes' placement and the reflection probes' proposals.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "afterglow/scenes/scene.h"
#include "afterglow/trace/raytracer.h"
#include "shells.h"

namespace afterglow::probes {

// A spherical Fibonacci set of n directions, turned off the axes so that no ray runs along an
// axis-aligned wall or through a row of columns exactly.
std::vector<glm::vec3> sphereDirections(int n);

// What a point's first hits say.
struct Sight {
  float backFraction = 0.0f;  // directions whose first hit is a single-sided back
  float winding = 0.0f;       // the most a double-sided object winds around the point
};

class InsideTest {
 public:
  // backFraction: the share of single-sided backs above which a point is inside.
  InsideTest(const scenes::Scene& scene, const trace::RayTracer& tracer, float backFraction);

  // The first static hit along each ray from p in the given directions (invalid on a miss).
  void firstHits(glm::vec3 p, const std::vector<glm::vec3>& directions,
                 std::vector<trace::Hit>& hits) const;
  // What such hits of point p say about it.
  Sight judge(glm::vec3 p, const std::vector<trace::Hit>& hits) const;

  bool inside(const Sight& s) const {
    return s.backFraction > backFraction_ || s.winding > 0.5f;
  }
  // Outside by a clear margin: a point moved out of geometry lands near what it left, where a
  // few rays more or less decide.
  bool clearlyOutside(const Sight& s) const {
    return s.backFraction < 0.75f * backFraction_ && s.winding < 0.25f;
  }

 private:
  const scenes::Scene& scene_;
  const trace::RayTracer& tracer_;
  float backFraction_;
  LevelObjects objects_;
  bool allStatic_ = true;
};

}  // namespace afterglow::probes
