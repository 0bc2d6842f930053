// How long a rank waits for a silent peer, and what it says when it gives
// up: one rule for the pipe and MPI transports (transport.h, Failure).
#pragma once
#include <cstdio>

#include "vismask/core/os.h"
#include "vismask/parallel/transport.h"

namespace vismask {

// A gap this long between two turns of a wait loop means this rank itself
// was stopped (or not scheduled): the peers' silence clocks restart.
constexpr double kStoppedGap = 1.0;

// The wait limit: --rank-timeout `timeout` (0: none), or kRankTimeoutScale
// times the run's longest wait so far, whichever is longer.
inline double RankWaitLimit(double timeout, double longestWait) {
  if (timeout <= 0.0) return 0.0;
  double scaled = kRankTimeoutScale * longestWait;
  return scaled > timeout ? scaled : timeout;
}

// "vismask: rank R: rank K sent nothing for S s (--rank-timeout...); ending the run".
inline void PrintSilentRank(int rank, int peer, bool reading, double limit, double timeout) {
  char scaled[96] = "";
  if (limit > timeout)
    std::snprintf(scaled, sizeof scaled,
                  ", %g times this run's longest wait; --rank-timeout is %g s", kRankTimeoutScale,
                  timeout);
  os::PrintErr("vismask: rank %d: rank %d %s for %.3g s (--rank-timeout%s); ending the run\n", rank,
               peer, reading ? "sent nothing" : "took none of this rank's bytes", limit, scaled);
}

}  // namespace vismask
