// Scenes built in code: the built-in sample for the README's first command and closed scenes
// with analytic answers for tests.
#pragma once

#include "afterglow/scenes/scene.h"

namespace afterglow::scenes {

// The Cornell box as Cornell measured it (graphics.cornell.edu/online/box/data.html), in metres
// in the data's own axes (Y up, right-handed): a 0.556 × 0.5488 × 0.5592 m room open towards -Z,
// short and tall blocks, and a 0.130 × 0.105 m emissive ceiling light (radiance (17, 12, 4),
// facing down, 1 mm below the ceiling). McGuire's measured colours: white 0.725/0.71/0.68, red
// 0.63/0.065/0.05 (left wall, x ≈ 0.556), green 0.14/0.45/0.091 (right wall, x = 0). Every wall,
// block and the light is its own single-sided mesh and instance, normals facing into the room
// ("floor", "ceiling", "back_wall", "left_wall", "right_wall", "short_block", "tall_block",
// "light"); camera "Camera" at (0.278, 0.273, -0.8) looking along +Z, yfov 0.686 rad.
Scene makeCornellBox();

// The Cornell box with metal, for reflection probes: the tall block a mirror (silver, roughness
// 0.02), the short one brushed copper (roughness 0.3), the open side closed by a white
// "front_wall", one reflection probe ("room_probe") filling the room with a 0.1 m blend, and the
// camera inside by the front wall (yfov 1.2 rad).
Scene makeCornellMetalBox();

struct FurnaceOptions {
  float size = 1.0f;                  // edge length of the cube, metres
  glm::vec3 albedo{0.5f};             // every surface's base colour (metallic 0, roughness 1)
  glm::vec3 emission{1.0f};           // every surface's emitted radiance
  int subdivisions = 4;               // quads per edge on each face
};
// A closed cube seen from inside: every surface has the same albedo and emission, so the
// radiance everywhere is Le / (1 - albedo), albedo being the bounce albedo of the material
// (baker::diffuseAlbedo: 0.96 × the base colour + 0.02 for this rough dielectric).
Scene makeFurnaceBox(const FurnaceOptions& options = {});

}  // namespace afterglow::scenes
