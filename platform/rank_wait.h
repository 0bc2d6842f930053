// How long a rank waits for a silent peer, and what it says when it gives
// up: one rule for the pipe and MPI transports (transport.h, Failure), and
// the base class that holds its state for both.
#pragma once
#include <cstdio>

#include "vismask/core/check.h"
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

// What the pipe and MPI transports share: this rank's place in the world,
// whether Finish was called, the state of the silence rule (Failure in
// transport.h), and Send and Recv's checks. Each transport sets rank_,
// size_ and timeout_ in its Start, sets finished_ in Finish, and calls
// NoteWait with every call's wait that ended normally.
class WaitingTransport : public Transport {
 public:
  WaitingTransport() = default;
  WaitingTransport(const WaitingTransport&) = delete;
  WaitingTransport& operator=(const WaitingTransport&) = delete;

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void Send(int to, const void* data, size_t bytes) final {
    CheckPointToPoint(to);
    PointToPoint(to, const_cast<void*>(data), bytes, false);
  }
  void Recv(int from, void* data, size_t bytes) final {
    CheckPointToPoint(from);
    PointToPoint(from, data, bytes, true);
  }

 protected:
  // Send (recv false) or Recv exactly `bytes` bytes with `peer`, another
  // rank of the world, before Finish.
  virtual void PointToPoint(int peer, void* data, size_t bytes, bool recv) = 0;
  void CheckPointToPoint(int peer) const {
    CHECK_MSG(!finished_, "transport used after Finish");
    CHECK(peer >= 0 && peer < size_ && peer != rank_);
  }
  // The wait limit now, 0 for none.
  double WaitLimit() const { return RankWaitLimit(timeout_, longestWait_); }
  // A call's wait of `waited` seconds ended normally.
  void NoteWait(double waited) {
    if (waited > longestWait_) longestWait_ = waited;
  }
  // PrintSilentRank for this rank: `peer` was silent for `limit` seconds.
  void PrintSilent(int peer, bool reading, double limit) const {
    PrintSilentRank(rank_, peer, reading, limit, timeout_);
  }

  int rank_ = 0;
  int size_ = 1;
  double timeout_ = 0.0;  // --rank-timeout; 0: none
  bool finished_ = false;

 private:
  double longestWait_ = 0.0;  // the longest wait of the run so far, seconds
};

}  // namespace vismask
