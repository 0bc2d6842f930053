#include "vismask/core/phase.h"

#include <atomic>

namespace vismask {

namespace {
std::atomic<int> gPhase{static_cast<int>(Phase::kInit)};
}

void SetPhase(Phase phase) {
  gPhase.store(static_cast<int>(phase), std::memory_order_relaxed);
}
Phase CurrentPhase() {
  return static_cast<Phase>(gPhase.load(std::memory_order_relaxed));
}

}  // namespace vismask
