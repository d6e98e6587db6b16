// The user's probes file (`afterglow probes place --add`), apart from the rest of the library so
// that the fuzzer links it alone.
#include <cmath>

#include <nlohmann/json.hpp>

#include "afterglow/core/atomic_file.h"
#include "afterglow/probes/probes_file.h"

namespace afterglow::probes {

using json = nlohmann::json;

Result<UserProbes> parseUserProbes(const std::string& text, const std::string& path) {
  const json doc = json::parse(text, nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return Status::error(path + ": not a JSON object");
  auto positions = doc.find("positions");
  if (positions == doc.end() || !positions->is_array())
    return Status::error(path + ": no \"positions\" array");
  UserProbes out;
  for (size_t i = 0; i < positions->size(); ++i) {
    const json& p = (*positions)[i];
    bool ok = p.is_array() && p.size() == 3;
    glm::vec3 v(0.0f);
    for (int k = 0; ok && k < 3; ++k) {
      ok = p[size_t(k)].is_number() && std::isfinite(p[size_t(k)].get<double>());
      if (ok) v[k] = float(p[size_t(k)].get<double>());
      ok = ok && std::isfinite(v[k]);  // finite as a float too
    }
    if (!ok)
      return Status::error(path + ": probe " + std::to_string(i) +
                           " is not three finite numbers: " + p.dump());
    out.positions.push_back(v);
  }
  out.names.assign(out.positions.size(), "");
  if (auto names = doc.find("names"); names != doc.end() && names->is_array()) {
    if (names->size() != out.positions.size())
      return Status::error(path + ": \"names\" has " + std::to_string(names->size()) +
                           " entries for " + std::to_string(out.positions.size()) + " positions");
    for (size_t i = 0; i < names->size(); ++i) {
      if (!(*names)[i].is_string())
        return Status::error(path + ": name " + std::to_string(i) + " is not a string");
      out.names[i] = (*names)[i].get<std::string>();
    }
  }
  return out;
}

Result<UserProbes> readUserProbes(const std::string& path) {
  Result<std::string> text = readFile(path);
  if (!text) return text.status();
  return parseUserProbes(text.value(), path);
}

}  // namespace afterglow::probes
