// A bake folder's light probes read back through the runtime, holding what the bake wrote to
// OUT/probes/light_probes_sh.bin: `afterglow probes sample` and `probes place --bake`.
#pragma once

#include <memory>
#include <string>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "afterglow/core/status.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/runtime.h"

namespace afterglow::cli {

struct BakedProbes {
  std::unique_ptr<runtime::Runtime> runtime;  // solved as the bake solved it
  std::string transportPath;                  // OUT/transport.agt
  int bounces = 0;            // the bake's bounce passes (report.json; 0: until converged)
  float deringWindow = 0.0f;  // the bake's --probe-dering (0: its SH are as solved)

  // The probes' radiance SH at p (tetrahedral interpolation, Runtime::sampleProbes from *hint),
  // deringed as the bake's SH file is: at a probe's position, that probe's SH in the file.
  runtime::ShL2 sample(glm::vec3 p, int* hint) const;
};

// The bounce passes a bake ran, from its report's settings (0: until converged); an error
// naming the report when "bounces" is not a count.
Result<int> bakedBounces(const nlohmann::json& settings, const std::string& reportPath);

// Loads OUT/transport.agt and solves it as `afterglow bake` did: from scratch, with the bake's
// bounce count and tolerance (OUT/report.json's settings; without a report, until converged,
// the bake's default), so the probes equal the bake's bit for bit (the runtime's update() runs
// the solver's loop, and a fresh Runtime is black until its first update). Errors name the
// file: no or a damaged transport, a report that is not one, a transport without light probes.
Result<BakedProbes> loadBakedProbes(const std::string& outDir);

}  // namespace afterglow::cli
