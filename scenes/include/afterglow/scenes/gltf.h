// glTF 2.0 import and export (.gltf and .glb).
#pragma once

#include <string>

#include "afterglow/core/status.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::scenes {

struct LoadOptions {
  bool loadTextures = true;  // false skips image decoding (faster `info`, UV-only work)
  // Decodes normal textures too (`afterglow render` with directional lightmaps); the bake
  // reads none of them, and decoding them would double its load time.
  bool loadNormalTextures = false;
  // Reads a baked level's indirect grid (TEXCOORD_2 and each node's
  // extras.afterglow.indirectLightmap, uv/indirect.h) into Primitive::indirectUv and
  // Instance::indirectLightmap, for `render` reading the grid's directional lightmaps. Off, a
  // level baked again gets a grid of the new bake's own.
  bool loadIndirectUvs = false;
};

// Loads a glTF. Errors name the file and the mesh/primitive/material at fault; recoverable
// problems (a missing texture, a non-triangle primitive) become Scene::warnings instead.
Result<Scene> loadGltf(const std::string& path, const LoadOptions& options = {});
// Same, from bytes in memory (the fuzzer's entry point). baseDir resolves external URIs.
Result<Scene> loadGltfFromMemory(const std::string& bytes, const std::string& nameForMessages,
                                 const std::string& baseDir, const LoadOptions& options = {});

struct SaveOptions {
  bool embedBuffers = false;  // true writes the buffer as a data: URI inside the .gltf
};

// Writes the scene as glTF (.gltf with a .bin beside it, or .glb by extension). Instances become
// root nodes; lights and cameras become nodes; TEXCOORD_1 is written when present; each
// instance's lightmap location goes to node extras.afterglow.lightmap. Texture images are
// referenced by their original URI relative to the output. The write is atomic.
Status saveGltf(const Scene& scene, const std::string& path, const SaveOptions& options = {});

}  // namespace afterglow::scenes
