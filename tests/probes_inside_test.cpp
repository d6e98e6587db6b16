// No light or reflection probe inside an object, judged apart from the placement's own ray test:
// by the generalised winding number of every shell (triangles joined by shared edges) of every
// static instance around every probe, w = Σ solid angle / 4π over the shell's triangles (Van
// Oosterom and Strackee's formula), whatever the surfaces' sidedness. w is 1 inside a closed
// shell facing out (a solid box), about 1 inside a block open only where it stands on the floor,
// never above one half for an open sheet (a curtain, a leaf), and negative inside a room whose
// walls face in. A shell that winds more than half around another shell's centre is a room,
// however its faces are wound (a double-sided shop around its table; Sponza's outer walls around
// its halls); one around nothing is an object, and a probe is inside an object where the object
// winds around it more than half.
// And DDGI's and Unity's validity on Sponza: a probe is invalid when more than a quarter of 256
// rays (a spherical Fibonacci set of this file's own) first hit the backs of single-sided
// surfaces.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "afterglow/baker/bake.h"
#include "afterglow/baker/reference.h"
#include "afterglow/core/math.h"
#include "afterglow/core/parallel.h"
#include "afterglow/probes/placement.h"
#include "afterglow/probes/reflection_placement.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/runtime/probe_lights.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/probe_visibility.h"
#include "afterglow/scenes/units.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/trace/raytracer.h"
#include "bake_fixtures.h"
#include "runtime/test_rng.h"
#include "test_util.h"

namespace afterglow::probes {
namespace {

using Triangle = std::array<glm::dvec3, 3>;

struct Shell {
  std::string name;  // instance name and shell index, for messages
  bool closed = true;         // every edge shared by two of its triangles
  bool doubleSided = false;   // any of its triangles
  std::vector<Triangle> triangles;  // world space, as wound
  glm::dvec3 lo{1e300}, hi{-1e300};
};

// Shells of one primitive list: corners joined where their positions are equal, triangles joined
// where they share two corners. *open lists the triangles with an edge no other triangle has.
std::vector<std::vector<size_t>> shellsOf(const std::vector<Triangle>& triangles,
                                          std::vector<uint8_t>* open) {
  std::map<std::array<double, 3>, size_t> corner;
  std::vector<std::array<size_t, 3>> ids(triangles.size());
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 p = triangles[t][size_t(k)];
      ids[t][size_t(k)] = corner.emplace(std::array<double, 3>{p.x, p.y, p.z}, corner.size())
                              .first->second;
    }
  std::vector<size_t> parent(triangles.size());
  std::iota(parent.begin(), parent.end(), size_t(0));
  auto find = [&](size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::map<std::pair<size_t, size_t>, std::vector<size_t>> edge;
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      size_t a = ids[t][size_t(k)], b = ids[t][size_t((k + 1) % 3)];
      if (a == b) continue;
      if (a > b) std::swap(a, b);
      std::vector<size_t>& owners = edge[std::make_pair(a, b)];
      if (!owners.empty()) parent[find(t)] = find(owners.front());
      owners.push_back(t);
    }
  open->assign(triangles.size(), 0);
  for (const auto& [key, owners] : edge)
    if (owners.size() != 2)
      for (size_t t : owners) (*open)[t] = 1;
  std::map<size_t, std::vector<size_t>> groups;
  for (size_t t = 0; t < triangles.size(); ++t) groups[find(t)].push_back(t);
  std::vector<std::vector<size_t>> out;
  for (auto& [root, members] : groups) out.push_back(std::move(members));
  return out;
}

double windingNumber(const Shell& shell, glm::dvec3 p);
std::vector<glm::vec3> fibonacci256();

// Every static instance's objects: its shells that hold no other shell's centre, closed ones (a
// column) and double-sided ones (a block open where it stands on the floor: its sidedness hides
// its inside from the placement's rays). An open single-sided shell winds around space it does
// not enclose (Sponza's vaults around the air above them) and is judged by its backs instead
// (the validity test below).
std::vector<Shell> objectShells(const scenes::Scene& scene) {
  std::vector<Shell> out;
  for (const scenes::Instance& inst : scene.instances) {
    if (!inst.isStatic || inst.mesh < 0 || size_t(inst.mesh) >= scene.meshes.size()) continue;
    std::vector<Triangle> world;
    std::vector<uint8_t> doubleSided;
    const scenes::Mesh& mesh = scene.meshes[size_t(inst.mesh)];
    scenes::forEachWorldTriangle(scene, inst, [&](size_t p, size_t, glm::vec3 a, glm::vec3 b,
                                                  glm::vec3 c) {
      world.push_back({glm::dvec3(a), glm::dvec3(b), glm::dvec3(c)});
      doubleSided.push_back(scene.material(mesh.primitives[p].material).doubleSided);
    });
    // A mirrored transform turns the winding: glTF then takes clockwise as the front.
    const bool mirrored = glm::determinant(glm::mat3(inst.transform)) < 0.0f;
    std::vector<uint8_t> open;
    const std::vector<std::vector<size_t>> shells = shellsOf(world, &open);
    for (size_t s = 0; s < shells.size(); ++s) {
      Shell shell;
      shell.name = inst.name + " shell " + std::to_string(s);
      for (size_t t : shells[s]) {
        shell.closed = shell.closed && !open[t];
        shell.doubleSided = shell.doubleSided || doubleSided[t];
        Triangle tri = world[t];
        if (mirrored) std::swap(tri[1], tri[2]);
        shell.triangles.push_back(tri);
        for (const glm::dvec3& c : tri) {
          shell.lo = glm::min(shell.lo, c);
          shell.hi = glm::max(shell.hi, c);
        }
      }
      out.push_back(std::move(shell));
    }
  }
  std::vector<uint8_t> room(out.size(), 0);
  parallelFor(out.size(), [&](size_t a) {
    for (size_t b = 0; b < out.size() && !room[a]; ++b) {
      if (b == a || glm::any(glm::lessThan(out[b].lo, out[a].lo)) ||
          glm::any(glm::greaterThan(out[b].hi, out[a].hi)))
        continue;
      room[a] = windingNumber(out[a], 0.5 * (out[b].lo + out[b].hi)) > 0.5;
    }
  }, 4);
  std::vector<Shell> objects;
  for (size_t a = 0; a < out.size(); ++a)
    if (!room[a] && (out[a].closed || out[a].doubleSided)) objects.push_back(std::move(out[a]));
  return objects;
}

// The generalised winding number of a shell around p: Σ Ω / 4π, Ω each triangle's signed solid
// angle, positive where p sees its back (inside a closed shell facing out).
double windingNumber(const Shell& shell, glm::dvec3 p) {
  double sum = 0.0;
  for (const Triangle& t : shell.triangles) {
    const glm::dvec3 a = t[0] - p, b = t[1] - p, c = t[2] - p;
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double det = glm::dot(a, glm::cross(b, c));
    const double div = la * lb * lc + glm::dot(a, b) * lc + glm::dot(b, c) * la + glm::dot(c, a) * lb;
    sum += 2.0 * std::atan2(det, div);
  }
  return sum / (4.0 * kPiDouble);
}

struct Inside {
  size_t count = 0;
  std::string first;  // the first one found, for the message
};

Inside probesInside(const std::vector<Shell>& shells, const std::vector<glm::vec3>& probes) {
  std::vector<int> shellOf(probes.size(), -1);
  parallelFor(probes.size(), [&](size_t i) {
    const glm::dvec3 p(probes[i]);
    for (size_t s = 0; s < shells.size(); ++s) {
      const Shell& shell = shells[s];
      if (glm::any(glm::lessThan(p, shell.lo)) || glm::any(glm::greaterThan(p, shell.hi))) continue;
      if (windingNumber(shell, p) > 0.5) {
        shellOf[i] = int(s);
        return;
      }
    }
  }, 16);
  Inside out;
  for (size_t i = 0; i < probes.size(); ++i) {
    if (shellOf[i] < 0) continue;
    if (out.count++ == 0)
      out.first = format("probe %zu at (%g, %g, %g) inside %s", i, double(probes[i].x),
                         double(probes[i].y), double(probes[i].z),
                         shells[size_t(shellOf[i])].name.c_str());
  }
  return out;
}

struct SharedCase {
  const char* file;
  const char* name;
};
void PrintTo(const SharedCase& c, std::ostream* os) { *os << c.name; }
class ProbesInsideObjects : public ::testing::TestWithParam<SharedCase> {};

// Every shared scene: the default light probes and reflection probe proposals, none inside an
// object.
TEST_P(ProbesInsideObjects, NoLightOrReflectionProbeInsideAnObject) {
  AG_REQUIRE_SHARED_SCENE(path, GetParam().file);
  scenes::LoadOptions load;
  load.loadTextures = false;
  Result<scenes::Scene> scene = scenes::loadGltf(path, load);
  ASSERT_TRUE(scene) << scene.message();
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(*scene);
  ASSERT_TRUE(tracer) << tracer.message();
  Result<Placement> light = placeProbes(*scene, *tracer.value());
  ASSERT_TRUE(light) << light.message();
  Result<ReflectionPlacement> reflection = placeReflectionProbes(*scene, *tracer.value());
  ASSERT_TRUE(reflection) << reflection.message();
  std::vector<glm::vec3> captures;
  for (const ReflectionProbeEntry& r : reflection->probes) captures.push_back(r.position);

  const std::vector<Shell> shells = objectShells(*scene);
  const Inside lightInside = probesInside(shells, light->positions);
  const Inside reflectionInside = probesInside(shells, captures);
  std::printf("%s: %zu objects; %zu of %zu light probes and %zu of %zu reflection probes "
              "inside an object%s%s\n",
              GetParam().name, shells.size(), lightInside.count, light->positions.size(),
              reflectionInside.count, captures.size(),
              lightInside.count ? (": " + lightInside.first).c_str() : "",
              reflectionInside.count ? (": " + reflectionInside.first).c_str() : "");
  EXPECT_EQ(lightInside.count, 0u) << lightInside.first;
  EXPECT_EQ(reflectionInside.count, 0u) << reflectionInside.first;
}

INSTANTIATE_TEST_SUITE_P(
    Shared, ProbesInsideObjects,
    ::testing::Values(SharedCase{"cornell_box_mcguire/CornellBox-Original.gltf", "McGuireCornell"},
                      SharedCase{"cornell_box_bevy/CornellBox.glb", "BevyCornell"},
                      SharedCase{"mixed_lighting_bevy/MixedLightingExample.gltf", "MixedLighting"},
                      SharedCase{"gas_station/GasStation.gltf", "GasStation"},
                      SharedCase{"sponza/Sponza.gltf", "Sponza"}),
    [](const ::testing::TestParamInfo<SharedCase>& info) { return std::string(info.param.name); });

// 256 directions of a spherical Fibonacci set (this file's own, not the placement's).
std::vector<glm::vec3> fibonacci256() {
  std::vector<glm::vec3> out;
  const double golden = kPiDouble * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < 256; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / 256.0, r = std::sqrt(1.0 - z * z);
    out.emplace_back(float(r * std::cos(golden * i)), float(z), float(r * std::sin(golden * i)));
  }
  return out;
}

// Sponza by DDGI's and Unity's rule: at most 1% of the default probes see the backs of
// single-sided surfaces first along more than a quarter of 256 rays (8.6% did when half was the
// placement's bar: above the aisles' roofs and behind the outer walls, where interpolation carries
// the outside's light through the walls).
TEST(ProbesValidity, SponzaAtMostOnePercentFailTheBackFaceRule) {
  AG_REQUIRE_SHARED_SCENE(path, "sponza/Sponza.gltf");
  scenes::LoadOptions load;
  load.loadTextures = false;
  Result<scenes::Scene> scene = scenes::loadGltf(path, load);
  ASSERT_TRUE(scene) << scene.message();
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(*scene);
  ASSERT_TRUE(tracer) << tracer.message();
  Result<Placement> placed = placeProbes(*scene, *tracer.value());
  ASSERT_TRUE(placed) << placed.message();
  const std::vector<glm::vec3> directions = fibonacci256();
  std::vector<uint8_t> invalid(placed->positions.size(), 0);
  parallelFor(placed->positions.size(), [&](size_t i) {
    std::vector<trace::Ray> rays(directions.size());
    std::vector<trace::Hit> hits(directions.size());
    for (size_t k = 0; k < rays.size(); ++k) {
      rays[k].origin = placed->positions[i];
      rays[k].direction = directions[k];
    }
    tracer.value()->intersect(rays.data(), hits.data(), rays.size());
    size_t back = 0;
    for (const trace::Hit& h : hits)
      back += h.valid() && !h.frontFace && !tracer.value()->material(h).doubleSided;
    invalid[i] = back * 4 > directions.size();
  }, 64);
  const size_t count = std::accumulate(invalid.begin(), invalid.end(), size_t(0));
  std::printf("Sponza: %zu of %zu default probes (%.2f%%) fail the 25%% back-face rule over 256 "
              "Fibonacci rays\n",
              count, placed->positions.size(),
              100.0 * double(count) / double(placed->positions.size()));
  EXPECT_LE(count * 100, placed->positions.size());
}

// A shared Cornell box baked with its default light probes, the probes sampled at points 2 to
// 10 cm outside its blocks (on their sides and tops, along the faces' normals) for the six axis
// normals, against the reference path tracer's irradiance at the same points: relative RMSE
// (each value's error relative to its own reference, floored at a tenth of the mean) at most 15%,
// and no value below half its reference (a probe inside a block once read 16-29% dark beside it).
// How values agree with a reference per (point, normal), as baker::compareToReference weighs
// texels: each error relative to its own reference (RGB summed), floored at a tenth of the
// reference's mean; and the lowest ratio among references above the floor.
struct Agreement {
  double rmse = 0.0, lowest = 1e30;
  std::string lowestWhere;
};
Agreement agreement(const std::vector<glm::vec3>& values, const std::vector<glm::vec3>& reference,
                    const std::vector<glm::vec3>& at, const std::vector<glm::vec3>& normals) {
  auto sum = [](glm::vec3 v) { return double(v.x) + double(v.y) + double(v.z); };
  double mean = 0.0;
  for (const glm::vec3& r : reference) mean += sum(r) / double(reference.size());
  const double floor = 0.1 * mean;
  Agreement a;
  double e2 = 0.0;
  for (size_t i = 0; i < values.size(); ++i) {
    const double r = sum(reference[i]), b = sum(values[i]);
    e2 += (b - r) * (b - r) / (std::max(r, floor) * std::max(r, floor));
    if (r > floor && b / r < a.lowest) {
      a.lowest = b / r;
      a.lowestWhere = format("(%.3f, %.3f, %.3f) normal (%g, %g, %g)", double(at[i].x),
                             double(at[i].y), double(at[i].z), double(normals[i].x),
                             double(normals[i].y), double(normals[i].z));
    }
  }
  a.rmse = std::sqrt(e2 / double(values.size()));
  return a;
}

struct BesideBlocks {
  Agreement probes;        // against the reference's radiance projected onto SH L2 at the points
  Agreement irradiance;    // against the reference's irradiance
  Agreement shFloor;       // that SH L2 itself against the irradiance
  Agreement withDirections;  // the probes with their small sources' directions, against it
};
void probesBesideBlocks(const std::string& path, float unitScale, const char* name,
                        BesideBlocks* out) {
  scenes::LoadOptions load;
  load.loadTextures = false;
  Result<scenes::Scene> loaded = scenes::loadGltf(path, load);
  ASSERT_TRUE(loaded) << loaded.message();
  scenes::Scene& scene = loaded.value();
  if (unitScale != 1.0f) scenes::scaleScene(scene, unitScale);
  ASSERT_GT(baker::unwrapIntoAtlas(scene, 256), 0u);
  Result<std::unique_ptr<trace::RayTracer>> tracer = trace::RayTracer::build(scene);
  ASSERT_TRUE(tracer) << tracer.message();
  Result<Placement> placed = placeProbes(scene, *tracer.value());
  ASSERT_TRUE(placed) << placed.message();
  Result<runtime::ProbeTetrahedra> mesh = tetrahedralize(placed->positions);
  ASSERT_TRUE(mesh) << mesh.message();
  baker::BakeOptions options = baker::draftOptions();
  options.links.texelRays = 128;
  options.probes = mesh.value();
  const baker::BakeResult baked = baker::bakeOrDie(scene, options);
  ASSERT_EQ(baked.probeSh.size(), placed->positions.size());

  // The blocks: the two largest objects.
  std::vector<Shell> objects = objectShells(scene);
  std::sort(objects.begin(), objects.end(), [](const Shell& a, const Shell& b) {
    const glm::dvec3 ea = a.hi - a.lo, eb = b.hi - b.lo;
    return ea.x * ea.y * ea.z > eb.x * eb.y * eb.z;
  });
  ASSERT_GE(objects.size(), 2u);
  objects.resize(2);

  // 40 points: a block's side or top triangle picked by area, a point on it, then out along its
  // normal (away from the block: its winding number there below one half).
  runtime::test::Rng rng{28};
  std::vector<glm::vec3> points;
  for (int tries = 0; points.size() < 40 && tries < 10000; ++tries) {
    const Shell& block = objects[points.size() % 2];
    double total = 0.0;
    for (const Triangle& t : block.triangles) total += glm::length(glm::cross(t[1] - t[0], t[2] - t[0]));
    double pick = rng.unit() * total;
    const Triangle* tri = &block.triangles.back();
    for (const Triangle& t : block.triangles)
      if ((pick -= glm::length(glm::cross(t[1] - t[0], t[2] - t[0]))) <= 0.0) {
        tri = &t;
        break;
      }
    glm::dvec3 n = glm::normalize(glm::cross((*tri)[1] - (*tri)[0], (*tri)[2] - (*tri)[0]));
    double u = rng.unit(), v = rng.unit();
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    const glm::dvec3 on = (*tri)[0] + u * ((*tri)[1] - (*tri)[0]) + v * ((*tri)[2] - (*tri)[0]);
    if (windingNumber(block, on + 0.01 * n) > 0.5) n = -n;
    if (n.y < -0.5) continue;  // the bottom, on the floor
    const glm::dvec3 p = on + (0.02 + 0.08 * rng.unit()) * n;
    bool free = true;
    for (const Shell& o : objects) free = free && windingNumber(o, p) < 0.5;
    // In the open: no other surface within 2 cm (a block stands 3 mm from a wall in Bevy's box,
    // a pocket no light reaches).
    for (const glm::vec3& d : fibonacci256()) {
      trace::Ray ray;
      ray.origin = glm::vec3(p);
      ray.direction = d;
      ray.tfar = 0.02f;
      free = free && !tracer.value()->occluded(ray);
    }
    if (free) points.emplace_back(p);
  }
  ASSERT_EQ(points.size(), 40u);

  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  // The probes' lights as the runtime and the bake folder have them (probe_lights.h), weighed
  // by visibility as the runtime weighs them (probe_visibility.h).
  const runtime::ProbeDirectionList directions =
      runtime::probeLights(baked.transport, runtime::directScales(baked.transport));
  ASSERT_EQ(directions.count(), placed->positions.size());
  std::vector<glm::vec3> at, normals, probe, withDirections;
  int hint = 0;
  for (const glm::vec3& p : points) {
    const runtime::ProbeLocation where = runtime::weighByVisibility(
        runtime::locateProbe(mesh.value(), p, hint), baked.transport.probes, p);
    hint = std::max(where.tetrahedron, 0);
    const runtime::ProbeLighting lighting = runtime::mixProbeLighting(where, baked.probeSh, directions);
    for (const glm::vec3& n : axes) {
      at.push_back(p);
      normals.push_back(n);
      probe.push_back(runtime::irradianceOverPi(lighting.sh, n));
      withDirections.push_back(lighting.irradianceOverPi(n));
    }
  }
  // The reference: its irradiance at the points (16,384 paths: at 4,096 its own noise adds
  // about 3% to McGuire's figure), and its radiance projected onto SH L2 there (what a perfect
  // SH probe at the point would hold: SH L2's own error against the irradiance).
  baker::ReferenceOptions ro;
  ro.samples = 16384;
  Result<baker::ReferencePoints> irradiance =
      baker::referenceIrradiance(scene, *tracer.value(), baker::Environment(), at, normals, ro);
  ASSERT_TRUE(irradiance) << irradiance.message();
  ro.samples = 4096;
  Result<std::vector<runtime::ShL2>> radiance =
      baker::referenceRadianceSh(scene, *tracer.value(), baker::Environment(), points, ro);
  ASSERT_TRUE(radiance) << radiance.message();
  std::vector<glm::vec3> perfect, exact = irradiance->irradiance;
  for (size_t i = 0; i < at.size(); ++i)
    perfect.push_back(runtime::irradianceOverPi((*radiance)[i / 6], normals[i]));
  const Agreement probes = agreement(probe, perfect, at, normals);
  const Agreement vsIrradiance = agreement(probe, exact, at, normals);
  const Agreement floor = agreement(perfect, exact, at, normals);
  const Agreement lit = agreement(withDirections, exact, at, normals);
  std::printf("%s: light probes 2-10 cm beside the blocks, 40 points x 6 normals: against the "
              "reference's SH L2 there relative RMSE %.1f%%, lowest %.0f%% (%s); against its "
              "irradiance %.1f%%, lowest %.0f%%, where SH L2 itself gives %.1f%%, lowest %.0f%%; "
              "with the small sources' directions (probe_lights.h) %.1f%%, lowest %.0f%% (%s)\n",
              name, 100.0 * probes.rmse, 100.0 * probes.lowest, probes.lowestWhere.c_str(),
              100.0 * vsIrradiance.rmse, 100.0 * vsIrradiance.lowest, 100.0 * floor.rmse,
              100.0 * floor.lowest, 100.0 * lit.rmse, 100.0 * lit.lowest, lit.lowestWhere.c_str());
  *out = BesideBlocks{probes, vsIrradiance, floor, lit};
}

// Both Cornell boxes of ../shared/scenes: file, the scale to metres, and a name.
const std::tuple<const char*, float, const char*> kCornellBoxes[] = {
    {"cornell_box_mcguire/CornellBox-Original.gltf", 1.0f, "McGuire's Cornell box"},
    {"cornell_box_bevy/CornellBox.glb", 0.001f,
     "Bevy's Cornell box (millimetres, scaled to metres)"}};

// Issue 28's target: at 40 points 2-10 cm beside the blocks of both Cornell boxes, probe E/π
// for the six axis normals within 15% RMS of the reference's irradiance and none below half of
// it. SH L2 alone cannot: its ringing around the small lamp puts it 17-23% off (lowest 30-45%)
// even when read from the reference's own radiance at the point; the lamp kept as a direction
// (probe_lights.h) takes that away. Also, the SH alone never fall below half of what a
// perfect SH probe there holds: probes inside the blocks once took a share of their darkness.
TEST(ProbesBesideObjects, WithinFifteenPercentOfTheReferenceIrradiance) {
  for (const auto& [file, scale, name] : kCornellBoxes) {
    AG_REQUIRE_SHARED_SCENE(path, file);
    BesideBlocks r;
    probesBesideBlocks(path, scale, name, &r);
    EXPECT_LE(r.withDirections.rmse, 0.15) << name;
    EXPECT_GE(r.withDirections.lowest, 0.5) << name << " at " << r.withDirections.lowestWhere;
    EXPECT_GE(r.probes.lowest, 0.5) << name << " at " << r.probes.lowestWhere;
  }
}

}  // namespace
}  // namespace afterglow::probes
