// Mask direction tables for tests: MaskDirections for one resolution, laid
// out and filled in their own arena, as an environment's are at init.
#pragma once
#include <cstdint>

#include "vismask/core/arena.h"
#include "vismask/solve/mask.h"

namespace vismask::test {

struct MaskTables {
  Arena arena{1};
  MaskDirections dirs;
  explicit MaskTables(uint32_t res) {
    Arena measure = Arena::Measure();
    dirs.Layout(measure, res);
    arena = Arena(measure.used());
    dirs.Layout(arena, res);
    dirs.Fill();
  }
};

}  // namespace vismask::test
