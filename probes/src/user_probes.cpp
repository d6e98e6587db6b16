// Reading the light probes' files (the user's probes for `afterglow probes place --add`, a
// placement for `afterglow bake --probes`), apart from the rest of the library so that the
// fuzzer links it alone.
#include <cmath>
#include <cstdlib>

#include <nlohmann/json.hpp>

#include "afterglow/core/atomic_file.h"
#include "afterglow/probes/probes_file.h"

namespace afterglow::probes {

using json = nlohmann::json;

const char* probeKindName(ProbeKind kind) {
  switch (kind) {
    case ProbeKind::Grid: return "grid";
    case ProbeKind::Refined: return "refined";
    case ProbeKind::Moved: return "moved";
    case ProbeKind::Pinned: return "pinned";
  }
  return "unknown";
}

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

Result<ProbesFile> parseProbesFile(const std::string& text, const std::string& path) {
  Result<UserProbes> base = parseUserProbes(text, path);
  if (!base) return base.status();
  const json doc = json::parse(text, nullptr, false);
  auto format = doc.find("format");
  if (format == doc.end() || !format->is_string() ||
      format->get<std::string>() != "afterglow-light-probes")
    return Status::error(path + ": not an afterglow light probes file (no \"format\": "
                                "\"afterglow-light-probes\"; write one with afterglow probes place)");
  ProbesFile out;
  out.positions = std::move(base->positions);
  const size_t n = out.positions.size();
  out.kinds.assign(n, ProbeKind::Grid);
  out.names.assign(n, "");
  if (auto kinds = doc.find("kinds"); kinds != doc.end()) {
    if (!kinds->is_array() || kinds->size() != n)
      return Status::error(path + ": \"kinds\" must list one kind per probe");
    for (size_t i = 0; i < n; ++i) {
      const json& k = (*kinds)[i];
      bool known = false;
      for (ProbeKind kind : {ProbeKind::Grid, ProbeKind::Refined, ProbeKind::Moved, ProbeKind::Pinned})
        if (k.is_string() && k.get<std::string>() == probeKindName(kind)) out.kinds[i] = kind, known = true;
      if (!known) return Status::error(path + ": probe " + std::to_string(i) + " has an unknown kind " + k.dump());
    }
  }
  if (auto names = doc.find("names"); names != doc.end() && names->is_object())
    for (auto it = names->begin(); it != names->end(); ++it) {
      char* end = nullptr;
      const unsigned long i = std::strtoul(it.key().c_str(), &end, 10);
      if (it.key().empty() || *end != '\0' || i >= n || !it.value().is_string())
        return Status::error(path + ": name \"" + it.key() + "\" is not a probe index with a string");
      out.names[i] = it.value().get<std::string>();
    }
  auto readQuads = [&](const char* key, std::vector<glm::ivec4>& quads, int lowest,
                       int highest) -> Status {
    auto it = doc.find(key);
    if (it == doc.end() || !it->is_array())
      return Status::error(path + ": no \"" + std::string(key) + "\" array");
    for (size_t t = 0; t < it->size(); ++t) {
      const json& q = (*it)[t];
      glm::ivec4 v(0);
      bool ok = q.is_array() && q.size() == 4;
      for (int k = 0; ok && k < 4; ++k) {
        ok = q[size_t(k)].is_number_integer() && q[size_t(k)].get<int64_t>() >= lowest &&
             q[size_t(k)].get<int64_t>() <= highest;
        if (ok) v[k] = int(q[size_t(k)].get<int64_t>());
      }
      if (!ok)
        return Status::error(std::string(key) == "tetrahedra"
                                 ? path + ": tetrahedron " + std::to_string(t) +
                                       " is not four probe indices below " + std::to_string(n) +
                                       ": " + q.dump()
                                 : path + ": neighbours of tetrahedron " + std::to_string(t) +
                                       " are not four tetrahedron indices (or -1): " + q.dump());
      quads.push_back(v);
    }
    return Status::ok();
  };
  out.mesh.positions = out.positions;
  if (Status st = readQuads("tetrahedra", out.mesh.tetrahedra, 0, int(n) - 1); !st) return st;
  if (Status st = readQuads("neighbours", out.mesh.neighbours, -1,
                            int(std::min<size_t>(out.mesh.tetrahedra.size(), 0x7fffffff)) - 1);
      !st)
    return st;
  if (out.mesh.neighbours.size() != out.mesh.tetrahedra.size())
    return Status::error(path + ": " + std::to_string(out.mesh.neighbours.size()) +
                         " neighbour entries for " + std::to_string(out.mesh.tetrahedra.size()) +
                         " tetrahedra");
  if (std::string bad = runtime::checkProbeTetrahedra(out.mesh); !bad.empty())
    return Status::error(path + ": " + bad);
  return out;
}

Result<ProbesFile> readProbesFile(const std::string& path) {
  Result<std::string> text = readFile(path);
  if (!text) return text.status();
  return parseProbesFile(text.value(), path);
}

Result<UserProbes> readUserProbes(const std::string& path) {
  Result<std::string> text = readFile(path);
  if (!text) return text.status();
  return parseUserProbes(text.value(), path);
}

}  // namespace afterglow::probes
