// The light probes' SH file (OUT/probes/light_probes_sh.bin), written by the bake and by
// `afterglow relight`, read by engines (GLM and the standard library only). Little-endian:
//
//    0  char[8]  magic "AGPRBSH\0"
//    8  u32      version (2; version 1 files, without bit 1 and its section, still read)
//   12  u32      probe count N (the order of "positions" in light_probes.json)
//   16  u32      floats per probe, 27
//   20  u32      flags: bit 0 set when the SH were deringed (then 24 holds the window);
//                       bit 1 set when the probes' directions follow the SH;
//                       bit 2 set when the probes' depth maps follow (after the directions)
//   24  f32      deringing window (deringed(), probe_sh.h; 0 when not deringed)
//   28  u32      0 (reserved)
//   32  f32[N × 27]  per probe, its radiance SH L2 (ShL2: L_i = ∫ L(ω) Y_i(ω) dω in the basis
//                    and order of probe_sh.h), coefficient-major: c0.r c0.g c0.b c1.r ... c8.b
// With bit 1, the small sources each probe reads as one direction (probe_lights.h: already in
// the SH; add lightCorrectionOverPi for their exact clamped cosine):
//       u32      M, the directions of all probes
//       u32[N+1] start: probe p's are directions start[p] .. start[p + 1]
//       f32[M × 6]  per direction: its unit direction x y z, then its power r g b
// With bit 2, the probes' depth maps (probe_visibility.h: weigh interpolation by them):
//       u16[N × 128]  per probe, 64 texels × (mean distance, deviation) as half floats
//
// E/π for a normal n is irradianceOverPi(sh, n) (plus the directions' corrections: the
// ProbeLighting of probe_lights.h); toUnitySH and toShaderConstants convert the SH.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afterglow/runtime/probe_lights.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_visibility.h"

namespace afterglow::runtime {

constexpr char kProbeShMagic[8] = {'A', 'G', 'P', 'R', 'B', 'S', 'H', '\0'};
constexpr uint32_t kProbeShVersion = 2;
constexpr size_t kProbeShHeaderSize = 32;

struct ProbeShFile {
  std::vector<ShL2> sh;
  float deringWindow = 0.0f;  // > 0 when the SH were deringed with this window
  ProbeDirectionList directions;  // empty, or one list per probe
  std::vector<uint16_t> depth;    // empty, or N × kProbeDepthValues (probe_visibility.h)
};

// The file's bytes.
std::vector<uint8_t> serializeProbeSh(const ProbeShFile& file);
// Parses the bytes; on failure returns false and sets *error (one line, without the path).
// Checks the magic, version, floats per probe, that the size is exactly the header, the probes
// and their directions, that every value is finite and every direction a unit vector.
bool parseProbeSh(const uint8_t* bytes, size_t size, ProbeShFile& out, std::string* error);
// Reads a file; errors start with the path.
bool readProbeSh(const std::string& path, ProbeShFile& out, std::string* error);

}  // namespace afterglow::runtime
