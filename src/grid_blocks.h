// Grid blocks (internal to src/grid.cpp): the coarse level of the grid, one
// bit per block of kBlock^3 cells saying whether any of its cells holds a
// patch, and the exact jump of Grid::Walk's 3D-DDA across an empty block.
// The jump lands on the cell, with the plane counts, that stepping cell by
// cell would reach, so the walk visits the same cells in the same order and
// counts the same steps (Grid::steps).
#pragma once
#include <cstddef>
#include <cstdint>
#include <limits>

#include "vismask/span.h"

namespace vismask::gridblocks {

constexpr int kShift = 3;  // blocks of 8 x 8 x 8 cells
constexpr int kBlock = 1 << kShift;

// Blocks along an axis of `res` cells (the last one may be partial).
inline int BlockRes(int res) { return (res + kBlock - 1) >> kShift; }

inline size_t BlockCount(const int res[3]) {
  return static_cast<size_t>(BlockRes(res[0])) * BlockRes(res[1]) * BlockRes(res[2]);
}

// Words of the block bitmap.
inline size_t BlockWords(const int res[3]) { return (BlockCount(res) + 63) / 64; }

// Sets block bit b (blocks x-fastest, as cells) iff a cell in it is occupied.
void MarkBlocks(const int res[3], Span<const uint64_t> occupied, Span<uint64_t> blocks);

// One axis of the walk's DDA: the k-th plane (k = 0, 1, ...) is crossed at
// first + k * delta, exactly the walk's formula (a still axis: first
// infinite, delta 0).
struct Axis {
  float first;
  float delta;
};

// Crosses the empty block the walk is in, as the walk's cell steps would:
// left[a] (1 to kBlock) is how many planes along axis a the walk crosses to
// leave the block that way, k[a] the planes crossed so far and t[a] = first +
// k[a] * delta. Steps go to the nearest plane (ties: z, then y, then x, as in
// the walk), so the walk's planes are those of all axes merged by (t, that
// priority): the walk leaves the block at the first of the axes' leaving
// planes, and along every other axis crosses exactly its planes that come
// before that one (counted without branches). Sets crossed[a] and advances k
// and t. Returns false, changing nothing, when that leaving plane is not
// before `limit` (the walk ends inside the block).
inline bool CrossBlock(const Axis axis[3], const int left[3], float limit, float k[3], float t[3],
                       int crossed[3]) {
  float last[3];
  for (int a = 0; a < 3; ++a)
    last[a] = axis[a].first + (k[a] + static_cast<float>(left[a] - 1)) * axis[a].delta;
  int out = last[0] < last[1] && last[0] < last[2] ? 0 : (last[1] < last[2] ? 1 : 2);
  float tOut = last[out];
  if (!(tOut < limit)) return false;
  for (int a = 0; a < 3; ++a) {
    if (a == out || !(axis[a].delta > 0.0f)) {
      crossed[a] = a == out ? left[a] : 0;
      continue;
    }
    const Axis& x = axis[a];
    // Plane m comes before the leaving plane: nearer, or as near and preferred.
    auto before = [&](float m) {
      float tm = x.first + m * x.delta;
      return tm < tOut || (tm == tOut && a > out);
    };
    float k0 = k[a], kMax = k0 + static_cast<float>(left[a] - 1);  // plane kMax is not before
    float e = (tOut - x.first) / x.delta;                           // estimate, then exact
    float m = e >= k0 ? (e < kMax ? static_cast<float>(static_cast<int>(e)) : kMax) : k0;
    if (before(m)) {
      do m += 1.0f;
      while (m < kMax && before(m));
    } else {
      while (m > k0 && !before(m - 1.0f)) m -= 1.0f;
    }
    crossed[a] = static_cast<int>(m - k0);
  }
  for (int a = 0; a < 3; ++a) {
    k[a] += static_cast<float>(crossed[a]);
    t[a] = axis[a].first + k[a] * axis[a].delta;
  }
  return true;
}

}  // namespace vismask::gridblocks
