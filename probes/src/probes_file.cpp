#include "afterglow/probes/probes_file.h"

#include <cmath>

#include <nlohmann/json.hpp>

#include "afterglow/core/atomic_file.h"

namespace afterglow::probes {

using json = nlohmann::json;

Result<UserProbes> readUserProbes(const std::string& path) {
  Result<std::string> text = readFile(path);
  if (!text) return text.status();
  const json doc = json::parse(text.value(), nullptr, false);
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

std::string probesJson(const Placement& placement, const std::vector<std::string>& names,
                       const runtime::ProbeTetrahedra& mesh, const std::string& settingsJson,
                       const std::string& summaryJson) {
  json doc;
  doc["format"] = "afterglow-light-probes";
  doc["version"] = 1;
  json positions = json::array(), kinds = json::array();
  for (size_t i = 0; i < placement.positions.size(); ++i) {
    const glm::vec3& p = placement.positions[i];
    positions.push_back({p.x, p.y, p.z});
    kinds.push_back(probeKindName(placement.kinds[i]));
  }
  doc["positions"] = std::move(positions);
  doc["kinds"] = std::move(kinds);
  json named = json::object();
  for (size_t i = 0; i < names.size(); ++i)
    if (!names[i].empty()) named[std::to_string(i)] = names[i];
  doc["names"] = std::move(named);
  json tetrahedra = json::array(), neighbours = json::array();
  for (size_t t = 0; t < mesh.tetrahedra.size(); ++t) {
    const glm::ivec4& c = mesh.tetrahedra[t];
    tetrahedra.push_back({c.x, c.y, c.z, c.w});
    const glm::ivec4& n = mesh.neighbours[t];
    neighbours.push_back({n.x, n.y, n.z, n.w});
  }
  doc["tetrahedra"] = std::move(tetrahedra);
  doc["neighbours"] = std::move(neighbours);
  doc["settings"] = json::parse(settingsJson, nullptr, false);
  doc["summary"] = json::parse(summaryJson, nullptr, false);
  // Compact: a level holds tens of thousands of probes and hundreds of thousands of tetrahedra.
  return doc.dump() + "\n";
}

}  // namespace afterglow::probes
