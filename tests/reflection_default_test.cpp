// Reflection probes by default (issue 28): a default bake proposes them where the level authors
// none, their boxes reaching past the walls so that every metal surface of a room takes the
// probes' full weight (the runtime's own blend weights, read at every lightmapped texel of the
// metal), and none sits inside an object (probes_inside_test.cpp).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "afterglow/bakefiles/pipeline.h"
#include "afterglow/runtime/reflection_probes.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"
#include "afterglow/scenes/units.h"
#include "test_util.h"

namespace afterglow::bakefiles {
namespace {

struct MetalCover {
  size_t texels = 0;    // lightmapped texels of metal surfaces
  size_t partial = 0;   // of which the sky takes some weight
  float lowest = 1.0f;  // the least weight the boxes give one
  size_t probes = 0;    // reflection probes baked
};

// A default bake of `scene` (the pipeline as `afterglow bake` runs it) and, at every valid texel
// of a material with metallicFactor > 0, the weight the reflection probes' boxes take (1 − the
// sky's, runtime::reflectionProbesAt).
MetalCover defaultBakeMetalCover(scenes::Scene scene) {
  BakeJob job;
  job.input = "test";
  job.bake.links.texelRays = 32;  // the weights depend on the boxes alone
  Result<BakedLevel> level = bakeLevel(scene, job);
  EXPECT_TRUE(level) << level.message();
  MetalCover out;
  if (!level) return out;
  const baker::BakeResult& r = level->result;
  std::vector<runtime::ReflectionProbeBox> boxes;
  for (const runtime::ReflectionProbeCapture& p : r.transport.reflections.probes)
    boxes.push_back(p.box);
  out.probes = boxes.size();
  const baker::TexelSet& texels = r.texels;
  for (uint32_t t = 0; t < texels.size(); ++t) {
    if (!texels.valid[t]) continue;
    const scenes::Instance& inst = scene.instances[texels.instance[t]];
    const int material = scene.meshes[size_t(inst.mesh)].primitives[texels.primitive[t]].material;
    if (!(scene.material(material).metallicFactor > 0.0f)) continue;
    ++out.texels;
    float boxes_weight = 0.0f;
    for (const runtime::ProbeWeight& w : runtime::reflectionProbesAt(boxes, texels.position[t]))
      if (w.probe > 0) boxes_weight += w.weight;
    if (boxes_weight < 1.0f - 1e-6f) ++out.partial;
    out.lowest = std::min(out.lowest, boxes_weight);
  }
  return out;
}

TEST(ReflectionProbesByDefault, TheMetalCornellBoxsMetalTakesTheProbesFullWeight) {
  const MetalCover c = defaultBakeMetalCover(scenes::makeCornellMetalBox());
  std::printf("builtin:cornell-metal: %zu reflection probe(s); %zu metal texels, %zu with less than "
              "the probes' full weight (lowest %.6f)\n",
              c.probes, c.texels, c.partial, double(c.lowest));
  ASSERT_GT(c.texels, 1000u);
  EXPECT_EQ(c.partial, 0u);
}

// Bevy's Cornell box (in millimetres: scaled to metres), its red wall made a rough metal, has no
// reflection probe of its own: the bake proposes one, and the metal wall takes its full weight.
TEST(ReflectionProbesByDefault, BevysCornellBoxWithAMetalWallGetsAProbeCoveringIt) {
  AG_REQUIRE_SHARED_SCENE(path, "cornell_box_bevy/CornellBox.glb");
  Result<scenes::Scene> loaded = scenes::loadGltf(path);
  ASSERT_TRUE(loaded) << loaded.message();
  scenes::Scene scene = std::move(loaded.value());
  scenes::scaleScene(scene, 0.001f);
  bool found = false;
  for (scenes::Material& m : scene.materials)
    if (m.name == "cbox.red.002") {
      m.metallicFactor = 1.0f;
      m.roughnessFactor = 0.3f;
      found = true;
    }
  ASSERT_TRUE(found);
  ASSERT_TRUE(scene.reflectionProbes.empty());
  const MetalCover c = defaultBakeMetalCover(std::move(scene));
  std::printf("Bevy's Cornell box, red wall metal: %zu reflection probe(s) proposed; %zu metal "
              "texels, %zu with less than the probes' full weight (lowest %.6f)\n",
              c.probes, c.texels, c.partial, double(c.lowest));
  EXPECT_GE(c.probes, 1u);
  ASSERT_GT(c.texels, 1000u);
  EXPECT_EQ(c.partial, 0u);
}

}  // namespace
}  // namespace afterglow::bakefiles
