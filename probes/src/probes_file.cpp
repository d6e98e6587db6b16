#include "afterglow/probes/probes_file.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <nlohmann/json.hpp>


namespace afterglow::probes {

using json = nlohmann::json;

namespace {

// The shortest "%g" decimal that reads back to v as a float (v finite).
std::string shortestDecimal(float v) {
  char text[32];
  for (int digits = 1; digits <= 9; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, double(v));
    if (std::strtof(text, nullptr) == v) break;
  }
  return text;
}

}  // namespace

std::string probesJson(const Placement& placement, const std::vector<std::string>& names,
                       const runtime::ProbeTetrahedra& mesh, const std::string& settingsJson,
                       const std::string& summaryJson, const std::string& shJson,
                       const std::vector<ReflectionProbeEntry>& reflectionProbes) {
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
  if (!reflectionProbes.empty()) {
    // Each number as the shortest decimal of its float, so a proposal's tidy millimetres are
    // written as such and read back to the same float.
    auto number = [](float v) { return json::parse(shortestDecimal(v)); };
    auto vec = [&](glm::vec3 v) { return json::array({number(v.x), number(v.y), number(v.z)}); };
    json reflections = json::array();
    for (const ReflectionProbeEntry& r : reflectionProbes) {
      json entry = {{"name", r.name}, {"position", vec(r.position)}, {"size", vec(r.size)}};
      if (r.projectionSize != glm::vec3(0.0f)) entry["projectionSize"] = vec(r.projectionSize);
      entry["blendDistance"] = number(r.blendDistance);
      entry["importance"] = r.importance;
      entry["boxProjection"] = r.boxProjection;
      entry["resolution"] = r.resolution;
      reflections.push_back(std::move(entry));
    }
    doc["reflectionProbes"] = std::move(reflections);
  }
  doc["settings"] = json::parse(settingsJson, nullptr, false);
  doc["summary"] = json::parse(summaryJson, nullptr, false);
  if (!shJson.empty()) doc["sh"] = json::parse(shJson, nullptr, false);
  // Compact: a level holds tens of thousands of probes and hundreds of thousands of tetrahedra.
  return doc.dump() + "\n";
}

}  // namespace afterglow::probes
