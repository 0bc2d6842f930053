// The grid's walks with the CPU's popcount instruction (Grid::Layout picks
// them when the CPU has one): on x86-64 this file alone is compiled for
// POPCNT, which its baseline lacks. The counts are the same integers either
// way, so the walks find the same hits and steps.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "vismask/accel/grid.h"

#if defined(__x86_64__)
#pragma GCC push_options
#pragma GCC target("popcnt")
#endif

#include "grid_walk.h"

namespace vismask {

VISMASK_GRID_WALKS(true)

}  // namespace vismask

#if defined(__x86_64__)
#pragma GCC pop_options
#endif
