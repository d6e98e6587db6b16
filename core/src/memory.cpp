#include "afterglow/core/memory.h"

#include <sys/resource.h>

namespace afterglow {

size_t peakMemoryBytes() {
  struct rusage usage {};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return size_t(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

}  // namespace afterglow
