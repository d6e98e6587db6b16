// The process's memory use, for reports and benchmarks.
#pragma once

#include <cstddef>

namespace afterglow {

// Peak resident memory of this process so far, bytes (getrusage); 0 when unknown.
size_t peakMemoryBytes();

}  // namespace afterglow
