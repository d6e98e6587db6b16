#include "baked_probes.h"

#include <filesystem>

#include <nlohmann/json.hpp>

#include "afterglow/core/atomic_file.h"
#include "afterglow/core/parallel.h"

namespace fs = std::filesystem;

namespace afterglow::cli {

runtime::ShL2 BakedProbes::sample(glm::vec3 p, int* hint) const {
  const runtime::ShL2 sh = runtime->sampleProbes(p, hint);
  // Deringing scales each band: interpolating deringed probes is deringing the interpolation.
  return deringWindow > 0.0f ? runtime::deringed(sh, deringWindow) : sh;
}

Result<int> bakedBounces(const nlohmann::json& settings, const std::string& reportPath) {
  const nlohmann::json bounces = settings.value("bounces", nlohmann::json(0));
  if (!bounces.is_number_integer() || bounces.get<int64_t>() < 0 ||
      bounces.get<int64_t>() > 100000)
    return Status::error(reportPath + ": settings.bounces is not a bounce count: " +
                         bounces.dump());
  return int(bounces.get<int64_t>());
}

Result<BakedProbes> loadBakedProbes(const std::string& outDir) {
  BakedProbes out;
  const fs::path dir(outDir);
  out.transportPath = (dir / "transport.agt").string();

  // The bake's settings, when its report is there (an engine's copy of the transport alone is
  // solved with the bake's defaults).
  const std::string reportPath = (dir / "report.json").string();
  std::error_code ec;
  if (fs::exists(reportPath, ec)) {
    Result<std::string> text = readFile(reportPath);
    if (!text) return text.status();
    const nlohmann::json report = nlohmann::json::parse(text.value(), nullptr, false);
    if (report.is_discarded() || !report.is_object() || !report.contains("settings") ||
        !report["settings"].is_object())
      return Status::error(reportPath + ": not a bake report");
    const nlohmann::json& settings = report["settings"];
    Result<int> bounces = bakedBounces(settings, reportPath);
    if (!bounces) return bounces.status();
    const nlohmann::json dering = settings.value("probeDering", nlohmann::json(0.0));
    if (!dering.is_number() || !(dering.get<double>() >= 0.0) || !(dering.get<double>() < 1e6))
      return Status::error(reportPath + ": settings.probeDering is not a window: " + dering.dump());
    out.bounces = bounces.value();
    out.deringWindow = dering.get<float>();
  }

  std::string error;
  out.runtime = runtime::Runtime::load(out.transportPath, &error);
  if (!out.runtime) return Status::error(error);
  if (out.runtime->probeCount() == 0)
    return Status::error(out.transportPath +
                         ": has no light probes (baked with --probes none, or --reference)");
  out.runtime->setParallelFor(blockRanges());  // results do not depend on it
  runtime::UpdateOptions update;
  update.maxBounces = out.bounces;
  update.fromScratch = true;
  out.runtime->update(update);
  return out;
}

}  // namespace afterglow::cli
