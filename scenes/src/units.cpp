#include "afterglow/scenes/units.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "afterglow/core/math.h"
#include "afterglow/core/status.h"

namespace afterglow::scenes {

// How the unit is judged. glTF is in metres, but exporters write centimetres (Unreal, 3ds Max,
// Maya) or millimetres (CAD; the Cornell box's published data) as they are. The level's size
// alone cannot tell: a 2 km terrain in metres is as wide as a 20 m room in centimetres, and a
// 550 mm box is narrower than a 6 m room. What the level holds can:
//
// 1. Each static instance's size is the largest edge of its world box, and the level's typical
//    object is the median of these sizes weighted by size^3/4. Counting each object once, a
//    level of a thousand small parts (the gas station's car and pumps) would read as made of
//    bolts; weighting by length, a floor plane would outweigh the chair on it (Bevy's
//    mixed-lighting room). The power between keeps both in proportion.
// 2. Metres, unless they make that typical object absurd: over kLargestTypicalMetres. A level
//    in metres is made of props, furniture, walls and building parts; what is larger (terrain,
//    floors, outer walls) is a minority. Sponza's typical object is 3.1 m, the gas station's
//    1.5 m, the mixed-lighting room's 0.8 m; the McGuire box, one 2 m object, is its level.
// 3. Otherwise centimetres or millimetres, whichever puts the level in proportion. In levels in
//    metres the typical object is about sqrt(kProportion × the level's size): a 6 m room holds
//    1–2 m furniture, a 50 m atrium 3 m columns and curtains, a 500 m town 10 m houses (Sponza,
//    the mixed-lighting room, the gas station, a furnished room and the Cornell box in metres
//    all fit within a factor of two and a half). A level of L units whose typical object is T
//    units is then in units of kProportion × L / T² metres, and the nearer of 0.01 and 0.001
//    (on a log scale) wins. So a level of thousands of units with objects of tens to hundreds
//    is in centimetres (Sponza in centimetres: 5100 units, objects of 310), and a level of
//    hundreds whose objects are hundreds each is one thing modelled in millimetres (Bevy's
//    Cornell box: 559, and 330).
//    Where the two readings meet, a small room of a few big pieces is ambiguous: a 6 m room of
//    six separate walls and little furniture, in centimetres, reads as a box in millimetres.
namespace {

constexpr float kLargestTypicalMetres = 20.0f;
constexpr double kProportion = 0.25;  // metres

// The largest edge of each static instance's world box over its finite vertices (instances
// without a size left out).
std::vector<float> staticObjectSizes(const Scene& scene) {
  std::vector<float> sizes;
  for (const Instance& inst : scene.instances) {
    const Mesh* mesh = scene.meshOf(inst);
    if (!inst.isStatic || !mesh) continue;
    Bounds b;
    for (const Primitive& p : mesh->primitives)
      for (const glm::vec3& v : p.positions)
        if (const glm::vec3 w = inst.toWorld(v); finite(w)) b.extend(w);
    const glm::vec3 s = b.size();
    const float size = std::max(s.x, std::max(s.y, s.z));
    if (size > 0.0f && std::isfinite(size)) sizes.push_back(size);
  }
  return sizes;
}

// The median of `sizes` weighted by size^3/4.
float typicalSize(std::vector<float> sizes) {
  std::sort(sizes.begin(), sizes.end());
  auto weight = [](float s) { return std::pow(double(s), 0.75); };
  double total = 0.0;
  for (float s : sizes) total += weight(s);
  double below = 0.0;
  for (float s : sizes) {
    below += weight(s);
    if (below >= 0.5 * total) return s;
  }
  return sizes.empty() ? 0.0f : sizes.back();
}

const char* unitName(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::Metres: return "metres";
    case LengthUnit::Centimetres: return "centimetres";
    case LengthUnit::Millimetres: return "millimetres";
  }
  return "?";
}

}  // namespace

UnitsGuess guessUnits(const Scene& scene) {
  UnitsGuess guess;
  const std::vector<float> sizes = staticObjectSizes(scene);
  guess.objects = sizes.size();
  if (sizes.empty()) return guess;
  guess.typicalSize = typicalSize(sizes);
  const glm::vec3 level = scene.staticBounds().size();
  guess.levelSize = std::max(level.x, std::max(level.y, level.z));
  if (!(guess.typicalSize > kLargestTypicalMetres)) return guess;
  const double metresPerUnitSeen =
      kProportion * double(guess.levelSize) / (double(guess.typicalSize) * guess.typicalSize);
  // Halfway between centimetres and millimetres on a log scale: sqrt(0.01 × 0.001).
  guess.unit = metresPerUnitSeen < std::sqrt(1e-5) ? LengthUnit::Millimetres
                                                    : LengthUnit::Centimetres;
  return guess;
}

float metresPerUnit(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::Metres: return 1.0f;
    case LengthUnit::Centimetres: return 0.01f;
    case LengthUnit::Millimetres: return 0.001f;
  }
  return 1.0f;
}

std::string unitsWarning(const UnitsGuess& guess, const std::string& name) {
  if (guess.unit == LengthUnit::Metres) return "";
  const std::string scale = format("%g", double(metresPerUnit(guess.unit)));
  return format("%s: the level looks like it is in %s, not metres: it is %.4g units across and "
                "its objects typically %.4g units (%.4g m each, read as metres); glTF is in "
                "metres: scale its root node by %s, or pass --unit-scale %s",
                name.c_str(), unitName(guess.unit), double(guess.levelSize),
                double(guess.typicalSize), double(guess.typicalSize), scale.c_str(),
                scale.c_str());
}

void scaleScene(Scene& scene, float factor) {
  const glm::mat4 s = glm::scale(glm::mat4(1.0f), glm::vec3(factor));
  for (Instance& inst : scene.instances) inst.transform = s * inst.transform;
  for (Light& light : scene.lights) {
    light.position *= factor;
    light.range *= factor;
    light.radius *= factor;
  }
  for (Camera& camera : scene.cameras) {
    // The position only: a camera's axes stay unit length, as glTF wants them.
    camera.transform[3] = glm::vec4(glm::vec3(camera.transform[3]) * factor, 1.0f);
    camera.znear *= factor;
    camera.zfar *= factor;
    camera.xmag *= factor;
    camera.ymag *= factor;
  }
  for (ProbeVolume& volume : scene.probeVolumes) {
    volume.transform = s * volume.transform;
    volume.spacing *= factor;
  }
  for (ReflectionProbe& probe : scene.reflectionProbes) {
    probe.transform = s * probe.transform;
    probe.blendDistance *= factor;
  }
}

}  // namespace afterglow::scenes
