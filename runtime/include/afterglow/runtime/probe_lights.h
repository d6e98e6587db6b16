// Light probes' small light sources kept as directions beside their SH (GLM only).
//
// Why. SH L2 cannot hold a small bright source: the clamped cosine's band-limited reading of one
// direction overshoots by 6% facing it, gives 9% of the light's peak at 90° and 6% behind it.
// Beside an object in a room lit by one small lamp (the Cornell boxes), that ringing alone puts
// a probe 14-24% RMS off the true irradiance, worse than all of the probes' other errors
// together; read with the lamp's clamped cosine exact, the same SH is 1-3% off.
//
// What. Each direct source's unit radiance SH at a probe (Source::probeTransfer) has a power
// Φ = L_0 / Y00 (∫ L dω) and a first moment v = ∫ L ω dω = (L_3, L_1, L_2) / 0.488603, with
// |v| = R·Φ, R in [0, 1] how concentrated the source is as the probe sees it (1: one direction).
// The part P = f(R)·|v| along d = v / |v| is read as one direction (Sloan, "Stupid Spherical
// Harmonics (SH) Tricks", 2008, "extracting a directional light"): E/π gains
//
//     P/π · (max(0, n·d) − s(n·d)),   s(c) = (1 + 2σ1·c + (5/8)·σ2·(3c² − 1)) / 4,
//
// the direction's exact clamped cosine minus what irradianceOverPi reads from its SH (σ the
// deringing window's band weights, 1 when not deringed). The SH themselves are unchanged:
// exports and engines that read SH alone get what they got before. f ramps from 0 at R = 0.93 to 1 at
// R = 0.99: for a uniform cap of light, one direction beats SH L2 up to a cap's half-angle of
// about 30° (R = 0.93); beyond it SH L2 is the better fit (a 45° cap: 0.7% RMS against 3.8%),
// and the ramp keeps the combination at or below SH L2's error for every cap size.
//
// Everything here is linear in the sources' scales and in the probes' weights, so lights
// interpolate with the same tetrahedral weights as the SH.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

// The part of a probe's light read as one direction: power = ∫ L dω of that part (RGB).
struct ProbeDirection {
  glm::vec3 direction{0.0f, 1.0f, 0.0f};
  glm::vec3 power{0.0f};
};

// The concentrated part of one source's radiance SH as a probe sees it (above); false when
// nothing is (a source spread over the sky, or none of it seen).
bool concentratedPart(const float radianceSh[kShCount], glm::vec3* direction, float* power);

// E/π that light adds to irradianceOverPi(sh, n) of an SH holding it (deringed with `window`
// as deringed() does, 0 for none): its exact clamped cosine minus its SH reading.
glm::vec3 lightCorrectionOverPi(const ProbeDirection& light, glm::vec3 normal, float window = 0.0f);

// Every probe's lights (CSR): probe p's are lights[start[p] .. start[p + 1]).
struct ProbeDirectionList {
  std::vector<uint32_t> start;  // probes + 1 (empty: no lights at all)
  std::vector<ProbeDirection> lights;
  size_t count() const { return start.empty() ? 0 : start.size() - 1; }
};
// The lights of the transport's probes with the sources' scales (sourceScale per source, the
// transport's order), the same scales their SH were solved with.
ProbeDirectionList probeLights(const TransportData& data, const std::vector<glm::vec3>& directScales);
// The same into `out`, reusing its memory: no allocation once it holds probeLightCapacity.
void probeLights(const TransportData& data, const std::vector<glm::vec3>& directScales,
                 ProbeDirectionList& out);
// The most directions the transport's probes can have (one per probe and source).
size_t probeLightCapacity(const TransportData& data);
// directScale() of every source as the transport holds them.
std::vector<glm::vec3> directScales(const TransportData& data);

// A probe's (or an interpolated point's) light: its SH and its lights.
struct ProbeLighting {
  ShL2 sh;
  std::vector<ProbeDirection> lights;
  // E/π for a unit normal: irradianceOverPi(sh) plus each light's correction (window: how sh
  // was deringed, 0 for not).
  glm::vec3 irradianceOverPi(glm::vec3 normal, float window = 0.0f) const;
};
// At a located point (locateProbe): its probes' SH and lights mixed with their weights. An
// empty list gives the SH alone.
ProbeLighting mixProbeLighting(const ProbeLocation& where, const std::vector<ShL2>& probeSh,
                               const ProbeDirectionList& lights);

}  // namespace afterglow::runtime
