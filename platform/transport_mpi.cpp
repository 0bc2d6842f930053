// The transport of build/vismask-mpi: `mpi`, over Open MPI's MPI_COMM_WORLD
// (run under `mpirun -np N`; without mpirun it is a singleton of one rank).
//
// Faults. MPI_COMM_WORLD returns errors (MPI_ERRORS_RETURN) and Check turns
// any error into "vismask: rank R: lost rank K (...)" and exit status 3
// (K is "?" for a collective: MPI does not say which rank failed); mpirun
// then ends the job with status 3. In practice Open MPI 4.1 (no ULFM) never
// returns an error for a dead peer: its runtime handles it. Observed on
// Open MPI 4.1.4 (Debian 12), one node, `mpirun -np 2..4 --oversubscribe`,
// a rank killed with SIGKILL in the middle of AllToAll rounds, shared-memory
// and `--mca btl tcp,self` alike: mpirun notices at once, sends the others
// SIGCONT, then SIGTERM 1 s later; every survivor dies by SIGTERM 1.0-1.2 s
// after the kill, without a "lost rank" line (over TCP the survivors first
// print Open MPI's "peer process has unexpectedly disconnected"), and mpirun
// prints "mpirun noticed that process rank K ... exited on signal 9" and
// exits with 137 (128 + SIGKILL), not 3. A rank that exits on its own with
// status 3 makes mpirun kill the rest and exit 3 (2.3 s). If mpirun itself is
// killed, the ranks end within 3 s. Rank 0's outputs stay under their
// temporary names in every case.
#include <mpi.h>

#include <climits>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "vismask/check.h"
#include "vismask/os.h"
#include "vismask/transport.h"

namespace vismask {
namespace {

// MPI counts are int: Send/Recv move larger messages in chunks of this size.
constexpr size_t kChunkBytes = size_t{1} << 30;

class MpiTransport final : public Transport {
 public:
  MpiTransport() = default;
  MpiTransport(const MpiTransport&) = delete;
  MpiTransport& operator=(const MpiTransport&) = delete;
  ~MpiTransport() override;

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  const char* name() const override { return "mpi"; }
  int ranksOnHost() const override { return ranksOnHost_; }

  void AllToAll(const Span<const uint8_t>* send, const Span<uint8_t>* recv,
                size_t* recvBytes) override;
  void AllGather(const void* mine, size_t bytes, void* all) override;
  void Send(int to, const void* data, size_t bytes) override;
  void Recv(int from, void* data, size_t bytes) override;
  int Finish(int exitCode) override;

  // MPI_Init, errors returned instead of aborting, and the count arrays.
  Status Start(const TransportRequest& request);

 private:
  // An MPI error is a lost rank: `peer` for point-to-point, -1 for a
  // collective (MPI does not say which rank failed).
  void Check(int rc, int peer, const char* call);

  int rank_ = 0;
  int size_ = 1;
  int ranksOnHost_ = 1;  // the size of this rank's shared-memory communicator
  bool started_ = false;
  bool finished_ = false;
  // AllToAll scratch, one entry per rank, made in Start.
  std::unique_ptr<uint64_t[]> sendSizes_;
  std::unique_ptr<uint64_t[]> recvSizes_;
  std::unique_ptr<int[]> sendCounts_;
  std::unique_ptr<int[]> sendDispls_;
  std::unique_ptr<int[]> recvCounts_;
  std::unique_ptr<int[]> recvDispls_;
  uint8_t dummy_ = 0;  // a valid address for a call that moves no bytes
};

MpiTransport::~MpiTransport() {
  if (!started_ || finished_) return;
  // Other ranks may be waiting in a collective: end the whole job, not just this rank.
  os::PrintErr("vismask: rank %d: the mpi transport ended without Finish; aborting the job\n",
               rank_);
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
    finished_ = true;
    MPI_Finalize();
    // Every rank would say it: rank 0 alone does (the others' status is empty).
    return rank_ == 0 ? Status::Error(tooMany + " (mpirun -np)") : Status::Error("");
  }
  MPI_Comm host;
  if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &host) ==
      MPI_SUCCESS) {
    MPI_Comm_size(host, &ranksOnHost_);
    MPI_Comm_free(&host);
  } else {
    ranksOnHost_ = size_;  // unknown: as if every rank shared this host
  }
  sendSizes_.reset(new uint64_t[size_]());
  recvSizes_.reset(new uint64_t[size_]());
  sendCounts_.reset(new int[size_]());
  sendDispls_.reset(new int[size_]());
  recvCounts_.reset(new int[size_]());
  recvDispls_.reset(new int[size_]());
  return Status::Ok();
}

void MpiTransport::Check(int rc, int peer, const char* call) {
  if (rc == MPI_SUCCESS) return;
  int errorClass = MPI_ERR_OTHER;
  MPI_Error_class(rc, &errorClass);
  CHECK_MSG(errorClass != MPI_ERR_TRUNCATE, "Send/Recv sizes disagree");
  char text[MPI_MAX_ERROR_STRING] = {};
  int length = 0;
  MPI_Error_string(rc, text, &length);
  if (peer >= 0) {
    os::PrintErr("vismask: rank %d: lost rank %d (%s: %s)\n", rank_, peer, call, text);
  } else {
    os::PrintErr("vismask: rank %d: lost rank ? (%s: %s)\n", rank_, call, text);
  }
  std::_Exit(kExitLostRank);
}

void MpiTransport::AllToAll(const Span<const uint8_t>* send, const Span<uint8_t>* recv,
                            size_t* recvBytes) {
  CHECK_MSG(!finished_, "transport used after Finish");
  for (int p = 0; p < size_; ++p) sendSizes_[p] = p == rank_ ? 0 : send[p].size();
  Check(MPI_Alltoall(sendSizes_.get(), 1, MPI_UINT64_T, recvSizes_.get(), 1, MPI_UINT64_T,
                     MPI_COMM_WORLD),
        -1, "MPI_Alltoall");

  // Alltoallv takes one base address per side and int byte offsets from it:
  // the lowest block is the base, and every block must lie within 2 GiB of it.
  uintptr_t sendBase = UINTPTR_MAX, recvBase = UINTPTR_MAX;
  for (int p = 0; p < size_; ++p) {
    if (sendSizes_[p] > 0) {
      uintptr_t a = reinterpret_cast<uintptr_t>(send[p].data());
      if (a < sendBase) sendBase = a;
    }
    if (recvSizes_[p] > 0) {
      uintptr_t a = reinterpret_cast<uintptr_t>(recv[p].data());
      if (a < recvBase) recvBase = a;
    }
  }
  if (sendBase == UINTPTR_MAX) sendBase = reinterpret_cast<uintptr_t>(&dummy_);
  if (recvBase == UINTPTR_MAX) recvBase = reinterpret_cast<uintptr_t>(&dummy_);
  for (int p = 0; p < size_; ++p) {
    sendCounts_[p] = 0;
    sendDispls_[p] = 0;
    recvCounts_[p] = 0;
    recvDispls_[p] = 0;
    if (sendSizes_[p] > 0) {
      uint64_t offset = reinterpret_cast<uintptr_t>(send[p].data()) - sendBase;
      CHECK_MSG(offset + sendSizes_[p] <= INT_MAX, "mpi: send blocks span more than 2 GiB");
      sendCounts_[p] = static_cast<int>(sendSizes_[p]);
      sendDispls_[p] = static_cast<int>(offset);
    }
    if (recvSizes_[p] > 0) {
      CHECK_MSG(recvSizes_[p] <= recv[p].size(), "receive buffer too small");
      uint64_t offset = reinterpret_cast<uintptr_t>(recv[p].data()) - recvBase;
      CHECK_MSG(offset + recvSizes_[p] <= INT_MAX, "mpi: receive blocks span more than 2 GiB");
      recvCounts_[p] = static_cast<int>(recvSizes_[p]);
      recvDispls_[p] = static_cast<int>(offset);
    }
  }
  Check(MPI_Alltoallv(reinterpret_cast<const void*>(sendBase), sendCounts_.get(), sendDispls_.get(),
                      MPI_BYTE, reinterpret_cast<void*>(recvBase), recvCounts_.get(),
                      recvDispls_.get(), MPI_BYTE, MPI_COMM_WORLD),
        -1, "MPI_Alltoallv");
  for (int p = 0; p < size_; ++p) recvBytes[p] = p == rank_ ? 0 : recvSizes_[p];
}

void MpiTransport::AllGather(const void* mine, size_t bytes, void* all) {
  CHECK_MSG(!finished_, "transport used after Finish");
  CHECK_MSG(bytes <= INT_MAX, "mpi: AllGather blocks are limited to 2 GiB");
  uint8_t* own = static_cast<uint8_t*>(all) + static_cast<size_t>(rank_) * bytes;
  const void* sendBuf = mine == own ? MPI_IN_PLACE : mine;
  Check(MPI_Allgather(sendBuf, static_cast<int>(bytes), MPI_BYTE, all, static_cast<int>(bytes),
                      MPI_BYTE, MPI_COMM_WORLD),
        -1, "MPI_Allgather");
}

void MpiTransport::Send(int to, const void* data, size_t bytes) {
  CHECK_MSG(!finished_, "transport used after Finish");
  CHECK(to >= 0 && to < size_ && to != rank_);
  const uint8_t* p = static_cast<const uint8_t*>(data);
  // At least one message, so an empty Send still meets its Recv.
  size_t offset = 0;
  do {
    size_t n = bytes - offset < kChunkBytes ? bytes - offset : kChunkBytes;
    Check(MPI_Send(n > 0 ? p + offset : &dummy_, static_cast<int>(n), MPI_BYTE, to, 0,
                   MPI_COMM_WORLD),
          to, "MPI_Send");
    offset += n;
  } while (offset < bytes);
}

void MpiTransport::Recv(int from, void* data, size_t bytes) {
  CHECK_MSG(!finished_, "transport used after Finish");
  CHECK(from >= 0 && from < size_ && from != rank_);
  uint8_t* p = static_cast<uint8_t*>(data);
  size_t offset = 0;
  do {
    size_t n = bytes - offset < kChunkBytes ? bytes - offset : kChunkBytes;
    MPI_Status status;
    Check(MPI_Recv(n > 0 ? p + offset : &dummy_, static_cast<int>(n), MPI_BYTE, from, 0,
                   MPI_COMM_WORLD, &status),
          from, "MPI_Recv");
    int got = 0;
    MPI_Get_count(&status, MPI_BYTE, &got);
    CHECK_MSG(static_cast<size_t>(got) == n, "Send/Recv sizes disagree");
    offset += n;
  } while (offset < bytes);
}

int MpiTransport::Finish(int exitCode) {
  CHECK_MSG(!finished_, "Finish called twice");
  int worst = exitCode;
  Check(MPI_Allreduce(&exitCode, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD), -1, "MPI_Allreduce");
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
