// The light probes' SH file (OUT/probes/light_probes_sh.bin), written by the bake and by
// `afterglow relight`, read by engines (GLM and the standard library only). Little-endian:
//
//    0  char[8]  magic "AGPRBSH\0"
//    8  u32      version (1)
//   12  u32      probe count N (the order of "positions" in light_probes.json)
//   16  u32      floats per probe, 27
//   20  u32      flags: bit 0 set when the SH were deringed (then 24 holds the window)
//   24  f32      deringing window (deringed(), probe_sh.h; 0 when not deringed)
//   28  u32      0 (reserved)
//   32  f32[N × 27]  per probe, its radiance SH L2 (ShL2: L_i = ∫ L(ω) Y_i(ω) dω in the basis
//                    and order of probe_sh.h), coefficient-major: c0.r c0.g c0.b c1.r ... c8.b
//
// E/π for a normal n is irradianceOverPi(sh, n); toUnitySH and toShaderConstants convert.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afterglow/runtime/probe_sh.h"

namespace afterglow::runtime {

constexpr char kProbeShMagic[8] = {'A', 'G', 'P', 'R', 'B', 'S', 'H', '\0'};
constexpr uint32_t kProbeShVersion = 1;
constexpr size_t kProbeShHeaderSize = 32;

struct ProbeShFile {
  std::vector<ShL2> sh;
  float deringWindow = 0.0f;  // > 0 when the SH were deringed with this window
};

// The file's bytes.
std::vector<uint8_t> serializeProbeSh(const ProbeShFile& file);
// Parses the bytes; on failure returns false and sets *error (one line, without the path).
// Checks the magic, version, floats per probe, that the size is exactly the header and the
// probes, and that every value is finite.
bool parseProbeSh(const uint8_t* bytes, size_t size, ProbeShFile& out, std::string* error);
// Reads a file; errors start with the path.
bool readProbeSh(const std::string& path, ProbeShFile& out, std::string* error);

}  // namespace afterglow::runtime
