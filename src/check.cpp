#include "vismask/check.h"

#include <cstdio>
#include <cstdlib>

namespace vismask {

void CheckFailed(const char* file, int line, const char* expr, const char* msg) {
  std::fprintf(stderr, "%s:%d: internal error: CHECK(%s) failed%s%s\n", file, line, expr,
               msg ? ": " : "", msg ? msg : "");
  std::abort();
}

void CheckOpFailed(const char* file, int line, const char* expr, const CheckValue& a,
                   const CheckValue& b) {
  std::fprintf(stderr, "%s:%d: internal error: CHECK(%s) failed: %s against %s\n", file, line, expr,
               a.text, b.text);
  std::abort();
}

}  // namespace vismask
