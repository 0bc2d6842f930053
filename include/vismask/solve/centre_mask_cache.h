// CentreMaskCache: Methods B and C keep the centre masks of local shooters,
// one slot per patch (direct-mapped) while they fit in --mask-cache bytes,
// for the patch's later shots: a local shooter's centre mask depends only on
// its geometry. With `partial` (C, and B when a shot may decide only the
// pixels read downstream) a slot also keeps the mask of the pixels whose
// centre ray is known, and takes twice the bytes. Carved from the
// environment's arena (Layout); none without centre rays.
#pragma once
#include <cstdint>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/solve/mask.h"

namespace vismask {

class CentreMaskCache {
 public:
  // Slots for up to `numPatches` patches in `bytes` bytes of masks of
  // `shape`, none unless `enabled` (also from a measuring arena).
  void Layout(Arena& arena, bool enabled, uint32_t numPatches, uint64_t bytes,
              const MaskShape& shape, bool partial);
  // Every slot empty.
  void Clear();
  // Patch i's slot: false when the cache has no slots. *centre (and with
  // `partial` *known) are its masks; on a miss the slot is taken for i and
  // its masks start all open (and none known) with *miss set, so the caller
  // fills them.
  bool Find(uint32_t i, MaskBits* centre, MaskBits* known, bool* miss);

 private:
  MaskShape shape_;
  bool partial_ = false;
  Span<uint64_t> words_;  // slot by slot: the centre mask (and the known one)
  Span<uint32_t> tag_;    // the local patch each slot holds, or kNoPatch
};

}  // namespace vismask
