// libFuzzer target: the light probes' user file (`afterglow probes place --add FILE.json`). Any
// input must give probes or an error, never a crash, and every probe it gives must be finite.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "afterglow/probes/probes_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  afterglow::Result<afterglow::probes::UserProbes> probes =
      afterglow::probes::parseUserProbes(text, "fuzz.json");
  if (!probes) return 0;
  if (probes->names.size() != probes->positions.size()) std::abort();
  for (const glm::vec3& p : probes->positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) std::abort();
  return 0;
}
