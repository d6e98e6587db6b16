// Writes the transport fuzzer's seed corpus: a few small synthetic transports serialised by the
// current writer, so the seeds always match the current format (no binary blobs in the repo).
//   transport_seeds OUT_DIR
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "afterglow/runtime/transport_file.h"

using namespace afterglow::runtime;

namespace {

// Two atlases with mixes, two materials, a light and an emissive source, links with a back-side
// row, the three sparse maps and the sky transfer: every section non-empty.
TransportData small(bool withSky, bool withFilter) {
  TransportData d;
  d.texelCount = 6;
  d.clusterCount = 3;
  d.gatherPointCount = 2;
  AtlasLayout a;
  a.width = 3;
  a.height = 2;
  a.texelOfPixel = {0, 1, kNoTexel, 2, 3, kNoTexel};
  a.mixPixel = {2, 5};
  a.mixStart = {0, 2, 3};
  a.mixTexel = {1, 3, 3};
  a.mixWeight = {0.5f, 0.5f, 1.0f};
  d.atlases.push_back(a);
  AtlasLayout b;
  b.width = 2;
  b.height = 1;
  b.texelOfPixel = {4, 5};
  d.atlases.push_back(b);
  d.materials.push_back({"wall", glm::vec3(0.7f), glm::vec3(0.0f)});
  d.materials.push_back({"lamp", glm::vec3(0.8f), glm::vec3(5.0f)});
  Source light;
  light.name = "sun";
  light.color = glm::vec3(1.0f, 0.9f, 0.8f);
  light.intensity = 3.0f;
  light.texelTransfer.assign(d.texelCount, 0.25f);
  light.clusterTransfer.assign(d.clusterCount, 0.5f);
  d.sources.push_back(light);
  Source lamp;
  lamp.name = "lamp";
  lamp.kind = SourceKind::Emissive;
  lamp.material = 1;
  lamp.enabled = false;
  lamp.clusterTransfer.assign(d.clusterCount, 0.125f);
  d.sources.push_back(lamp);
  d.clusterMaterial = {0, 0, 1};
  d.clusterAlbedoTexture.assign(3, glm::vec3(1.0f));
  d.clusterEmissionTexture.assign(3, glm::vec3(0.5f));
  const uint32_t targets[] = {0, 1, 2, 3};  // 3: the far cluster over clusters 0 and 1
  const float weights[] = {0.2f, 0.3f, 0.1f, 0.1f};
  const float half[] = {0.5f, 0.5f};
  d.farClusters.appendRow(targets, half, 2);
  d.links.appendRow(targets, weights, 4);
  d.links.appendRow(targets + 1, weights + 1, 2);
  d.links.appendRow(targets, weights, 1);  // a back-side cluster's row
  const uint32_t rowsOf[] = {0, 1, 2};
  const float one[] = {1.0f};
  d.clusterGather.appendRow(rowsOf, half, 2);
  d.clusterGather.appendRow(rowsOf + 1, one, 1);
  d.clusterGather.appendRow(rowsOf + 2, one, 1);
  d.filterPasses = withFilter ? 2 : 0;
  for (uint32_t t = 0; t < d.texelCount; ++t) {
    d.texelPoint.push_back(t % 2);
    d.texelNeighbours.push_back(0xff);
  }
  buildGatherMaps(d);
  if (withSky) {
    for (uint32_t i = 0; i < d.texelCount * kShCount; ++i)
      d.texelSky.push_back(floatToHalf(0.1f * float(i % 7)));
    d.clusterSky.assign(d.clusterCount * kShCount, floatToHalf(0.25f));
    d.skySh[0] = glm::vec3(1.0f, 1.5f, 2.0f);
  }
  d.indirectIntensity = 1.5f;
  d.albedoBoost = 1.25f;
  return d;
}

// small() with one reflection probe of 1×1 texel faces: a miss, a lightmapped hit and so on.
TransportData withReflections() {
  TransportData d = small(true, true);
  ReflectionTransport& r = d.reflections;
  for (const MaterialParams& m : d.materials) r.bakedAlbedo.push_back(m.albedo);
  ReflectionProbeCapture c;
  c.name = "hall";
  c.resolution = 1;
  c.box.halfSize = glm::vec3(2.0f, 1.0f, 3.0f);
  r.probes.push_back(c);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    ReflectionHit h;
    if (face > 0) {
      h.material = uint32_t(face % 2);
      h.atlas = face == 5 ? kReflectionNoAtlas : uint16_t(face % 2);
      h.lightmapUv = glm::vec2(0.25f, 0.75f);
      h.roughness = floatToHalf(0.5f);
      for (int k = 0; k < 3; ++k) {
        h.diffuse[k] = h.emission[k] = h.f0[k] = floatToHalf(0.5f);
        h.normal[k] = floatToHalf(k == 1 ? 1.0f : 0.0f);
      }
      h.distance = 1.5f;
    }
    r.hits.push_back(h);
  }
  return d;
}

// withReflections() at two resolutions (lightmap_layers.h): its 6 texels become an indirect grid
// under 5 lightmap texels in a 2x2 atlas and a 2x1 one with a mix; the sun's direct light is in
// the layers (its texel transfer goes), the lamp has none.
TransportData layered() {
  TransportData d = withReflections();
  d.sources[0].texelTransfer.clear();
  LightmapLayers& l = d.lightmap;
  l.texelCount = 5;
  AtlasLayout a;
  a.width = 2;
  a.height = 2;
  a.texelOfPixel = {0, 1, 2, 3};
  l.atlases.push_back(a);
  AtlasLayout b;
  b.width = 2;
  b.height = 1;
  b.texelOfPixel = {4, kNoTexel};
  b.mixPixel = {1};
  b.mixStart = {0, 2};
  b.mixTexel = {3, 4};
  b.mixWeight = {0.5f, 0.5f};
  l.atlases.push_back(b);
  // Corners in the 3x2 indirect atlas (one on an empty pixel, renormalised away; on its top row
  // the lower two alone) and in the 2x1 one; the last with no corner that counts.
  l.corners = {{0, 0, 0, 0x00, 0xf, 0},
               {1, 0, 0, 0x88, 0xf, 0},
               {0, 1, 0, 0x4c, 0x3, 0},
               {0, 0, 1, 0x08, 0x3, 0},
               {0, 0, 0, 0x00, 0x0, 0}};
  l.direct.resize(d.sources.size());
  l.directScale.assign(d.sources.size(), 0.0f);
  l.directScale[0] = encodeDirectLayer({0.25f, 1.0f, 0.5f, 3.0f, 0.0f}, l.direct[0]);
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: transport_seeds OUT_DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  const std::vector<std::pair<std::string, TransportData>> seeds = {
      {"empty.agt", TransportData{}},
      {"small.agt", small(true, true)},
      {"no-sky.agt", small(false, true)},
      {"no-filter.agt", small(true, false)},
      {"reflections.agt", withReflections()},
      {"layers.agt", layered()},
  };
  for (const auto& [name, data] : seeds) {
    std::string error;
    if (!saveTransport(data, dir + "/" + name, &error)) {
      std::fprintf(stderr, "transport_seeds: %s\n", error.c_str());
      return 1;
    }
  }
  std::printf("transport_seeds: wrote %zu seeds to %s\n", seeds.size(), dir.c_str());
  return 0;
}
