// AG_CHECK: invariants that stay on in release builds. A failed check is a bug in afterglow,
// not bad input (bad input gets a Status), so it prints where and aborts.
#pragma once

namespace afterglow::detail {
[[noreturn]] void checkFailed(const char* expr, const char* file, int line, const char* message);
}

#define AG_CHECK(cond, message)                                                \
  do {                                                                         \
    if (!(cond)) ::afterglow::detail::checkFailed(#cond, __FILE__, __LINE__, message); \
  } while (0)
