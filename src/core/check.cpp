#include "vismask/core/check.h"

#include <cstdio>
#include <cstdlib>

#include "vismask/core/os.h"

namespace vismask {

void CheckFailed(const char* file, int line, const char* expr, const char* msg) {
  os::PrintErr("%s:%d: internal error: CHECK(%s) failed%s%s\n", file, line, expr, msg ? ": " : "",
               msg ? msg : "");
  os::RemoveTempFiles();  // no output of a failed run is left, not even a temporary one
  std::abort();
}

void CheckOpFailed(const char* file, int line, const char* expr, const CheckValue& a,
                   const CheckValue& b) {
  os::PrintErr("%s:%d: internal error: CHECK(%s) failed: %s against %s\n", file, line, expr, a.text,
               b.text);
  os::RemoveTempFiles();  // as CheckFailed: no output of a failed run is left
  std::abort();
}

}  // namespace vismask
