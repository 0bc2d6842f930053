// SlotIndex: the foreign queue's bookkeeping beside its fixed slots: which
// slot holds a shooter's shot (an open-addressed table keyed by shooter id
// and shot index, linear probing, deletion by backward shift) and which
// slots are free (a bitmap, the lowest free slot first). Both carved from
// the arena at init; every operation is O(1) expected, where the scans they
// replace cost a pass over every slot for each packet and shot.
#pragma once
#include <cstdint>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"

namespace vismask {

class SlotIndex {
 public:
  // Room for `slots` slots (also from a measuring arena).
  void Layout(Arena& arena, uint32_t slots);
  // Every slot free, the table empty.
  void Clear();
  // The slot holding (shooter, shot), or -1.
  int Find(uint32_t shooter, uint32_t shot) const;
  // Takes the lowest free slot for (shooter, shot), which must not be held
  // yet; -1 when every slot is taken.
  int Take(uint32_t shooter, uint32_t shot);
  // Frees slot `slot`, which holds (shooter, shot).
  void Release(int slot, uint32_t shooter, uint32_t shot);

 private:
  static uint64_t Key(uint32_t shooter, uint32_t shot) { return (uint64_t(shooter) << 32) | shot; }
  uint32_t Home(uint64_t key) const;
  uint32_t mask_ = 0;        // table size - 1 (a power of two)
  Span<uint64_t> keys_;      // the table: the key of each entry
  Span<int32_t> entries_;    // its slot, -1 where empty
  Span<uint64_t> freeBits_;  // bit s set: slot s free
  uint32_t slots_ = 0;
};

}  // namespace vismask
