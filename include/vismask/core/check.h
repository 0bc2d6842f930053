// Internal assertions. CHECK is always on; DCHECK is for hot loops and
// compiles out where NDEBUG is defined: release builds (the Makefile's
// default) drop it, SAN=1 and DEBUG=1 builds keep it. A failed check is a
// bug in vismask (never a user error): it prints file:line and the
// expression (CHECK_EQ and the like: both operands too), then aborts. User
// errors go through Status (status.h) instead.
#pragma once
#include <cstdio>
#include <type_traits>

namespace vismask {
[[noreturn]] void CheckFailed(const char* file, int line, const char* expr, const char* msg);

// An operand of CHECK_EQ and the like, printed into a fixed buffer.
struct CheckValue {
  char text[40];
  template <class T>
  explicit CheckValue(const T& v) {
    if constexpr (std::is_floating_point<T>::value)
      std::snprintf(text, sizeof text, "%.17g", static_cast<double>(v));
    else if constexpr (std::is_enum<T>::value)
      std::snprintf(text, sizeof text, "%lld", static_cast<long long>(v));
    else if constexpr (std::is_signed<T>::value)
      std::snprintf(text, sizeof text, "%lld", static_cast<long long>(v));
    else if constexpr (std::is_unsigned<T>::value)
      std::snprintf(text, sizeof text, "%llu", static_cast<unsigned long long>(v));
    else if constexpr (std::is_pointer<T>::value)
      std::snprintf(text, sizeof text, "%p", static_cast<const void*>(v));
    else
      std::snprintf(text, sizeof text, "?");
  }
};

[[noreturn]] void CheckOpFailed(const char* file, int line, const char* expr, const CheckValue& a,
                                const CheckValue& b);
}  // namespace vismask

#define CHECK(cond) ((cond) ? (void)0 : ::vismask::CheckFailed(__FILE__, __LINE__, #cond, nullptr))
#define CHECK_MSG(cond, msg) \
  ((cond) ? (void)0 : ::vismask::CheckFailed(__FILE__, __LINE__, #cond, (msg)))

// CHECK_EQ(a, b) and the like: on failure, both operands' values as well.
#define VISMASK_CHECK_OP(a, op, b)                                    \
  do {                                                                \
    const auto& vismask_a_ = (a);                                     \
    const auto& vismask_b_ = (b);                                     \
    if (!(vismask_a_ op vismask_b_))                                  \
      ::vismask::CheckOpFailed(__FILE__, __LINE__, #a " " #op " " #b, \
                               ::vismask::CheckValue(vismask_a_),     \
                               ::vismask::CheckValue(vismask_b_));    \
  } while (0)
#define CHECK_EQ(a, b) VISMASK_CHECK_OP(a, ==, b)
#define CHECK_NE(a, b) VISMASK_CHECK_OP(a, !=, b)
#define CHECK_LE(a, b) VISMASK_CHECK_OP(a, <=, b)
#define CHECK_LT(a, b) VISMASK_CHECK_OP(a, <, b)
#define CHECK_GE(a, b) VISMASK_CHECK_OP(a, >=, b)
#define CHECK_GT(a, b) VISMASK_CHECK_OP(a, >, b)

#ifdef NDEBUG
#define DCHECK(cond) ((void)0)
#else
#define DCHECK(cond) CHECK(cond)
#endif
