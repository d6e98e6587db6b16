// Scenes built in code. The Cornell box follows Cornell's published measurements
// (graphics.cornell.edu/online/box/data.html) in their own axes (Y up, the camera at z = -0.8
// looking along +Z), converted from millimetres to metres, so coordinates can be checked
// against the data page line by line.
#include "afterglow/scenes/procedural.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "afterglow/core/check.h"

namespace afterglow::scenes {
namespace {

using Quad = std::array<glm::vec3, 4>;

// Millimetres (the data page's unit) to metres, divided in double so that e.g. 552.8 mm becomes
// the float nearest to 0.5528 m rather than a product of two rounded floats.
glm::vec3 mm(glm::vec3 p) { return glm::vec3(glm::dvec3(p) / 1000.0); }

Quad quadMm(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
  return {mm(a), mm(b), mm(c), mm(d)};
}

// Newell's normal: well defined for the measured quads, a few of which are slightly non-planar
// (the left wall leans by 3.2 mm), where a single triangle's normal would favour one half.
glm::vec3 newellNormal(const Quad& q) {
  glm::vec3 n(0.0f);
  for (int i = 0; i < 4; ++i) {
    const glm::vec3& p = q[i];
    const glm::vec3& r = q[(i + 1) % 4];
    n.x += (p.y - r.y) * (p.z + r.z);
    n.y += (p.z - r.z) * (p.x + r.x);
    n.z += (p.x - r.x) * (p.y + r.y);
  }
  return glm::normalize(n);
}

glm::vec3 quadCentre(const Quad& q) { return (q[0] + q[1] + q[2] + q[3]) * 0.25f; }

// Appends a quad as two triangles (0,1,2) and (0,2,3) with its own four vertices (hard edges
// between quads), reversing the winding when needed so that the front face, counter-clockwise
// as glTF defines it, faces `towards`.
void addQuad(Primitive& prim, Quad q, glm::vec3 towards) {
  if (glm::dot(newellNormal(q), towards) < 0.0f) std::swap(q[1], q[3]);
  const glm::vec3 n = newellNormal(q);
  const uint32_t base = uint32_t(prim.positions.size());
  for (const glm::vec3& p : q) {
    prim.positions.push_back(p);
    prim.normals.push_back(n);
  }
  for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) prim.indices.push_back(base + i);
}

Material diffuse(const char* name, glm::vec3 albedo) {
  Material m;
  m.name = name;
  m.baseColorFactor = glm::vec4(albedo, 1.0f);
  m.metallicFactor = 0.0f;
  m.roughnessFactor = 1.0f;
  return m;
}

// glTF clamps emissiveFactor to [0, 1]; the brightest channel moves into emissiveStrength.
void setEmission(Material& m, glm::vec3 radiance) {
  const float peak = std::max(radiance.x, std::max(radiance.y, radiance.z));
  if (peak > 0.0f) {
    m.emissiveFactor = radiance / peak;
    m.emissiveStrength = peak;
  } else {
    m.emissiveFactor = glm::vec3(0.0f);
    m.emissiveStrength = 1.0f;
  }
}

void addMeshInstance(Scene& scene, const char* name, Primitive prim) {
  Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(std::move(prim));
  Instance inst;
  inst.name = name;
  inst.mesh = int(scene.meshes.size());
  scene.meshes.push_back(std::move(mesh));
  scene.instances.push_back(std::move(inst));
}

// A block from the data page: the top quad then four side quads, normals facing away from the
// block's centre. The bottom is omitted as in the original data (it rests on the floor).
Primitive block(const std::array<Quad, 5>& faces, int material) {
  glm::vec3 centre(0.0f);
  for (const Quad& q : faces) centre += quadCentre(q);
  centre /= float(faces.size());
  Primitive prim;
  prim.material = material;
  for (const Quad& q : faces) addQuad(prim, q, quadCentre(q) - centre);
  return prim;
}

}  // namespace

Scene makeCornellBox() {
  Scene scene;
  scene.sourcePath = "";

  enum { kWhite, kRed, kGreen, kLight };
  scene.materials.push_back(diffuse("white", {0.725f, 0.71f, 0.68f}));
  scene.materials.push_back(diffuse("red", {0.63f, 0.065f, 0.05f}));
  scene.materials.push_back(diffuse("green", {0.14f, 0.45f, 0.091f}));
  Material light = diffuse("light", glm::vec3(0.78f));  // McGuire's Kd for the lamp
  setEmission(light, {17.0f, 12.0f, 4.0f});
  scene.materials.push_back(light);

  // Walls face the room's centre; the room is 556 × 548.8 × 559.2 mm.
  const glm::vec3 roomCentre = mm({278.0f, 274.4f, 279.6f});
  auto wall = [&](const char* name, const Quad& q, int material) {
    Primitive prim;
    prim.material = material;
    addQuad(prim, q, roomCentre - quadCentre(q));
    addMeshInstance(scene, name, std::move(prim));
  };
  wall("floor",
       quadMm({552.8f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 559.2f},
              {549.6f, 0.0f, 559.2f}),
       kWhite);
  wall("ceiling",
       quadMm({556.0f, 548.8f, 0.0f}, {556.0f, 548.8f, 559.2f}, {0.0f, 548.8f, 559.2f},
              {0.0f, 548.8f, 0.0f}),
       kWhite);
  wall("back_wall",
       quadMm({549.6f, 0.0f, 559.2f}, {0.0f, 0.0f, 559.2f}, {0.0f, 548.8f, 559.2f},
              {556.0f, 548.8f, 559.2f}),
       kWhite);
  // Seen from the camera (looking along +Z with +Y up in a right-handed frame), +X is on the
  // left: the red wall at x ≈ 556 mm is on the left, the green one at x = 0 on the right.
  wall("left_wall",
       quadMm({552.8f, 0.0f, 0.0f}, {549.6f, 0.0f, 559.2f}, {556.0f, 548.8f, 559.2f},
              {556.0f, 548.8f, 0.0f}),
       kRed);
  wall("right_wall",
       quadMm({0.0f, 0.0f, 559.2f}, {0.0f, 0.0f, 0.0f}, {0.0f, 548.8f, 0.0f},
              {0.0f, 548.8f, 559.2f}),
       kGreen);

  addMeshInstance(
      scene, "short_block",
      block({quadMm({130.0f, 165.0f, 65.0f}, {82.0f, 165.0f, 225.0f}, {240.0f, 165.0f, 272.0f},
                    {290.0f, 165.0f, 114.0f}),
             quadMm({290.0f, 0.0f, 114.0f}, {290.0f, 165.0f, 114.0f}, {240.0f, 165.0f, 272.0f},
                    {240.0f, 0.0f, 272.0f}),
             quadMm({130.0f, 0.0f, 65.0f}, {130.0f, 165.0f, 65.0f}, {290.0f, 165.0f, 114.0f},
                    {290.0f, 0.0f, 114.0f}),
             quadMm({82.0f, 0.0f, 225.0f}, {82.0f, 165.0f, 225.0f}, {130.0f, 165.0f, 65.0f},
                    {130.0f, 0.0f, 65.0f}),
             quadMm({240.0f, 0.0f, 272.0f}, {240.0f, 165.0f, 272.0f}, {82.0f, 165.0f, 225.0f},
                    {82.0f, 0.0f, 225.0f})},
            kWhite));
  addMeshInstance(
      scene, "tall_block",
      block({quadMm({423.0f, 330.0f, 247.0f}, {265.0f, 330.0f, 296.0f}, {314.0f, 330.0f, 456.0f},
                    {472.0f, 330.0f, 406.0f}),
             quadMm({423.0f, 0.0f, 247.0f}, {423.0f, 330.0f, 247.0f}, {472.0f, 330.0f, 406.0f},
                    {472.0f, 0.0f, 406.0f}),
             quadMm({472.0f, 0.0f, 406.0f}, {472.0f, 330.0f, 406.0f}, {314.0f, 330.0f, 456.0f},
                    {314.0f, 0.0f, 456.0f}),
             quadMm({314.0f, 0.0f, 456.0f}, {314.0f, 330.0f, 456.0f}, {265.0f, 330.0f, 296.0f},
                    {265.0f, 0.0f, 296.0f}),
             quadMm({265.0f, 0.0f, 296.0f}, {265.0f, 330.0f, 296.0f}, {423.0f, 330.0f, 247.0f},
                    {423.0f, 0.0f, 247.0f})},
            kWhite));

  // The lamp is 130 × 105 mm as published, lowered 1 mm below the ceiling so the two surfaces
  // never overlap (the data page puts both at 548.8 mm, which z-fights and confuses ray casts).
  {
    const float y = 547.8f;
    Primitive prim;
    prim.material = kLight;
    addQuad(prim,
            quadMm({343.0f, y, 227.0f}, {343.0f, y, 332.0f}, {213.0f, y, 332.0f},
                   {213.0f, y, 227.0f}),
            {0.0f, -1.0f, 0.0f});
    addMeshInstance(scene, "light", std::move(prim));
  }

  // The published camera: (278, 273, -800) mm looking along +Z, a 35 mm lens on a 25 × 25 mm
  // film. glTF cameras look down -Z, so the camera is turned half a turn about Y.
  Camera camera;
  camera.name = "Camera";
  camera.perspective = true;
  camera.yfov = 2.0f * std::atan(12.5f / 35.0f);  // 0.6860 rad = 39.31°
  camera.aspectRatio = 1.0f;
  camera.znear = 0.01f;
  camera.zfar = 0.0f;
  camera.transform = glm::mat4(1.0f);
  camera.transform[0] = glm::vec4(-1.0f, 0.0f, 0.0f, 0.0f);
  camera.transform[2] = glm::vec4(0.0f, 0.0f, -1.0f, 0.0f);
  camera.transform[3] = glm::vec4(mm({278.0f, 273.0f, -800.0f}), 1.0f);
  scene.cameras.push_back(camera);
  return scene;
}

Scene makeCornellMetalBox() {
  Scene scene = makeCornellBox();
  // The blocks become metals: a mirror (silver, roughness 0.02) and brushed copper (0.3).
  Material mirror = diffuse("mirror", {0.95f, 0.95f, 0.95f});
  mirror.metallicFactor = 1.0f;
  mirror.roughnessFactor = 0.02f;
  Material copper = diffuse("copper", {0.95f, 0.64f, 0.54f});
  copper.metallicFactor = 1.0f;
  copper.roughnessFactor = 0.3f;
  const int kMirror = int(scene.materials.size()), kCopper = kMirror + 1;
  scene.materials.push_back(mirror);
  scene.materials.push_back(copper);
  for (Instance& inst : scene.instances) {
    Primitive& prim = scene.meshes[size_t(inst.mesh)].primitives[0];
    if (inst.name == "tall_block") prim.material = kMirror;
    if (inst.name == "short_block") prim.material = kCopper;
  }
  // The open side closed by a white wall, so that every reflection shows the room.
  const glm::vec3 roomCentre = mm({278.0f, 274.4f, 279.6f});
  Primitive front;
  front.material = 0;  // white
  const Quad q = quadMm({0.0f, 0.0f, 0.0f}, {556.0f, 0.0f, 0.0f}, {556.0f, 548.8f, 0.0f},
                        {0.0f, 548.8f, 0.0f});
  addQuad(front, q, roomCentre - quadCentre(q));
  addMeshInstance(scene, "front_wall", std::move(front));
  // One reflection probe filling the room, and the camera moved inside, by the front wall. Its
  // box projects onto the walls, and its influence reaches the blend distance beyond them, so
  // everything in the room, the walls included, takes its full weight.
  ReflectionProbe probe;
  probe.name = "room_probe";
  probe.transform[3] = glm::vec4(roomCentre, 1.0f);
  probe.projectionSize = mm({556.0f, 548.8f, 559.2f});
  probe.blendDistance = 0.1f;
  probe.size = probe.projectionSize + glm::vec3(2.0f * probe.blendDistance);
  scene.reflectionProbes.push_back(probe);
  Camera& camera = scene.cameras.front();
  camera.transform[3] = glm::vec4(mm({278.0f, 273.0f, 20.0f}), 1.0f);
  camera.yfov = 1.2f;
  camera.aspectRatio = 0.0f;
  return scene;
}

Scene makeFurnaceBox(const FurnaceOptions& options) {
  AG_CHECK(options.size > 0.0f, "furnace box size must be positive");
  AG_CHECK(options.subdivisions >= 1, "furnace box needs at least one quad per edge");
  const int n = options.subdivisions;
  const float h = 0.5f * options.size;

  Scene scene;
  scene.sourcePath = "";
  Material m = diffuse("furnace", options.albedo);
  setEmission(m, options.emission);
  scene.materials.push_back(m);

  Primitive prim;
  prim.material = 0;
  // Each face is a grid spanned by two axes u, v around the outward axis; the grid vertices are
  // shared inside a face and duplicated along the cube's edges, where the normal changes.
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = -1; side <= 1; side += 2) {
      glm::vec3 outward(0.0f);
      outward[axis] = float(side);
      glm::vec3 u(0.0f), v(0.0f);
      u[(axis + 1) % 3] = 1.0f;
      v[(axis + 2) % 3] = 1.0f;
      const glm::vec3 inward = -outward;
      // Counter-clockwise seen from inside: (u, v, inward) must be right-handed.
      if (glm::dot(glm::cross(u, v), inward) < 0.0f) std::swap(u, v);
      const uint32_t base = uint32_t(prim.positions.size());
      for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
          const float s = -h + options.size * float(i) / float(n);
          const float t = -h + options.size * float(j) / float(n);
          prim.positions.push_back(outward * h + u * s + v * t);
          prim.normals.push_back(inward);
        }
      }
      const uint32_t row = uint32_t(n + 1);
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          const uint32_t a = base + uint32_t(j) * row + uint32_t(i);
          const uint32_t b = a + 1, c = a + row + 1, d = a + row;
          for (uint32_t k : {a, b, c, a, c, d}) prim.indices.push_back(k);
        }
      }
    }
  }
  addMeshInstance(scene, "furnace_box", std::move(prim));

  Camera camera;
  camera.name = "Camera";
  camera.yfov = 1.5707963f;  // 90°: the box's centre sees one whole face
  camera.aspectRatio = 1.0f;
  camera.znear = 0.001f * options.size;
  scene.cameras.push_back(camera);
  return scene;
}

}  // namespace afterglow::scenes
