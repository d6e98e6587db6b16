// libFuzzer target for the glTF importer: every input must give a Scene or an error, never a
// crash, a sanitizer report, a leak or a hang.
//
// Textures are not decoded (loadTextures = false): image decoding belongs to OpenImageIO, which
// is not instrumented here, and it would only spend the time budget outside our code. The
// importer still resolves every texture, image and bufferView reference.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "afterglow/scenes/gltf.h"

namespace {

void appendU32(std::string& s, uint32_t v) {
  const char bytes[4] = {char(v & 0xFF), char(v >> 8 & 0xFF), char(v >> 16 & 0xFF), char(v >> 24)};
  s.append(bytes, 4);
}

// The input as the JSON chunk of a well-formed GLB with a small BIN chunk, so that mutations of
// plain JSON also reach the GLB buffer paths (buffers without a uri).
std::string wrapAsGlb(const std::string& json) {
  std::string text = json;
  while (text.size() % 4) text.push_back(' ');
  std::string bin(256, '\0');
  for (size_t i = 0; i < bin.size(); ++i) bin[i] = char(i * 37 + 11);
  std::string glb = "glTF";
  appendU32(glb, 2);
  appendU32(glb, uint32_t(12 + 8 + text.size() + 8 + bin.size()));
  appendU32(glb, uint32_t(text.size()));
  appendU32(glb, 0x4E4F534A);
  glb += text;
  appendU32(glb, uint32_t(bin.size()));
  appendU32(glb, 0x004E4942);
  glb += bin;
  return glb;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > (1u << 20)) return 0;
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  afterglow::scenes::LoadOptions options;
  options.loadTextures = false;
  // A base folder that does not exist: external URIs resolve to nothing.
  const std::string baseDir = "/nonexistent/afterglow-fuzz";
  // As given: .gltf JSON, or .glb when it starts with the GLB magic.
  (void)afterglow::scenes::loadGltfFromMemory(bytes, "fuzz.gltf", baseDir, options);
  if (size < 4 || std::memcmp(data, "glTF", 4) != 0)
    (void)afterglow::scenes::loadGltfFromMemory(wrapAsGlb(bytes), "fuzz.glb", baseDir, options);
  return 0;
}
