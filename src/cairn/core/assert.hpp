#pragma once
/// \file
/// CAIRN_ASSERT: programmer errors only (broken preconditions inside cairn), never user data.
/// Bad input from a file, flag or config throws cairn::io::ParseError instead.

#include <cstdio>
#include <cstdlib>

namespace cairn::core::detail {
[[noreturn]] inline void assert_fail(const char* expr, const char* file, int line, const char* msg) {
  std::fprintf(stderr, "cairn: internal error at %s:%d: %s (assertion `%s` failed)\n", file, line,
               msg, expr);
  std::abort();
}
}  // namespace cairn::core::detail

#define CAIRN_ASSERT(expr, msg)                                                  \
  do {                                                                           \
    if (!(expr)) ::cairn::core::detail::assert_fail(#expr, __FILE__, __LINE__, msg); \
  } while (false)
