// CentreMaskCache: the slots of local shooters' centre masks.
#include "vismask/solve/centre_mask_cache.h"

#include <algorithm>

#include "vismask/solve/patch.h"

namespace vismask {

void CentreMaskCache::Layout(Arena& arena, bool enabled, uint32_t numPatches, uint64_t bytes,
                             const MaskShape& shape, bool partial) {
  shape_ = shape;
  partial_ = partial;
  size_t slots = 0, perSlot = (partial ? 2 : 1) * shape.words();
  if (enabled && perSlot > 0) slots = std::min<uint64_t>(numPatches, bytes / (8 * perSlot));
  words_ = arena.Alloc<uint64_t>(slots * perSlot);
  tag_ = arena.Alloc<uint32_t>(slots);
}

void CentreMaskCache::Clear() {
  for (uint32_t& tag : tag_) tag = kNoPatch;
}

bool CentreMaskCache::Find(uint32_t i, MaskBits* centre, MaskBits* known, bool* miss) {
  *miss = false;
  if (tag_.empty()) return false;
  size_t slot = i % tag_.size(), w = shape_.words(), per = partial_ ? 2 : 1;
  *centre = MaskBits(words_.subspan(slot * per * w, w), shape_);
  if (partial_) *known = MaskBits(words_.subspan((slot * per + 1) * w, w), shape_);
  if (tag_[slot] != i) {
    centre->SetAllOpen();
    if (partial_) known->SetAllClosed();
    tag_[slot] = i;
    *miss = true;
  }
  return true;
}

}  // namespace vismask
