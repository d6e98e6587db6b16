// Reading the light probes' files (the user's probes for `afterglow probes place --add`, a
// placement for `afterglow bake --probes`), apart from the rest of the library so that the
// fuzzer links it alone.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iterator>

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

namespace {

// The "reflectionProbes" array (absent: none). Strict, as a glTF node's reflectionProbe is: a
// probe that silently took a default would light the wrong region, and this file is edited by
// hand.
Status parseReflectionProbes(const json& doc, const std::string& path,
                             std::vector<ReflectionProbeEntry>& out) {
  auto list = doc.find("reflectionProbes");
  if (list == doc.end()) return Status::ok();
  if (!list->is_array())
    return Status::error(path + ": \"reflectionProbes\" is not an array of reflection probes");
  for (size_t i = 0; i < list->size(); ++i) {
    const json& r = (*list)[i];
    std::string where = path + ": reflection probe " + std::to_string(i);
    if (!r.is_object()) return Status::error(where + " is not an object");
    ReflectionProbeEntry e;
    auto name = r.find("name");
    if (name == r.end() || !name->is_string() || name->get<std::string>().empty())
      return Status::error(where + " has no \"name\" (a non-empty string)");
    e.name = name->get<std::string>();
    where += " ('" + e.name + "')";
    for (const ReflectionProbeEntry& earlier : out)
      if (earlier.name == e.name)
        return Status::error(where + ": the name is taken by an earlier reflection probe");
    for (auto it = r.begin(); it != r.end(); ++it) {
      static const char* const kKnown[] = {"name",       "position",      "size",
                                           "blendDistance", "importance", "boxProjection",
                                           "resolution"};
      if (std::find(std::begin(kKnown), std::end(kKnown), it.key()) == std::end(kKnown))
        return Status::error(where + ": unknown member \"" + it.key() +
                             "\" (known: name, position, size, blendDistance, importance, "
                             "boxProjection, resolution)");
    }
    // Three finite numbers (as floats too), all positive when `positive`.
    auto vec3 = [&](const char* key, bool positive, glm::vec3& v) -> Status {
      auto it = r.find(key);
      bool ok = it != r.end() && it->is_array() && it->size() == 3;
      for (int k = 0; ok && k < 3; ++k) {
        const json& c = (*it)[size_t(k)];
        ok = c.is_number() && std::isfinite(c.get<double>()) && std::abs(c.get<double>()) < 1e9;
        if (ok) v[k] = float(c.get<double>());
        ok = ok && (!positive || v[k] > 0.0f);
      }
      if (ok) return Status::ok();
      return Status::error(where + ": \"" + key + "\" must be three " +
                           (positive ? "positive " : "") + "finite numbers (metres)" +
                           (it == r.end() ? std::string(", and is missing") : ", got " + it->dump()));
    };
    if (Status st = vec3("position", false, e.position); !st) return st;
    if (Status st = vec3("size", true, e.size); !st) return st;
    if (auto it = r.find("blendDistance"); it != r.end()) {
      const double d = it->is_number() ? it->get<double>() : -1.0;
      if (!(std::isfinite(d) && d >= 0.0 && d < 1e9))
        return Status::error(where + ": \"blendDistance\" must be a number of metres >= 0, got " +
                             it->dump());
      e.blendDistance = float(d);
    }
    if (auto it = r.find("importance"); it != r.end()) {
      const double v = it->is_number() ? it->get<double>() : 0.5;
      if (!(std::isfinite(v) && v == std::floor(v) && std::abs(v) <= 1e6))
        return Status::error(where + ": \"importance\" must be a whole number, got " + it->dump());
      e.importance = int(v);
    }
    if (auto it = r.find("boxProjection"); it != r.end()) {
      if (!it->is_boolean())
        return Status::error(where + ": \"boxProjection\" must be true or false, got " +
                             it->dump());
      e.boxProjection = it->get<bool>();
    }
    if (auto it = r.find("resolution"); it != r.end()) {
      const double v = it->is_number() ? it->get<double>() : 0.0;
      const bool powerOfTwo = std::isfinite(v) && v >= 8.0 && v <= 2048.0 && v == std::floor(v) &&
                              (int(v) & (int(v) - 1)) == 0;
      if (!powerOfTwo)
        return Status::error(where + ": \"resolution\" must be a power of two from 8 to 2048, "
                                     "got " + it->dump());
      e.resolution = int(v);
    }
    out.push_back(std::move(e));
  }
  return Status::ok();
}

}  // namespace

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
  if (Status st = parseReflectionProbes(doc, path, out.reflectionProbes); !st) return st;
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
