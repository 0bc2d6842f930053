// MaxTree: which patch has the most unshot power, in O(1), kept current in
// O(log n) per change. A tournament tree over a fixed key array, carved from
// the arena; ties go to the lower index, so the choice is deterministic.
// With ties (Layout's `ties`), equal keys go to the lower tie value first
// (the foreign queue: the lower shooter id and shot, whatever the slot).
#pragma once
#include <cstdint>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/solve/patch.h"

namespace vismask {

class MaxTree {
 public:
  // Carves room for `n` keys, and with `ties` their tie values (also from a
  // measuring arena).
  void Layout(Arena& arena, uint32_t n, bool ties = false);
  // Sets every key to `key` (and every tie value to 0).
  void Clear(double key = 0.0);
  // Sets key `i` and its tie value (trees laid out with ties).
  void Set(uint32_t i, double key, uint64_t tie) {
    tie_[i] = tie;
    Set(i, key);
  }
  // Sets key `i` and replays its path to the root.
  void Set(uint32_t i, double key);
  // Raises key `i` to `key` (>= its current key): climbs only while `i` wins,
  // so a receiver that stays small costs one or two comparisons.
  void Increase(uint32_t i, double key);
  double Key(uint32_t i) const { return key_[i]; }
  // The index with the largest key (lowest index on ties); kNoPatch if n == 0.
  uint32_t Top() const { return n_ == 0 ? kNoPatch : node_[1]; }

 private:
  uint32_t Winner(uint32_t a, uint32_t b) const;
  uint32_t n_ = 0;
  uint32_t leaves_ = 1;  // power of two >= n
  Span<double> key_;
  Span<uint64_t> tie_;   // empty: ties by index alone
  Span<uint32_t> node_;  // node_[1..leaves_-1]; leaves are implicit
};

}  // namespace vismask
