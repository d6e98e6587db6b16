// The shells of a level's static instances: each mesh's triangles joined wherever two share an
// edge (corners welded by their exact object-space position, so vertices split for normals or
// UVs still join). A closed box is one shell, a block open where it stands on the floor another,
// a curtain or a leaf card a third.
//
// A double-sided shell hides which side is its inside. One that winds around other geometry (a
// table, a shelf: the generalised winding number of that geometry's centre above one half) is a
// room, however its faces are wound: a shop modelled as a double-sided box around its furniture.
// One that holds nothing is an object: probes and reflection probes do not belong inside it
// (inside_test.h), which the object's generalised winding number around a point tells exactly,
// whatever its faces' sidedness and even where it is open (a block open only where it stands on
// the floor winds more than half around every point inside it; an open sheet never does).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/scenes/scene.h"

namespace afterglow::probes {

// The double-sided objects of a level's static instances, in world space.
class LevelObjects {
 public:
  explicit LevelObjects(const scenes::Scene& scene);
  // The most any object winds around p (its generalised winding number, 0 outside every
  // object's bounds): above one half p is inside that object.
  float winding(glm::vec3 p) const;
  size_t objects() const { return objects_.size(); }
  size_t rooms() const { return rooms_; }

 private:
  struct Object {
    std::vector<std::array<glm::vec3, 3>> triangles;  // as wound (mirroring undone)
    glm::vec3 lo{1e30f}, hi{-1e30f};
  };
  std::vector<Object> objects_;
  size_t rooms_ = 0;
};

}  // namespace afterglow::probes
