// The transport of build/vismask-mpi: `mpi`, over Open MPI's MPI_COMM_WORLD
// (run under `mpirun -np N`; without mpirun it is a singleton of one rank).
//
// Every call is point-to-point and non-blocking: MPI_Irecv and MPI_Isend
// straight from and into the caller's buffers (AllToAll receives into each
// whole buffer and takes the size from MPI_Get_count; Finish gathers every
// rank's code on rank 0 and sends back the worst), completed by one loop of
// MPI_Testsome over request arrays made in Start. The loop knows which peers
// it still waits for, so a silent one can be named; it spins for
// kSpinSeconds after the last completion, then sleeps between tests, so
// that a rank waiting for a slow or stopped peer does not burn a core. The bytes moved are the same
// as with blocking collectives.
//
// Faults. A peer silent for the wait limit (transport.h, --rank-timeout)
// makes the waiting rank print "vismask: rank R: rank K sent nothing for S
// s (--rank-timeout); ending the run", remove its temporary files and call
// MPI_Abort(MPI_COMM_WORLD, 3): mpirun kills every rank, a stopped one
// included, and exits with status 3. A dead rank: MPI_COMM_WORLD returns
// errors (MPI_ERRORS_RETURN) and Fail turns one into "vismask: rank R: lost
// rank K (...)" and exit status 3, but in practice Open MPI 4.1 (no ULFM)
// never returns an error for a dead peer: its runtime handles it. Observed
// on Open MPI 4.1.4 (Debian 12), one node, `mpirun -np 2..4
// --oversubscribe`, a rank killed with SIGKILL in the middle of the solve:
// mpirun notices at once, sends the others SIGCONT, then SIGTERM 1 s later;
// each survivor's SIGTERM handler (os.h) removes rank 0's temporary files
// and, if the rank was waiting, prints "vismask: rank R: ended by SIGTERM
// while waiting for rank K"; mpirun prints "mpirun noticed that process rank
// K ... exited on signal 9" and exits with 137 (128 + SIGKILL), not 3. A
// rank that exits on its own with status 3 makes mpirun kill the rest and
// exit 3. If mpirun itself is killed, the ranks end within 3 s.
#include <mpi.h>
#include <sched.h>
#include <time.h>

#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "rank_wait.h"
#include "vismask/core/check.h"
#include "vismask/core/os.h"
#include "vismask/parallel/transport.h"

namespace vismask {
namespace {

// MPI counts are int: Send/Recv move larger messages in chunks of this size.
constexpr size_t kChunkBytes = size_t{1} << 30;
// One tag per kind of call, so that no message of one can match another.
constexpr int kTagPoint = 0, kTagAllToAll = 1, kTagAllGather = 2, kTagFinish = 3;
// A waiting rank tests without pause for kSpinSeconds after the last
// completion, then sleeps between tests an eighth of the time since, from
// kMinNap to kMaxNap: a wait is lengthened by at most 1/8 (and 1 ms).
constexpr double kSpinSeconds = 1e-3;
constexpr double kMinNap = 5e-5, kMaxNap = 1e-3;

class MpiTransport final : public WaitingTransport {
 public:
  MpiTransport() = default;
  ~MpiTransport() override;

  const char* name() const override { return "mpi"; }
  int ranksOnHost() const override { return ranksOnHost_; }

  void AllToAll(const Span<const uint8_t>* send, const Span<uint8_t>* recv,
                size_t* recvBytes) override;
  void AllGather(const void* mine, size_t bytes, void* all) override;
  int Finish(int exitCode) override;

  // MPI_Init, errors returned instead of aborting, and the request arrays.
  Status Start(const TransportRequest& request);

 private:
  // An MPI error is a lost rank: `peer`, or -1 when MPI does not say which.
  void Check(int rc, int peer, const char* call);
  // Records request posted_ (just made by an MPI_Irecv or MPI_Isend
  // returning `rc`) as one to or from `peer`.
  void Post(int rc, int peer, bool recv, const char* call);
  // Completes the posted requests; ends the run if a peer stays silent.
  void Wait(const char* call);
  [[noreturn]] void Silent(int peer, bool reading, double limit);
  // Moves `bytes` in messages of at most kChunkBytes.
  void PointToPoint(int peer, void* data, size_t bytes, bool recv) override;

  int ranksOnHost_ = 1;  // the size of this rank's shared-memory communicator
  bool started_ = false;
  // The requests of one call (at most a receive and a send per peer), made in Start.
  int posted_ = 0;
  std::unique_ptr<MPI_Request[]> requests_;
  std::unique_ptr<MPI_Status[]> statuses_;
  std::unique_ptr<int[]> indices_;
  std::unique_ptr<int[]> peerOf_;      // of each request
  std::unique_ptr<uint8_t[]> isRecv_;  // of each request
  std::unique_ptr<int[]> received_;    // bytes each completed receive took
  std::unique_ptr<double[]> heard_;    // per peer: when a request with it last completed
  std::unique_ptr<int[]> codes_;       // rank 0's Finish: every rank's code
  uint8_t dummy_ = 0;                  // a valid address for a call that moves no bytes
};

MpiTransport::~MpiTransport() {
  if (!started_ || finished_) return;
  // Other ranks may be waiting in a collective: end the whole job, not just this rank.
  os::PrintErr("vismask: rank %d: the mpi transport ended without Finish; aborting the job\n",
               rank_);
  os::RemoveTempFiles();
  MPI_Abort(MPI_COMM_WORLD, kExitLostRank);
}

Status MpiTransport::Start(const TransportRequest& request) {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  }
  started_ = true;
  timeout_ = request.rankTimeout;
  // Errors come back as return codes (Check turns them into a lost rank).
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  if (request.ranks != 1 && request.ranks != size_) {
    // Every rank sees the same request and world, so all of them end here.
    finished_ = true;
    MPI_Finalize();
    return Status::Error("vismask: --ranks " + std::to_string(request.ranks) +
                         " does not match the MPI world size " + std::to_string(size_) +
                         " (mpirun -np sets the number of ranks)");
  }
  std::string tooMany = RankCountError(size_, "the MPI world size is");
  if (!tooMany.empty()) {
    // Every rank would say it: rank 0 alone does, and says it here, before
    // the barrier. The others exit 2 as soon as they are past it, and
    // mpirun then ends the job: rank 0's line, printed after returning, was
    // sometimes lost (make stability, 257 ranks on 2 cores).
    finished_ = true;
    if (rank_ == 0) {
      std::fprintf(stderr, "%s (mpirun -np)\n", tooMany.c_str());
      std::fflush(stderr);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    MPI_Finalize();
    return Status::Error("");  // said above, by rank 0
  }
  MPI_Comm host;
  if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &host) ==
      MPI_SUCCESS) {
    MPI_Comm_size(host, &ranksOnHost_);
    MPI_Comm_free(&host);
  } else {
    ranksOnHost_ = size_;  // unknown: as if every rank shared this host
  }
  const size_t most = 2 * static_cast<size_t>(size_);
  requests_.reset(new MPI_Request[most]);
  for (size_t i = 0; i < most; ++i) requests_[i] = MPI_REQUEST_NULL;
  statuses_.reset(new MPI_Status[most]);
  indices_.reset(new int[most]());
  peerOf_.reset(new int[most]());
  isRecv_.reset(new uint8_t[most]());
  received_.reset(new int[most]());
  heard_.reset(new double[size_]());
  codes_.reset(new int[size_]());
  // SIGTERM (mpirun's, when a rank dies) removes rank 0's temporary files
  // and says which rank this one was waiting for.
  os::InstallSignalCleanup();
  return Status::Ok();
}

void MpiTransport::Check(int rc, int peer, const char* call) {
  if (rc == MPI_SUCCESS) return;
  int errorClass = MPI_ERR_OTHER;
  MPI_Error_class(rc, &errorClass);
  CHECK_MSG(errorClass != MPI_ERR_TRUNCATE,
            "a message is larger than its receive buffer (Send/Recv sizes disagree)");
  char text[MPI_MAX_ERROR_STRING] = {};
  int length = 0;
  MPI_Error_string(rc, text, &length);
  if (peer >= 0) {
    os::PrintErr("vismask: rank %d: lost rank %d (%s: %s)\n", rank_, peer, call, text);
  } else {
    os::PrintErr("vismask: rank %d: lost rank ? (%s: %s)\n", rank_, call, text);
  }
  os::RemoveTempFiles();
  std::_Exit(kExitLostRank);
}

void MpiTransport::Post(int rc, int peer, bool recv, const char* call) {
  Check(rc, peer, call);
  CHECK(posted_ < 2 * size_);
  peerOf_[posted_] = peer;
  isRecv_[posted_] = recv;
  received_[posted_] = 0;
  ++posted_;
}

void MpiTransport::Silent(int peer, bool reading, double limit) {
  PrintSilent(peer, reading, limit);
  os::RemoveTempFiles();
  MPI_Abort(MPI_COMM_WORLD, kExitLostRank);
  std::_Exit(kExitLostRank);  // MPI_Abort does not return
}

void MpiTransport::Wait(const char* call) {
  const int n = posted_;
  posted_ = 0;
  const double start = os::Seconds();
  const double limit = WaitLimit();
  double lastTurn = start, lastDone = start;
  for (int p = 0; p < size_; ++p) heard_[p] = start;
  int left = n, noted = -1;
  while (left > 0) {
    int done = 0;
    int rc = MPI_Testsome(n, requests_.get(), &done, indices_.get(), statuses_.get());
    if (rc != MPI_SUCCESS && rc != MPI_ERR_IN_STATUS) Check(rc, -1, call);
    CHECK(done != MPI_UNDEFINED);  // `left` requests are still active
    const double now = os::Seconds();
    for (int k = 0; k < done; ++k) {
      int i = indices_[k];
      if (rc == MPI_ERR_IN_STATUS) Check(statuses_[k].MPI_ERROR, peerOf_[i], call);
      if (isRecv_[i]) MPI_Get_count(&statuses_[k], MPI_BYTE, &received_[i]);
      heard_[peerOf_[i]] = now;
      --left;
    }
    // This rank was not running: its peers' silence is not theirs.
    if (now - lastTurn > kStoppedGap) {
      for (int p = 0; p < size_; ++p) heard_[p] = now;
    }
    lastTurn = now;
    if (left == 0) break;
    // The peer a SIGTERM handler names (os::NoteWaiting): the first one
    // this rank still waits to hear from, else the first it sends to.
    int first = -1;
    for (int i = 0; i < n && first < 0; ++i)
      if (requests_[i] != MPI_REQUEST_NULL && isRecv_[i]) first = peerOf_[i];
    for (int i = 0; i < n && first < 0; ++i)
      if (requests_[i] != MPI_REQUEST_NULL) first = peerOf_[i];
    if (first != noted) os::NoteWaiting(rank_, first);
    noted = first;
    if (limit > 0.0) {
      for (int pass = 0; pass < 2; ++pass) {
        for (int i = 0; i < n; ++i) {
          if (requests_[i] == MPI_REQUEST_NULL || isRecv_[i] != (pass == 0)) continue;
          if (now - heard_[peerOf_[i]] > limit) Silent(peerOf_[i], pass == 0, limit);
        }
      }
    }
    if (done > 0) {
      lastDone = now;
    } else if (now - lastDone <= kSpinSeconds) {
      sched_yield();  // a rank that shares a core with another runs it
    } else {
      double idle = (now - lastDone) / 8.0;
      double seconds = idle < kMinNap ? kMinNap : idle > kMaxNap ? kMaxNap : idle;
      timespec nap = {0, static_cast<long>(seconds * 1e9)};
      ::nanosleep(&nap, nullptr);
    }
  }
  if (noted >= 0) os::NoteWaiting(rank_, -1);
  NoteWait(os::Seconds() - start);
}

void MpiTransport::AllToAll(const Span<const uint8_t>* send, const Span<uint8_t>* recv,
                            size_t* recvBytes) {
  CHECK_MSG(!finished_, "transport used after Finish");
  // Each receive takes up to its whole buffer; MPI_Get_count says how much came.
  for (int p = 0; p < size_; ++p) {
    if (p == rank_) continue;
    size_t room = recv[p].size() < size_t{INT_MAX} ? recv[p].size() : size_t{INT_MAX};
    Post(MPI_Irecv(room > 0 ? recv[p].data() : &dummy_, static_cast<int>(room), MPI_BYTE, p,
                   kTagAllToAll, MPI_COMM_WORLD, &requests_[posted_]),
         p, true, "MPI_Irecv");
  }
  for (int p = 0; p < size_; ++p) {
    if (p == rank_) continue;
    CHECK_MSG(send[p].size() <= size_t{INT_MAX}, "mpi: an AllToAll block is limited to 2 GiB");
    Post(MPI_Isend(send[p].size() > 0 ? send[p].data() : &dummy_, static_cast<int>(send[p].size()),
                   MPI_BYTE, p, kTagAllToAll, MPI_COMM_WORLD, &requests_[posted_]),
         p, false, "MPI_Isend");
  }
  const int n = posted_;
  Wait("AllToAll");
  recvBytes[rank_] = 0;
  for (int i = 0; i < n; ++i)
    if (isRecv_[i]) recvBytes[peerOf_[i]] = static_cast<size_t>(received_[i]);
}

void MpiTransport::AllGather(const void* mine, size_t bytes, void* all) {
  CHECK_MSG(!finished_, "transport used after Finish");
  CHECK_MSG(bytes <= INT_MAX, "mpi: AllGather blocks are limited to 2 GiB");
  uint8_t* allBytes = static_cast<uint8_t*>(all);
  uint8_t* own = allBytes + static_cast<size_t>(rank_) * bytes;
  const int count = static_cast<int>(bytes);
  for (int p = 0; p < size_; ++p) {
    if (p == rank_) continue;
    uint8_t* block = allBytes + static_cast<size_t>(p) * bytes;
    Post(MPI_Irecv(count > 0 ? block : &dummy_, count, MPI_BYTE, p, kTagAllGather, MPI_COMM_WORLD,
                   &requests_[posted_]),
         p, true, "MPI_Irecv");
  }
  for (int p = 0; p < size_; ++p) {
    if (p == rank_) continue;
    Post(MPI_Isend(count > 0 ? mine : &dummy_, count, MPI_BYTE, p, kTagAllGather, MPI_COMM_WORLD,
                   &requests_[posted_]),
         p, false, "MPI_Isend");
  }
  const int n = posted_;
  Wait("AllGather");
  for (int i = 0; i < n; ++i)
    CHECK_MSG(!isRecv_[i] || received_[i] == count, "AllGather block sizes disagree");
  if (own != mine && bytes > 0) std::memmove(own, mine, bytes);
}

void MpiTransport::PointToPoint(int peer, void* data, size_t bytes, bool recv) {
  const char* call = recv ? "Recv" : "Send";
  uint8_t* p = static_cast<uint8_t*>(data);
  // At least one message, so an empty Send still meets its Recv.
  size_t offset = 0;
  do {
    size_t n = bytes - offset < kChunkBytes ? bytes - offset : kChunkBytes;
    uint8_t* at = n > 0 ? p + offset : &dummy_;
    const int count = static_cast<int>(n);
    if (recv) {
      Post(MPI_Irecv(at, count, MPI_BYTE, peer, kTagPoint, MPI_COMM_WORLD, &requests_[posted_]),
           peer, true, "MPI_Irecv");
    } else {
      Post(MPI_Isend(at, count, MPI_BYTE, peer, kTagPoint, MPI_COMM_WORLD, &requests_[posted_]),
           peer, false, "MPI_Isend");
    }
    Wait(call);
    if (recv) CHECK_MSG(static_cast<size_t>(received_[0]) == n, "Send/Recv sizes disagree");
    offset += n;
  } while (offset < bytes);
}

int MpiTransport::Finish(int exitCode) {
  CHECK_MSG(!finished_, "Finish called twice");
  // Every rank's code to rank 0, and the worst back to every rank.
  int worst = exitCode;
  if (rank_ == 0) {
    for (int p = 1; p < size_; ++p)
      Post(MPI_Irecv(&codes_[p], 1, MPI_INT, p, kTagFinish, MPI_COMM_WORLD, &requests_[posted_]), p,
           true, "MPI_Irecv");
    Wait("Finish");
    for (int p = 1; p < size_; ++p)
      if (codes_[p] > worst) worst = codes_[p];
    for (int p = 1; p < size_; ++p)
      Post(MPI_Isend(&worst, 1, MPI_INT, p, kTagFinish, MPI_COMM_WORLD, &requests_[posted_]), p,
           false, "MPI_Isend");
    Wait("Finish");
  } else {
    Post(MPI_Isend(&exitCode, 1, MPI_INT, 0, kTagFinish, MPI_COMM_WORLD, &requests_[posted_]), 0,
         false, "MPI_Isend");
    Post(MPI_Irecv(&worst, 1, MPI_INT, 0, kTagFinish, MPI_COMM_WORLD, &requests_[posted_]), 0, true,
         "MPI_Irecv");
    Wait("Finish");
  }
  finished_ = true;
  MPI_Finalize();
  return worst;
}

}  // namespace

std::unique_ptr<Transport> MakeTransport(const TransportRequest& request, Status* error) {
  if (!request.name.empty() && request.name != "mpi") {
    *error = Status::Error("vismask: --transport " + request.name +
                           " is in build/vismask; this binary (vismask-mpi) has mpi");
    return nullptr;
  }
  if (request.ranks < 1) {
    *error = Status::Error("vismask: --ranks must be at least 1");
    return nullptr;
  }
  auto transport = std::make_unique<MpiTransport>();
  Status s = transport->Start(request);
  if (!s.ok()) {
    *error = s;
    return nullptr;
  }
  return transport;
}

}  // namespace vismask
