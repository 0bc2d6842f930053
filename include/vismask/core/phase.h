// The phase a render is in. The no-heap-after-init property is defined on it:
// no allocation may happen while the phase is kSolve or kOutput. The
// allocation-counting test (tests/alloc_test.cpp) reads this marker.
#pragma once

namespace vismask {

enum class Phase : int { kInit = 0, kSolve = 1, kOutput = 2, kDone = 3 };

void SetPhase(Phase phase);
Phase CurrentPhase();

}  // namespace vismask
