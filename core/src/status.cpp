#include "afterglow/core/status.h"

#include <cstdarg>
#include <cstdio>
#include <cstdlib>

#include "afterglow/core/check.h"

namespace afterglow {

std::string format(const char* fmt, ...) {
  va_list args;
  va_start(args, fmt);
  va_list copy;
  va_copy(copy, args);
  int size = std::vsnprintf(nullptr, 0, fmt, copy);
  va_end(copy);
  std::string out(size > 0 ? size_t(size) : 0, '\0');
  if (size > 0) std::vsnprintf(out.data(), out.size() + 1, fmt, args);
  va_end(args);
  return out;
}

namespace detail {
void checkFailed(const char* expr, const char* file, int line, const char* message) {
  std::fprintf(stderr, "afterglow: internal check failed at %s:%d: %s (%s)\n", file, line, message,
               expr);
  std::abort();
}
}  // namespace detail

}  // namespace afterglow
