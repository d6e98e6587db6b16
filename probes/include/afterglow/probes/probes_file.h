// The light probes' JSON file (`afterglow probes place -o PROBES.json`, and later the bake's
// OUT/probes/light_probes.json):
//   {
//     "format": "afterglow-light-probes", "version": 1,
//     "positions": [[x, y, z], ...],                    metres, world (glTF axes, +Y up)
//     "kinds": ["grid" | "refined" | "moved" | "pinned", ...],   one per probe
//     "names": {"<probe index>": "name", ...},         the user's probes that were named
//     "tetrahedra": [[a, b, c, d], ...],                 probe indices, positively oriented
//     "neighbours": [[n0, n1, n2, n3], ...],             across the face opposite each corner;
//                                                        -1 on the hull
//     "reflectionProbes": [{"name", "position": [x, y, z], "size": [x, y, z],
//                           "blendDistance", "importance", "boxProjection", "resolution"}, ...]
//                                                        optional (probes place --reflection):
//                                                        axis-aligned boxes centred on their
//                                                        capture positions, for the bake
//     "settings": {...}, "summary": {...}               how it was made
//   }
// A user's own probes (`--add FILE.json`) are read from the same "positions" (and optional
// "names", a list of strings, one per position); any other member is ignored, so a PROBES.json
// can be added back.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/core/status.h"
#include "afterglow/probes/placement.h"
#include "afterglow/probes/reflection_placement.h"
#include "afterglow/runtime/probe_tetrahedra.h"

namespace afterglow::probes {

struct UserProbes {
  std::vector<glm::vec3> positions;
  std::vector<std::string> names;  // one per position ("" when unnamed)
};

// Reads a user's probes. Errors name the file and the probe: not JSON, no "positions" array,
// a position that is not three finite numbers, "names" of the wrong length or type.
Result<UserProbes> readUserProbes(const std::string& path);
// The same from the file's text (`path` names it in errors).
Result<UserProbes> parseUserProbes(const std::string& text, const std::string& path);

// A placement read back (`afterglow bake --probes PROBES.json`, `probes sample`): positions,
// kinds, names and the tetrahedra with their neighbours, checked.
struct ProbesFile {
  std::vector<glm::vec3> positions;
  std::vector<ProbeKind> kinds;     // Grid where the file has none
  std::vector<std::string> names;   // one per probe ("" when unnamed)
  runtime::ProbeTetrahedra mesh;    // positions, tetrahedra, neighbours
  std::vector<ReflectionProbeEntry> reflectionProbes;  // none when the file has none
};
// Errors name the file and the object at fault: not a light probes file, a position that is
// not three finite numbers, an unknown kind, a tetrahedron with an index out of range (or not
// four integers), neighbours that do not match (runtime::checkProbeTetrahedra); a reflection
// probe (by index and name) without a name or with one already taken, a position or size that
// is not three finite numbers (sizes positive), a negative or non-finite blendDistance, an
// importance that is not a whole number, a boxProjection that is not true or false, a
// resolution that is not a power of two from 8 to 2048, or a member it does not know (a typo
// would otherwise silently take the default).
Result<ProbesFile> readProbesFile(const std::string& path);
Result<ProbesFile> parseProbesFile(const std::string& text, const std::string& path);

// The file's text. `settingsJson` and `summaryJson` are JSON objects as text ("{}" for none);
// `shJson`, when not empty, becomes the "sh" member (the bake's SH file, named and described);
// `reflectionProbes`, when not empty, the "reflectionProbes" array.
std::string probesJson(const Placement& placement, const std::vector<std::string>& names,
                       const runtime::ProbeTetrahedra& mesh, const std::string& settingsJson,
                       const std::string& summaryJson, const std::string& shJson = "",
                       const std::vector<ReflectionProbeEntry>& reflectionProbes = {});

}  // namespace afterglow::probes
