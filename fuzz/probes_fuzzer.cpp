// libFuzzer target: the light probes' files. The same bytes go to the user's probes file
// (`afterglow probes place --add FILE.json`), a placement (`afterglow bake --probes
// PROBES.json`, checked tetrahedra) and the baked SH file (OUT/probes/light_probes_sh.bin). Any
// input must give a result or an error, never a crash, and every result must hold what its
// reader promises: finite positions and SH, tetrahedra that pass runtime::checkProbeTetrahedra,
// reflection probes with positive finite boxes and power-of-two resolutions.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "afterglow/core/math.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/runtime/probe_sh_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace afterglow;
  const std::string text(reinterpret_cast<const char*>(data), size);
  if (Result<probes::UserProbes> user = probes::parseUserProbes(text, "fuzz.json")) {
    if (user->names.size() != user->positions.size()) std::abort();
    for (const glm::vec3& p : user->positions)
      if (!afterglow::finite(p)) std::abort();
  }
  if (Result<probes::ProbesFile> file = probes::parseProbesFile(text, "fuzz.json")) {
    const size_t n = file->positions.size();
    if (file->kinds.size() != n || file->names.size() != n || file->mesh.positions.size() != n)
      std::abort();
    if (!runtime::checkProbeTetrahedra(file->mesh).empty()) std::abort();
    for (const glm::vec3& p : file->positions)
      if (!afterglow::finite(p)) std::abort();
    for (const probes::ReflectionProbeEntry& r : file->reflectionProbes) {
      if (r.name.empty() || !afterglow::finite(r.position) || !afterglow::finite(r.size))
        std::abort();
      if (!(r.size.x > 0.0f && r.size.y > 0.0f && r.size.z > 0.0f)) std::abort();
      if (!(r.blendDistance >= 0.0f) || !std::isfinite(r.blendDistance)) std::abort();
      if (r.resolution < 8 || r.resolution > 2048 || (r.resolution & (r.resolution - 1))) std::abort();
    }
  }
  runtime::ProbeShFile sh;
  std::string error;
  if (runtime::parseProbeSh(data, size, sh, &error)) {
    const runtime::ProbeDirectionList& d = sh.directions;
    const size_t section = d.start.empty() ? 0 : 4 + d.start.size() * 4 + d.lights.size() * 24;
    if (size != runtime::kProbeShHeaderSize + sh.sh.size() * 27 * 4 + section + sh.depth.size() * 2)
      std::abort();
    if (!sh.depth.empty() && sh.depth.size() != sh.sh.size() * runtime::kProbeDepthValues)
      std::abort();
    for (uint16_t v : sh.depth)
      if (!(runtime::halfToFloat(v) >= 0.0f) || !std::isfinite(runtime::halfToFloat(v))) std::abort();
    for (const runtime::ShL2& s : sh.sh)
      for (const glm::vec3& c : s.c)
        if (!afterglow::finite(c)) std::abort();
    if (!d.start.empty() && (d.count() != sh.sh.size() || d.start.back() != d.lights.size()))
      std::abort();
    for (size_t p = 0; p < d.count(); ++p)
      if (d.start[p] > d.start[p + 1]) std::abort();
    for (const runtime::ProbeDirection& l : d.lights)
      if (!afterglow::finite(l.direction) || !afterglow::finite(l.power) ||
          std::abs(glm::length(l.direction) - 1.0f) > 1e-3f)
        std::abort();
  } else if (error.empty() || error.find('\n') != std::string::npos) {
    std::abort();
  }
  return 0;
}
