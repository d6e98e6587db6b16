// Pictures of lightmap atlases: each chart filled in its own colour with a darker outline, so a
// person can judge a layout at a glance.
#pragma once

#include <string>
#include <vector>

#include "afterglow/core/atomic_file.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::uv {

// Writes one PNG per atlas: `<pathPrefix><atlas index>.png`. Returns the final paths written.
Result<std::vector<std::string>> writeAtlasPictures(const scenes::Scene& scene,
                                                    const std::string& pathPrefix,
                                                    AtomicOutput& output);

}  // namespace afterglow::uv
