#include "vismask/solve/slot_index.h"

#include "vismask/core/check.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/rng.h"

namespace vismask {

void SlotIndex::Layout(Arena& arena, uint32_t slots) {
  slots_ = slots;
  // At most half full, so probes stay short.
  uint32_t size = 1;
  while (size < 2 * slots) size <<= 1;
  mask_ = slots > 0 ? size - 1 : 0;
  keys_ = arena.Alloc<uint64_t>(slots > 0 ? size : 0);
  entries_ = arena.Alloc<int32_t>(slots > 0 ? size : 0);
  freeBits_ = arena.Alloc<uint64_t>((size_t(slots) + 63) / 64);
}

void SlotIndex::Clear() {
  for (int32_t& e : entries_) e = -1;
  for (size_t w = 0; w < freeBits_.size(); ++w) {
    const uint32_t lo = static_cast<uint32_t>(64 * w), n = slots_ - lo;
    freeBits_[w] = n >= 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1;
  }
}

uint32_t SlotIndex::Home(uint64_t key) const {
  return static_cast<uint32_t>(Mix64(key)) & mask_;
}

int SlotIndex::Find(uint32_t shooter, uint32_t shot) const {
  if (entries_.empty()) return -1;
  const uint64_t key = Key(shooter, shot);
  for (uint32_t i = Home(key);; i = (i + 1) & mask_) {
    if (entries_[i] < 0) return -1;
    if (keys_[i] == key) return entries_[i];
  }
}

int SlotIndex::Take(uint32_t shooter, uint32_t shot) {
  int slot = -1;
  for (size_t w = 0; w < freeBits_.size() && slot < 0; ++w)
    if (freeBits_[w] != 0) slot = static_cast<int>(64 * w + CountTrailingZeros(freeBits_[w]));
  if (slot < 0) return -1;
  freeBits_[size_t(slot) >> 6] &= ~(uint64_t(1) << (slot & 63));
  const uint64_t key = Key(shooter, shot);
  uint32_t i = Home(key);
  while (entries_[i] >= 0) {
    DCHECK(keys_[i] != key);
    i = (i + 1) & mask_;
  }
  keys_[i] = key;
  entries_[i] = slot;
  return slot;
}

void SlotIndex::Release(int slot, uint32_t shooter, uint32_t shot) {
  const uint64_t key = Key(shooter, shot);
  uint32_t i = Home(key);
  while (!(entries_[i] == slot && keys_[i] == key)) {
    CHECK_MSG(entries_[i] >= 0, "released a slot the index does not hold");
    i = (i + 1) & mask_;
  }
  // Backward-shift deletion: pull later entries of the probe run into the
  // hole when their home does not lie between the hole and them.
  uint32_t hole = i;
  for (uint32_t j = (hole + 1) & mask_; entries_[j] >= 0; j = (j + 1) & mask_) {
    const uint32_t home = Home(keys_[j]);
    const bool between = hole <= j ? (home > hole && home <= j) : (home > hole || home <= j);
    if (between) continue;
    keys_[hole] = keys_[j];
    entries_[hole] = entries_[j];
    hole = j;
  }
  entries_[hole] = -1;
  freeBits_[size_t(slot) >> 6] |= uint64_t(1) << (slot & 63);
}

}  // namespace vismask
