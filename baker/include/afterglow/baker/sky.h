// The sky: an equirectangular HDR image projected onto the SH L2 basis the transport stores.
// The bake reads it before its first ray; `render --reference` reads it back from a report.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "afterglow/core/status.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::baker {

// Reads a lat-long image (any format OpenImageIO reads; linear radiance) and projects it onto
// real SH L2 over world directions, in the basis of the sky transfer (sampling::shBasis). The
// image's u runs around +Y (glTF's up) from +X toward +Z; v runs from +Y (top row) to −Y.
Status projectEquirectSky(const std::string& path, glm::vec3 sh[runtime::kShCount]);

}  // namespace afterglow::baker
