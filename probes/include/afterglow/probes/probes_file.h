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
};
// Errors name the file and the object at fault: not a light probes file, a position that is
// not three finite numbers, an unknown kind, a tetrahedron with an index out of range (or not
// four integers), neighbours that do not match (runtime::checkProbeTetrahedra).
Result<ProbesFile> readProbesFile(const std::string& path);
Result<ProbesFile> parseProbesFile(const std::string& text, const std::string& path);

// The file's text. `settingsJson` and `summaryJson` are JSON objects as text ("{}" for none);
// `shJson`, when not empty, becomes the "sh" member (the bake's SH file, named and described).
std::string probesJson(const Placement& placement, const std::vector<std::string>& names,
                       const runtime::ProbeTetrahedra& mesh, const std::string& settingsJson,
                       const std::string& summaryJson, const std::string& shJson = "");

}  // namespace afterglow::probes
