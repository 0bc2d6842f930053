// Transport: how the ranks of a run move bytes. The radiosity code packs and
// unpacks everything itself; a transport only moves byte blocks between
// ranks, with buffers the caller made at init (no allocation per message).
// Implementations live in platform/ and are chosen by what the Makefile
// links: build/vismask has `loop` (one process) and `pipe` (forked processes
// over POSIX pipes); build/vismask-mpi has `mpi` (Open MPI).
//
// Failure: a rank that dies or a connection that closes is fatal. The
// transport prints "vismask: rank R: lost rank K (...)" and ends the process
// with exit status 3 (kExitLostRank), so no rank ever waits forever on a dead
// one. A peer that is alive but silent (stopped, hung) is fatal too: a rank
// that waits in a call and hears nothing from a peer for the wait limit
// prints "vismask: rank R: rank K sent nothing for S s (--rank-timeout);
// ending the run" and ends the run with status 3 (pipe: rank 0 kills the
// silent child, a child ends rank 0; mpi: MPI_Abort). The wait limit is
// TransportRequest::rankTimeout, or 10 times the longest wait a call of this
// run has ended normally after, if that is longer; time this rank itself
// was stopped does not count. Before a rank ends the process this way it
// removes the temporary output files (os::RemoveTempFiles). Calls return
// only on success.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "vismask/core/span.h"
#include "vismask/core/status.h"

namespace vismask {

constexpr int kExitLostRank = 3;
// The default --rank-timeout, seconds (see Failure above).
constexpr double kDefaultRankTimeout = 60.0;
// A call's wait limit is at least this many times the longest wait of the run so far.
constexpr double kRankTimeoutScale = 10.0;

// The most ranks a run may have, whatever the transport: rank-indexed
// tables (the pipe transport's peers, init's agreement on every rank's
// status) are fixed arrays of this size. Both transports refuse a larger
// world with RankCountError.
constexpr int kMaxRanks = 256;

// Empty if `ranks` is a run's possible rank count, else the user's error.
inline std::string RankCountError(int ranks, const char* what) {
  if (ranks >= 1 && ranks <= kMaxRanks) return "";
  return "vismask: " + std::string(what) + " " + std::to_string(ranks) + ": a run has 1 to " +
         std::to_string(kMaxRanks) + " ranks";
}

// Empty unless `transport` is "loop" with several ranks, the one
// combination of the two that cannot run (loop is one process): then the
// user's error. ParseArgs refuses it; MakeTransport refuses it again for a
// request made without the command line.
inline std::string LoopTransportError(const std::string& transport, int ranks) {
  if (transport != "loop" || ranks <= 1) return "";
  return "vismask: --transport loop runs one process; use --transport pipe with --ranks";
}

class Transport {
 public:
  virtual ~Transport() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  virtual const char* name() const = 0;
  // How many of the run's ranks share this rank's host (and its memory):
  // the default memory budget is the host's available memory over them.
  virtual int ranksOnHost() const { return size(); }

  // Every rank sends send[r].size() bytes to each rank r (send[rank()] is not
  // sent) and receives into recv[r] what rank r sent it; recvBytes[r] gets
  // the size (recvBytes[rank()] = 0). The three arrays have size() entries.
  // Each recv[r] must be large enough for what r can send (a bigger block is
  // a CHECK failure). mpi: the send blocks must lie within 2 GiB of each
  // other, and so must the receive blocks (one arena region does).
  virtual void AllToAll(const Span<const uint8_t>* send, const Span<uint8_t>* recv,
                        size_t* recvBytes) = 0;
  // Every rank contributes `bytes` bytes (the same on every rank); `all`
  // (size() * bytes) receives every rank's block in rank order, its own
  // included. `mine` may be the rank's own block of `all`.
  virtual void AllGather(const void* mine, size_t bytes, void* all) = 0;
  // Blocking point-to-point transfer of exactly `bytes` bytes; the sizes of
  // a Send and its Recv must agree (CHECK). Send may wait until the receiver
  // takes the bytes, so two ranks must not Send to each other at once.
  virtual void Send(int to, const void* data, size_t bytes) = 0;
  virtual void Recv(int from, void* data, size_t bytes) = 0;

  // Ends this rank's part of the run with `exitCode`; no call may follow.
  // Every rank must call it, on every path after MakeTransport succeeded. On
  // rank 0 it returns the status to report (the worst of all ranks'; pipe:
  // kExitLostRank if a child died or exited without Finish); on other ranks
  // of a transport that made them (pipe), the process ends here; mpi: every
  // rank returns the worst code.
  virtual int Finish(int exitCode) = 0;
};

// What the command line asked for.
struct TransportRequest {
  std::string name;  // "loop", "pipe", "mpi" or "" (the binary's default)
  int ranks = 1;     // --ranks (pipe)
  // --rank-timeout: seconds a waiting rank hears nothing from a peer before
  // it ends the run (0: wait forever).
  double rankTimeout = kDefaultRankTimeout;
};

// The transport this binary provides for `request` (platform/). Called once,
// early in init: the pipe transport forks here, so every process carries on
// from this call with its own rank. On error (an unknown or unavailable
// transport, or a rank count outside 1..kMaxRanks) returns null and sets
// *error.
std::unique_ptr<Transport> MakeTransport(const TransportRequest& request, Status* error);

}  // namespace vismask
