// Internal assertions. CHECK is always on; DCHECK compiles out with NDEBUG and
// is for hot loops. A failed check is a bug in vismask (never a user error):
// it prints file:line and the expression, then aborts. User errors go through
// Status (status.h) instead.
#pragma once

namespace vismask {
[[noreturn]] void CheckFailed(const char* file, int line, const char* expr, const char* msg);
}  // namespace vismask

#define CHECK(cond) \
  ((cond) ? (void)0 : ::vismask::CheckFailed(__FILE__, __LINE__, #cond, nullptr))
#define CHECK_MSG(cond, msg) \
  ((cond) ? (void)0 : ::vismask::CheckFailed(__FILE__, __LINE__, #cond, (msg)))

#ifdef NDEBUG
#define DCHECK(cond) ((void)0)
#else
#define DCHECK(cond) CHECK(cond)
#endif
