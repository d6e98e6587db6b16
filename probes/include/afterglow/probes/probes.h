// afterglow_probes: light probes (placement, tetrahedralisation, SH transfer), and later
// reflection probes. See ../shared/DESIGN.md.
#pragma once

namespace afterglow::probes {
const char* libraryName();
}  // namespace afterglow::probes
