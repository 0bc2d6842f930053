// The name of an enumerator, from a table of the enum's names.
#pragma once
#include <cstddef>

namespace vismask {

// names[value]: `names` lists the names of the enum's enumerators, which
// run 0, 1, ... kLast, in that order (a missing or extra name does not
// compile); "?" for a value past kLast.
template <auto kLast, size_t N>
const char* EnumName(decltype(kLast) value, const char* const (&names)[N]) {
  static_assert(N == static_cast<size_t>(kLast) + 1, "one name per enumerator");
  const size_t k = static_cast<size_t>(value);
  return k < N ? names[k] : "?";
}

}  // namespace vismask
