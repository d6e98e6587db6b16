// Reading the light probes' files (the user's probes for `afterglow probes place --add`, a
// placement for `afterglow bake --probes`), apart from the rest of the library so that the
// fuzzer links it alone.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iterator>

#include <nlohmann/json.hpp>

#include "afterglow/core/atomic_file.h"
#include "afterglow/core/json_text.h"
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

namespace {

// What a place in a probes file holds, as messages name it: "probe 2", "tetrahedron 5", ...
std::string objectAt(const JsonPath& at) {
  if (at.size() < 2) return at.empty() ? std::string() : "\"" + at[0] + "\"";
  const std::string& list = at[0];
  if (list == "positions" || list == "kinds") return "probe " + at[1];
  if (list == "names") return "name " + at[1];
  if (list == "tetrahedra") return "tetrahedron " + at[1];
  if (list == "neighbours") return "neighbours of tetrahedron " + at[1];
  if (list == "reflectionProbes") return "reflection probe " + at[1];
  return "\"" + list + "\"";
}

// A probes file's text and name, so that an error says where in it the value at fault is: the
// files are edited by hand and hold thousands of probes.
struct ProbesText {
  const std::string& text;
  const std::string& path;

  // "PATH: what (line L, column C)" at the start of the value at `at` (of its deepest part
  // that is there).
  Status error(const std::string& what, const JsonPath& at) const {
    return Status::error(path + ": " + what + " (" + textPlace(text, jsonValueOffset(text, at)) +
                         ")");
  }
  // The document, or why it is not JSON (a NaN, a 1e999, a missing comma): where, and in
  // which probe.
  Result<json> parse() const {
    json doc = json::parse(text, nullptr, false);
    if (doc.is_discarded()) {
      const JsonSyntaxError bad =
          findJsonSyntaxError(text).value_or(JsonSyntaxError{0, "not JSON"});
      const std::string object = objectAt(jsonPathAt(text, bad.offset));
      return Status::error(path + ": " + (object.empty() ? "" : object + ": ") +
                           "not valid JSON: " + bad.reason + " (" +
                           textPlace(text, bad.offset) + ")");
    }
    if (!doc.is_object()) return error("not a JSON object", {});
    return doc;
  }
};

std::string indexText(size_t i) { return std::to_string(i); }

Result<UserProbes> userProbesOf(const json& doc, const ProbesText& file) {
  auto positions = doc.find("positions");
  if (positions == doc.end() || !positions->is_array())
    return file.error("no \"positions\" array", {"positions"});
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
      return file.error("probe " + indexText(i) + " is not three finite numbers: " + p.dump(),
                        {"positions", indexText(i)});
    out.positions.push_back(v);
  }
  out.names.assign(out.positions.size(), "");
  if (auto names = doc.find("names"); names != doc.end() && names->is_array()) {
    if (names->size() != out.positions.size())
      return file.error("\"names\" has " + indexText(names->size()) + " entries for " +
                            indexText(out.positions.size()) + " positions",
                        {"names"});
    for (size_t i = 0; i < names->size(); ++i) {
      if (!(*names)[i].is_string())
        return file.error("name " + indexText(i) + " is not a string", {"names", indexText(i)});
      out.names[i] = (*names)[i].get<std::string>();
    }
  }
  return out;
}

}  // namespace

Result<UserProbes> parseUserProbes(const std::string& text, const std::string& path) {
  const ProbesText file{text, path};
  Result<json> doc = file.parse();
  if (!doc) return doc.status();
  return userProbesOf(doc.value(), file);
}

namespace {

// One reflection probe's members but its name, each checked where present (position and size
// must be). `where` names the probe ("reflection probe 1 ('porch')"), `at` its place.
Status readReflectionMembers(const json& r, const ProbesText& file, const std::string& where,
                             const JsonPath& at, ReflectionProbeEntry& e) {
  auto fail = [&](const std::string& key, const std::string& what) {
    JsonPath member = at;
    member.push_back(key);
    return file.error(where + ": \"" + key + "\" " + what, member);
  };
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
    return fail(key, std::string("must be three ") + (positive ? "positive " : "") +
                         "finite numbers (metres)" +
                         (it == r.end() ? std::string(", and is missing") : ", got " + it->dump()));
  };
  if (Status st = vec3("position", false, e.position); !st) return st;
  if (Status st = vec3("size", true, e.size); !st) return st;
  if (r.contains("projectionSize"))
    if (Status st = vec3("projectionSize", true, e.projectionSize); !st) return st;
  if (auto it = r.find("blendDistance"); it != r.end()) {
    const double d = it->is_number() ? it->get<double>() : -1.0;
    if (!(std::isfinite(d) && d >= 0.0 && d < 1e9))
      return fail("blendDistance", "must be a number of metres >= 0, got " + it->dump());
    e.blendDistance = float(d);
  }
  if (auto it = r.find("importance"); it != r.end()) {
    const double v = it->is_number() ? it->get<double>() : 0.5;
    if (!(std::isfinite(v) && v == std::floor(v) && std::abs(v) <= 1e6))
      return fail("importance", "must be a whole number, got " + it->dump());
    e.importance = int(v);
  }
  if (auto it = r.find("boxProjection"); it != r.end()) {
    if (!it->is_boolean()) return fail("boxProjection", "must be true or false, got " + it->dump());
    e.boxProjection = it->get<bool>();
  }
  if (auto it = r.find("resolution"); it != r.end()) {
    const double v = it->is_number() ? it->get<double>() : 0.0;
    const bool powerOfTwo = std::isfinite(v) && v >= 8.0 && v <= 2048.0 && v == std::floor(v) &&
                            (int(v) & (int(v) - 1)) == 0;
    if (!powerOfTwo)
      return fail("resolution", "must be a power of two from 8 to 2048, got " + it->dump());
    e.resolution = int(v);
  }
  return Status::ok();
}

// The "reflectionProbes" array (absent: none). Strict, as a glTF node's reflectionProbe is: a
// probe that silently took a default would light the wrong region, and this file is edited by
// hand.
Status parseReflectionProbes(const json& doc, const ProbesText& file,
                             std::vector<ReflectionProbeEntry>& out) {
  auto list = doc.find("reflectionProbes");
  if (list == doc.end()) return Status::ok();
  if (!list->is_array())
    return file.error("\"reflectionProbes\" is not an array of reflection probes",
                      {"reflectionProbes"});
  for (size_t i = 0; i < list->size(); ++i) {
    const json& r = (*list)[i];
    const JsonPath at = {"reflectionProbes", indexText(i)};
    std::string where = "reflection probe " + indexText(i);
    if (!r.is_object()) return file.error(where + " is not an object", at);
    ReflectionProbeEntry e;
    auto name = r.find("name");
    if (name == r.end() || !name->is_string() || name->get<std::string>().empty())
      return file.error(where + " has no \"name\" (a non-empty string)", at);
    e.name = name->get<std::string>();
    where += " ('" + e.name + "')";
    for (const ReflectionProbeEntry& earlier : out)
      if (earlier.name == e.name)
        return file.error(where + ": the name is taken by an earlier reflection probe",
                          {at[0], at[1], "name"});
    for (auto it = r.begin(); it != r.end(); ++it) {
      static const char* const kKnown[] = {"name",          "position",   "size",
                                           "projectionSize", "blendDistance", "importance",
                                           "boxProjection", "resolution"};
      if (std::find(std::begin(kKnown), std::end(kKnown), it.key()) == std::end(kKnown))
        return file.error(where + ": unknown member \"" + it.key() +
                              "\" (known: name, position, size, projectionSize, blendDistance, "
                              "importance, boxProjection, resolution)",
                          {at[0], at[1], it.key()});
    }
    if (Status st = readReflectionMembers(r, file, where, at, e); !st) return st;
    out.push_back(std::move(e));
  }
  return Status::ok();
}

// "kinds" (absent: every probe a grid probe) and the "names" object into out.
Status readKindsAndNames(const json& doc, const ProbesText& file, ProbesFile& out) {
  const size_t n = out.positions.size();
  out.kinds.assign(n, ProbeKind::Grid);
  out.names.assign(n, "");
  if (auto kinds = doc.find("kinds"); kinds != doc.end()) {
    if (!kinds->is_array() || kinds->size() != n)
      return file.error("\"kinds\" must list one kind per probe", {"kinds"});
    for (size_t i = 0; i < n; ++i) {
      const json& k = (*kinds)[i];
      bool known = false;
      for (ProbeKind kind : {ProbeKind::Grid, ProbeKind::Refined, ProbeKind::Moved, ProbeKind::Pinned})
        if (k.is_string() && k.get<std::string>() == probeKindName(kind)) out.kinds[i] = kind, known = true;
      if (!known)
        return file.error("probe " + indexText(i) + " has an unknown kind " + k.dump(),
                          {"kinds", indexText(i)});
    }
  }
  if (auto names = doc.find("names"); names != doc.end() && names->is_object())
    for (auto it = names->begin(); it != names->end(); ++it) {
      char* end = nullptr;
      const unsigned long i = std::strtoul(it.key().c_str(), &end, 10);
      if (it.key().empty() || *end != '\0' || i >= n || !it.value().is_string())
        return file.error("name \"" + it.key() + "\" is not a probe index with a string",
                          {"names", it.key()});
      out.names[i] = it.value().get<std::string>();
    }
  return Status::ok();
}

// doc[key]: an array of four integers in [lowest, highest] each, into quads.
Status readQuads(const json& doc, const ProbesText& file, const char* key,
                 std::vector<glm::ivec4>& quads, int lowest, int highest) {
  auto it = doc.find(key);
  if (it == doc.end() || !it->is_array())
    return file.error("no \"" + std::string(key) + "\" array", {key});
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
      return file.error(
          std::string(key) == "tetrahedra"
              ? "tetrahedron " + indexText(t) + " is not four probe indices below " +
                    indexText(size_t(highest) + 1) + ": " + q.dump()
              : "neighbours of tetrahedron " + indexText(t) +
                    " are not four tetrahedron indices (or -1): " + q.dump(),
          {key, indexText(t)});
    quads.push_back(v);
  }
  return Status::ok();
}

// Where runtime::checkProbeTetrahedra's complaint is: it names the tetrahedron first
// ("tetrahedron 3: ..."), its neighbours when it is about them.
JsonPath meshPlace(const std::string& complaint) {
  const std::string name = "tetrahedron ";
  if (complaint.rfind(name, 0) != 0) return {};
  const std::string index = complaint.substr(name.size(), complaint.find(':') - name.size());
  const bool neighbours = complaint.find(": neighbour ") != std::string::npos;
  return {neighbours ? "neighbours" : "tetrahedra", index};
}

// The tetrahedra and their neighbours, read and checked.
Status readMesh(const json& doc, const ProbesText& file, ProbesFile& out) {
  const size_t n = out.positions.size();
  out.mesh.positions = out.positions;
  if (Status st = readQuads(doc, file, "tetrahedra", out.mesh.tetrahedra, 0, int(n) - 1); !st)
    return st;
  if (Status st = readQuads(doc, file, "neighbours", out.mesh.neighbours, -1,
                            int(std::min<size_t>(out.mesh.tetrahedra.size(), 0x7fffffff)) - 1);
      !st)
    return st;
  if (out.mesh.neighbours.size() != out.mesh.tetrahedra.size())
    return file.error(indexText(out.mesh.neighbours.size()) + " neighbour entries for " +
                          indexText(out.mesh.tetrahedra.size()) + " tetrahedra",
                      {"neighbours"});
  if (std::string bad = runtime::checkProbeTetrahedra(out.mesh); !bad.empty())
    return file.error(bad, meshPlace(bad));
  return Status::ok();
}

}  // namespace

Result<ProbesFile> parseProbesFile(const std::string& text, const std::string& path) {
  const ProbesText file{text, path};
  Result<json> parsed = file.parse();
  if (!parsed) return parsed.status();
  const json& doc = parsed.value();
  Result<UserProbes> base = userProbesOf(doc, file);
  if (!base) return base.status();
  auto format = doc.find("format");
  if (format == doc.end() || !format->is_string() ||
      format->get<std::string>() != "afterglow-light-probes")
    return file.error("not an afterglow light probes file (no \"format\": "
                      "\"afterglow-light-probes\"; write one with afterglow probes place)",
                      {"format"});
  ProbesFile out;
  out.positions = std::move(base->positions);
  if (Status st = readKindsAndNames(doc, file, out); !st) return st;
  if (Status st = readMesh(doc, file, out); !st) return st;
  if (Status st = parseReflectionProbes(doc, file, out.reflectionProbes); !st) return st;
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
