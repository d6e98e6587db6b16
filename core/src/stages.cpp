#include "afterglow/core/stages.h"

namespace afterglow {

const char* stageName(Stage stage) {
  // In the enum's order; report.json's keys, so existing reports keep their names.
  static const char* const kNames[kStageCount] = {
      "load",  "uv",    "probe placement", "raytracer", "texels", "reference",
      "gather", "clusters", "direct",       "refine",    "links",  "probes",
      "solve", "dilate", "reflection capture", "reflection passes", "write"};
  const int i = int(stage);
  return i >= 0 && i < kStageCount ? kNames[i] : "?";
}

std::string stageStep(Stage stage, const char* step) {
  return std::string(stageName(stage)) + ": " + step;
}

}  // namespace afterglow
