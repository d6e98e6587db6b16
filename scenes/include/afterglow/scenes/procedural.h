// Scenes built in code: the built-in sample for the README's first command and closed scenes
// with analytic answers for tests.
#pragma once

#include "afterglow/scenes/scene.h"

namespace afterglow::scenes {

// The Cornell box with the classic dimensions (Cornell's measured data, 5.56 m box scaled to
// metres ×0.01, i.e. a 5.56 × 5.49 × 5.59 box of 0.556 m... see procedural.cpp) and McGuire's
// measured colours: white 0.725/0.71/0.68, red 0.63/0.065/0.05, green 0.14/0.45/0.091, two
// boxes, and an emissive ceiling light.
Scene makeCornellBox();

struct FurnaceOptions {
  float size = 1.0f;                  // edge length of the cube, metres
  glm::vec3 albedo{0.5f};             // every surface's diffuse albedo
  glm::vec3 emission{1.0f};           // every surface's emitted radiance
  int subdivisions = 4;               // quads per edge on each face
};
// A closed cube seen from inside: every surface has the same albedo and emission, so the
// radiance everywhere is Le / (1 - albedo).
Scene makeFurnaceBox(const FurnaceOptions& options = {});

}  // namespace afterglow::scenes
