// FMax and FMin: std::fmax and std::fmin (float), inline, for the hot paths
// (ray sampling, slabs, a hit's patch parameters). On baseline x86-64 GCC
// calls libm's fmaxf and fminf for them: 2% of a Method B run's
// instructions. These give exactly what glibc's x86-64 functions give
// (maxss / minss: x when x > y, resp. x < y, else y, so of two zeros the
// second; the other operand when one is a NaN), so x86-64's outputs keep
// their bytes. On aarch64 libm's fmaxf is fmaxnm, which takes +0 over -0
// in either order: these make aarch64 agree with x86-64 there too.
#pragma once

namespace vismask {

inline float FMax(float x, float y) {
  return (x > y || y != y) ? x : y;
}
inline float FMin(float x, float y) {
  return (x < y || y != y) ? x : y;
}

}  // namespace vismask
