// The pipe transport of build/vismask: ranks forked from the calling
// process, one POSIX pipe per ordered pair of ranks. This header, internal
// to the transport's three files, holds its class PipeTransport and its wire
// constants: transport_pipe.cpp has the collectives and MakePipeTransport,
// transport_pipe_process.cpp the ranks' lifecycle (forking, signals,
// reaping, Finish and the exit status), transport_pipe_frames.cpp the frame
// pump (framed reads and writes over the pipes, the wait limit).
//
// Pipe wire format: every message is a frame [uint64 length][length bytes].
// A collective sends exactly one frame to each peer and reads exactly one
// from each, so consecutive calls cannot mix. Finish on a child sends the
// frame [kFinishWord][int64 exit code] to rank 0, which tells a child that
// finished from one that died.
//
// Losing a rank: EOF, EPIPE or ECONNRESET on a peer's pipe, a child that
// died (rank 0 polls waitpid at every call and every kPollMs while waiting)
// or the death of rank 0 (children check getppid and get SIGTERM through
// PR_SET_PDEATHSIG) prints "vismask: rank R: lost rank K (why)" and ends the
// process with kExitLostRank. A process that exits closes its pipes, so the
// others see EOF in turn: nobody waits on a dead rank.
//
// A silent rank (stopped, hung): while a call waits, each awaited peer's
// clock restarts whenever poll reports its pipe ready; a peer silent for the
// wait limit (transport.h) ends the run. Rank 0 kills a silent child with
// SIGKILL (which also ends a stopped one) and exits; a child that finds
// rank 0 silent sends it SIGUSR1 and SIGCONT, and rank 0's SIGUSR1 handler
// removes its temporary files and exits with kExitLostRank. Either way the
// others see EOF. If this rank's own poll loop did not run for kStoppedGap
// (it was stopped itself, or the host suspended), the clocks restart.
#pragma once
#include <poll.h>
#include <signal.h>
#include <sys/types.h>

#include <cstddef>
#include <cstdint>

#include "rank_wait.h"
#include "vismask/core/span.h"
#include "vismask/core/status.h"
#include "vismask/parallel/transport.h"

namespace vismask {

constexpr int kMaxPipeRanks = kMaxRanks;
// Length word of the frame a child sends from Finish (no data frame is this long).
constexpr uint64_t kFinishWord = ~uint64_t{0};
constexpr size_t kWordBytes = sizeof(uint64_t);

class PipeTransport final : public WaitingTransport {
 public:
  PipeTransport() = default;
  ~PipeTransport() override;

  const char* name() const override { return "pipe"; }

  void AllToAll(const Span<const uint8_t>* send, const Span<uint8_t>* recv,
                size_t* recvBytes) override;
  void AllGather(const void* mine, size_t bytes, void* all) override;
  int Finish(int exitCode) override;

  // Creates the pipes and forks the children; each process leaves with its
  // rank. `timeout`: --rank-timeout (0: none).
  Status Start(int ranks, double timeout);

 private:
  void PointToPoint(int peer, void* data, size_t bytes, bool recv) override;

  // This process's ends of the pipes to and from one peer.
  struct Peer {
    int readFd = -1;
    int writeFd = -1;
    pid_t pid = 0;        // rank 0: the child's process id
    bool reaped = false;  // rank 0: waitpid has returned `status`
    int status = 0;
  };
  // The frame being written to one peer in the current call.
  struct OutFrame {
    bool active = false;
    uint64_t word = 0;  // the length word (kFinishWord for a finish frame)
    const uint8_t* data = nullptr;
    uint64_t bytes = 0;
    uint64_t done = 0;  // bytes written, length word included
  };
  // The frame being read from one peer in the current call.
  struct InFrame {
    bool active = false;
    bool exact = false;      // Recv: the length must equal `capacity`
    bool atFinish = false;   // rank 0's Finish: expect a finish frame or EOF
    bool eof = false;        // atFinish: the peer closed without a frame
    bool outOfStep = false;  // atFinish: the peer sent a data frame instead
    uint64_t word = 0;
    uint8_t* data = nullptr;
    uint64_t capacity = 0;
    uint64_t bytes = 0;  // valid once the length word is in
    uint64_t done = 0;
  };

  [[noreturn]] void Lost(int peer, const char* why);
  // Ends the run: `peer` has been silent for `limit` seconds (reading: this
  // rank waited for its bytes; else for it to take this rank's).
  [[noreturn]] void Silent(int peer, bool reading, double limit);
  // Rank 0 about to exit: resume stopped children, so that they can take
  // the SIGTERM rank 0's death sends them.
  void ContinueChildren();
  // Ends the run if a peer is known dead: rank 0 reaps children that died
  // (killed, or exited with kExitLostRank); a child checks its parent.
  void CheckPeers();
  void ReapChild(int peer, bool block);
  // Moves every active frame to and from all peers at once until all are done.
  void Pump(bool atFinish);
  void WriteSome(int peer);
  void ReadSome(int peer);
  void AcceptWord(int peer);
  [[noreturn]] void FinishChild(int exitCode);
  void CloseAll();
  void RestoreSigpipe();

  bool sigpipeSaved_ = false;
  bool sigusr1Saved_ = false;
  pid_t rankZeroPid_ = 0;
  struct sigaction oldSigpipe_ = {};
  struct sigaction oldSigusr1_ = {};
  // When each awaited peer last made its pipe ready in the current Pump.
  double heard_[kMaxPipeRanks];
  Peer peers_[kMaxPipeRanks];
  OutFrame out_[kMaxPipeRanks];
  InFrame in_[kMaxPipeRanks];
  // Scratch of one Pump: the poll set, and the peer (+ kMaxPipeRanks: read side) of each entry.
  pollfd pollFds_[2 * kMaxPipeRanks];
  int pollPeer_[2 * kMaxPipeRanks];
  // Scratch of AllGather (built on AllToAll) and of rank 0's Finish.
  Span<const uint8_t> gatherSend_[kMaxPipeRanks];
  Span<uint8_t> gatherRecv_[kMaxPipeRanks];
  size_t gatherBytes_[kMaxPipeRanks];
  int64_t finishCodes_[kMaxPipeRanks];
};

}  // namespace vismask
