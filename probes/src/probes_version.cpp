// Placeholder translation unit so the library exists before its first module lands.
#include "afterglow/probes/probes.h"

namespace afterglow::probes {
const char* libraryName() { return "afterglow_probes"; }
}  // namespace afterglow::probes
