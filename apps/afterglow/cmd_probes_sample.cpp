// `afterglow probes sample OUT/ --at x,y,z`: the bake's (or a relit folder's) light probes
// interpolated at points, as an engine's dynamic object there would be lit
// (runtime::Runtime::sampleProbeLighting), as E/π per normal or, with --json, with the
// tetrahedron, weights, SH and directions for scripts.
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afterglow/runtime/probe_tetrahedra.h"
#include "args.h"
#include "afterglow/bakefiles/read.h"
#include "commands.h"
#include "common.h"

using nlohmann::json;

namespace afterglow::cli {

namespace {

struct Normal {
  std::string label;  // "+X" ... for the default axes, "" for a given one
  glm::vec3 n;
};

std::string vecText(glm::vec3 v) {
  return format("%.6g,%.6g,%.6g", double(v.x), double(v.y), double(v.z));
}

}  // namespace

int runProbesSample(int argc, char** argv, int first) {
  const Command command = {"probes sample", "probes", kProbesHelp};
  Args args;
  if (std::optional<int> stop =
          parseOrExit(args, argc, argv, first,
                      {{"at"}, {"normal"}, {"json", 0, false}, {"help", 'h', false}}, command))
    return *stop;
  std::string outDir;
  if (!args.single("bake folder OUT/", &outDir)) return command.usage(args.error());
  std::vector<glm::vec3> points;
  for (const std::string& a : args.getAll("at")) {
    glm::vec3 p;
    if (!parseVec3(a, &p)) return command.usage("--at wants x,y,z (metres), got '" + a + "'");
    points.push_back(p);
  }
  if (points.empty()) return command.usage("missing --at x,y,z");
  std::vector<Normal> normals;
  for (const std::string& a : args.getAll("normal")) {
    glm::vec3 n;
    const float len = parseVec3(a, &n) ? glm::length(n) : 0.0f;
    if (!(len > 0.0f) || !std::isfinite(len))
      return command.usage("--normal wants a non-zero x,y,z, got '" + a + "'");
    normals.push_back({"", n / len});
  }
  if (normals.empty())
    normals = {{"+X", {1, 0, 0}}, {"-X", {-1, 0, 0}}, {"+Y", {0, 1, 0}},
               {"-Y", {0, -1, 0}}, {"+Z", {0, 0, 1}}, {"-Z", {0, 0, -1}}};

  Result<bakefiles::BakedProbes> loaded = bakefiles::loadBakedProbes(outDir);
  if (interrupted()) return interruptedExit();
  if (!loaded) {
    printError(loaded.message());
    return kExitBadInput;
  }
  const bakefiles::BakedProbes& baked = loaded.value();
  const runtime::ProbeTetrahedra& mesh = baked.mesh();

  json all = json::array();
  for (const glm::vec3 p : points) {
    // Each point walks from the first tetrahedron, so its answer does not depend on the others.
    int hint = 0;
    const runtime::ProbeLighting lighting = baked.sampleLighting(p, &hint);
    const runtime::ShL2& sh = lighting.sh;
    const runtime::ProbeLocation where = runtime::locateProbe(mesh, p, 0);
    std::vector<glm::vec3> values;
    for (const Normal& n : normals) values.push_back(lighting.irradianceOverPi(n.n, baked.window()));
    if (!args.has("json")) {
      std::string line = vecText(p);
      for (size_t k = 0; k < normals.size(); ++k)
        line += "  " + (normals[k].label.empty() ? "n=" + vecText(normals[k].n) : normals[k].label) +
                " " + vecText(values[k]);
      if (!where.inside) line += "  (outside the probes' hull)";
      std::printf("%s\n", line.c_str());
      continue;
    }
    json coefficients = json::array(), irradiance = json::array(), directions = json::array();
    for (const runtime::ProbeDirection& d : lighting.lights)
      directions.push_back({{"direction", {d.direction.x, d.direction.y, d.direction.z}},
                            {"power", {d.power.r, d.power.g, d.power.b}}});
    for (const glm::vec3& c : sh.c)
      for (int k = 0; k < 3; ++k) coefficients.push_back(c[k]);
    for (size_t k = 0; k < normals.size(); ++k)
      irradiance.push_back({{"normal", {normals[k].n.x, normals[k].n.y, normals[k].n.z}},
                            {"value", {values[k].r, values[k].g, values[k].b}}});
    all.push_back({{"position", {p.x, p.y, p.z}},
                   {"tetrahedron", where.tetrahedron},
                   {"inside", where.inside},
                   {"probes", {where.probes.x, where.probes.y, where.probes.z, where.probes.w}},
                   {"weights", {where.weights.x, where.weights.y, where.weights.z, where.weights.w}},
                   {"sh", coefficients},
                   {"directions", directions},
                   {"irradiance", irradiance}});
  }
  // One point's object a line: readable, and still one JSON array.
  if (args.has("json")) {
    std::printf("[");
    for (size_t i = 0; i < all.size(); ++i)
      std::printf("%s\n%s", i ? "," : "", all[i].dump().c_str());
    std::printf("\n]\n");
  }
  return kExitOk;
}

}  // namespace afterglow::cli
