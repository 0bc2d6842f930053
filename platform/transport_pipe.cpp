// The pipe transport of build/vismask: ranks forked from the calling
// process, one POSIX pipe per ordered pair of ranks.
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
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/uio.h>
#include <sys/wait.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "rank_wait.h"
#include "transport_local.h"
#include "vismask/check.h"
#include "vismask/os.h"
#include "vismask/transport.h"

namespace vismask {
namespace {

constexpr int kMaxPipeRanks = kMaxRanks;
// How long a waiting rank sleeps in poll() before it checks that its peers live.
constexpr int kPollMs = 100;
// Length word of the frame a child sends from Finish (no data frame is this long).
constexpr uint64_t kFinishWord = ~uint64_t{0};
constexpr size_t kWordBytes = sizeof(uint64_t);

// For the SIGTERM handler of a child: its parent's pid and a ready message.
pid_t gRankZeroPid = 0;
char gParentLostLine[96];
size_t gParentLostLineBytes = 0;

// A child's SIGTERM: PR_SET_PDEATHSIG sends it when rank 0 dies (the child has
// then been re-parented); any other SIGTERM keeps its default meaning.
void ChildSigterm(int) {
  if (::getppid() != gRankZeroPid) {
    ssize_t ignored = ::write(2, gParentLostLine, gParentLostLineBytes);
    (void)ignored;
    ::_exit(kExitLostRank);
  }
  ::signal(SIGTERM, SIG_DFL);
  ::raise(SIGTERM);
}

// Rank 0's SIGUSR1: a child found rank 0 silent and ends the run (it said why).
void EndedByAChild(int) {
  os::RemoveTempFiles();
  ::_exit(kExitLostRank);
}

// "killed by signal 9", "exited with status 7" for a wait status.
void DescribeWaitStatus(int status, char* out, size_t n) {
  if (WIFSIGNALED(status)) {
    std::snprintf(out, n, "killed by signal %d", WTERMSIG(status));
  } else if (WIFEXITED(status)) {
    std::snprintf(out, n, "exited with status %d", WEXITSTATUS(status));
  } else {
    std::snprintf(out, n, "wait status %d", status);
  }
}

const char* ErrnoReason(int err) {
  if (err == EPIPE) return "broken pipe";
  if (err == ECONNRESET) return "connection reset";
  return std::strerror(err);
}

class PipeTransport final : public Transport {
 public:
  PipeTransport() = default;
  PipeTransport(const PipeTransport&) = delete;
  PipeTransport& operator=(const PipeTransport&) = delete;
  ~PipeTransport() override;

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  const char* name() const override { return "pipe"; }

  void AllToAll(const Span<const uint8_t>* send, const Span<uint8_t>* recv,
                size_t* recvBytes) override;
  void AllGather(const void* mine, size_t bytes, void* all) override;
  void Send(int to, const void* data, size_t bytes) override;
  void Recv(int from, void* data, size_t bytes) override;
  int Finish(int exitCode) override;

  // Creates the pipes and forks the children; each process leaves with its
  // rank. `timeout`: --rank-timeout (0: none).
  Status Start(int ranks, double timeout);

 private:
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
  // The wait limit now (transport.h), 0 for none.
  double WaitLimit() const;
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

  int rank_ = 0;
  int size_ = 1;
  bool finished_ = false;
  bool sigpipeSaved_ = false;
  bool sigusr1Saved_ = false;
  pid_t rankZeroPid_ = 0;
  double timeout_ = 0.0;      // --rank-timeout; 0: none
  double longestWait_ = 0.0;  // the longest Pump so far, seconds
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

PipeTransport::~PipeTransport() {
  if (finished_ || size_ == 1) {
    CloseAll();
    RestoreSigpipe();
    return;
  }
  // A child must never return into the caller: end it as Finish(1) would.
  if (rank_ != 0) {
    os::PrintErr("vismask: rank %d: transport destroyed without Finish\n", rank_);
    FinishChild(1);
  }
  // Rank 0 without Finish: hang up and collect the children, so none is left behind.
  CloseAll();
  for (int p = 1; p < size_; ++p) {
    if (peers_[p].reaped || peers_[p].pid <= 0) continue;
    ::kill(peers_[p].pid, SIGTERM);
    ReapChild(p, true);
  }
  RestoreSigpipe();
}

Status PipeTransport::Start(int ranks, double timeout) {
  size_ = ranks;
  rank_ = 0;
  rankZeroPid_ = ::getpid();
  timeout_ = timeout;
  if (ranks == 1) return Status::Ok();

  // 2*N*(N-1) descriptors are open in rank 0 until every child is forked.
  const uint64_t needFds = 2ull * ranks * (ranks - 1) + 64;
  rlimit lim;
  if (::getrlimit(RLIMIT_NOFILE, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY &&
      lim.rlim_cur < needFds) {
    rlimit raised = lim;
    raised.rlim_cur =
        (lim.rlim_max == RLIM_INFINITY || lim.rlim_max >= needFds) ? needFds : lim.rlim_max;
    if (::setrlimit(RLIMIT_NOFILE, &raised) != 0 || raised.rlim_cur < needFds) {
      return Status::Error("vismask: --ranks " + std::to_string(ranks) + " needs " +
                           std::to_string(needFds) + " open files for its pipes; the limit is " +
                           std::to_string(lim.rlim_max) + " (ulimit -n)");
    }
  }

  // pipeFd[(from * N + to) * 2 + end]: the pipe that carries from -> to.
  std::vector<int> pipeFd(2u * ranks * ranks, -1);
  auto closeAllPipes = [&]() {
    for (int& fd : pipeFd) {
      if (fd >= 0) ::close(fd);
      fd = -1;
    }
  };
  for (int from = 0; from < ranks; ++from) {
    for (int to = 0; to < ranks; ++to) {
      if (from == to) continue;
      int* fds = &pipeFd[(static_cast<size_t>(from) * ranks + to) * 2];
      if (::pipe2(fds, O_CLOEXEC | O_NONBLOCK) != 0) {
        std::string why = std::strerror(errno);
        closeAllPipes();
        return Status::Error("vismask: cannot create the pipes for --ranks " +
                             std::to_string(ranks) + ": " + why);
      }
    }
  }

  // A write to a dead peer must fail with EPIPE, not kill this process.
  struct sigaction ignore = {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigpipeSaved_ = ::sigaction(SIGPIPE, &ignore, &oldSigpipe_) == 0;

  // Nothing buffered before the fork may be written twice.
  std::fflush(nullptr);
  int myRank = 0;
  for (int r = 1; r < ranks; ++r) {
    pid_t pid = ::fork();
    if (pid == 0) {
      myRank = r;
      break;
    }
    if (pid < 0) {
      std::string why = std::strerror(errno);
      for (int k = 1; k < r; ++k) {
        ::kill(peers_[k].pid, SIGKILL);
        int status;
        while (::waitpid(peers_[k].pid, &status, 0) < 0 && errno == EINTR) {
        }
        peers_[k].pid = 0;
      }
      closeAllPipes();
      RestoreSigpipe();
      size_ = 1;
      return Status::Error("vismask: cannot start rank " + std::to_string(r) + ": " + why);
    }
    peers_[r].pid = pid;
  }
  rank_ = myRank;

  // Keep this rank's ends (write to each peer, read from each peer); close the rest.
  for (int from = 0; from < ranks; ++from) {
    for (int to = 0; to < ranks; ++to) {
      if (from == to) continue;
      int* fds = &pipeFd[(static_cast<size_t>(from) * ranks + to) * 2];
      if (to == rank_) {
        peers_[from].readFd = fds[0];
        fds[0] = -1;
      }
      if (from == rank_) {
        peers_[to].writeFd = fds[1];
        fds[1] = -1;
      }
    }
  }
  closeAllPipes();

  if (rank_ != 0) {
    // A child hears of rank 0's death by SIGTERM even while it computes.
    gRankZeroPid = rankZeroPid_;
    int n = std::snprintf(gParentLostLine, sizeof gParentLostLine,
                          "vismask: rank %d: lost rank 0 (rank 0's process ended)\n", rank_);
    gParentLostLineBytes = n > 0 ? static_cast<size_t>(n) : 0;
    struct sigaction term = {};
    term.sa_handler = ChildSigterm;
    sigemptyset(&term.sa_mask);
    ::sigaction(SIGTERM, &term, nullptr);
#ifdef __linux__
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
#endif
    for (int p = 0; p < ranks; ++p) peers_[p].pid = 0;
    // Start only once rank 0 has forked every child (it kills them otherwise).
    Recv(0, nullptr, 0);
  } else {
    // A child that finds rank 0 silent ends it with SIGUSR1.
    struct sigaction ended = {};
    ended.sa_handler = EndedByAChild;
    sigemptyset(&ended.sa_mask);
    sigusr1Saved_ = ::sigaction(SIGUSR1, &ended, &oldSigusr1_) == 0;
    for (int p = 1; p < ranks; ++p) Send(p, nullptr, 0);
  }
  return Status::Ok();
}

void PipeTransport::Lost(int peer, const char* why) {
  // No second report from the SIGTERM handler while this one is written.
  sigset_t term;
  sigemptyset(&term);
  sigaddset(&term, SIGTERM);
  ::sigprocmask(SIG_BLOCK, &term, nullptr);
  os::PrintErr("vismask: rank %d: lost rank %d (%s)\n", rank_, peer, why);
  if (rank_ == 0) {
    os::RemoveTempFiles();
    ContinueChildren();
  }
  ::_exit(kExitLostRank);
}

void PipeTransport::Silent(int peer, bool reading, double limit) {
  sigset_t term;
  sigemptyset(&term);
  sigaddset(&term, SIGTERM);
  ::sigprocmask(SIG_BLOCK, &term, nullptr);
  PrintSilentRank(rank_, peer, reading, limit, timeout_);
  if (rank_ == 0) {
    os::RemoveTempFiles();
    if (!peers_[peer].reaped && peers_[peer].pid > 0) ::kill(peers_[peer].pid, SIGKILL);
    ContinueChildren();
  } else if (peer == 0 && ::getppid() == rankZeroPid_) {
    ::kill(rankZeroPid_, SIGUSR1);
    ::kill(rankZeroPid_, SIGCONT);
  }
  ::_exit(kExitLostRank);
}

double PipeTransport::WaitLimit() const {
  return RankWaitLimit(timeout_, longestWait_);
}

void PipeTransport::ContinueChildren() {
  for (int p = 1; p < size_; ++p) {
    if (!peers_[p].reaped && peers_[p].pid > 0) ::kill(peers_[p].pid, SIGCONT);
  }
}

void PipeTransport::ReapChild(int peer, bool block) {
  Peer& p = peers_[peer];
  if (p.reaped || p.pid <= 0) return;
  int status = 0;
  pid_t r;
  do {
    r = ::waitpid(p.pid, &status, block ? 0 : WNOHANG);
  } while (r < 0 && errno == EINTR);
  if (r == p.pid) {
    p.reaped = true;
    p.status = status;
  } else if (r < 0) {
    // Not our child any more (someone else reaped it): count it as gone.
    p.reaped = true;
    p.status = kExitLostRank << 8;
  }
}

void PipeTransport::CheckPeers() {
  if (rank_ != 0) {
    if (::getppid() != rankZeroPid_) Lost(0, "rank 0's process ended");
    return;
  }
  for (int p = 1; p < size_; ++p) {
    ReapChild(p, false);
    if (!peers_[p].reaped) continue;
    // A child that exited cleanly may still have frames in its pipe: EOF decides.
    int st = peers_[p].status;
    if (WIFSIGNALED(st) || (WIFEXITED(st) && WEXITSTATUS(st) == kExitLostRank)) {
      char why[64];
      DescribeWaitStatus(st, why, sizeof why);
      Lost(p, why);
    }
  }
}

void PipeTransport::AcceptWord(int peer) {
  InFrame& f = in_[peer];
  if (f.atFinish) {
    if (f.word == kFinishWord) {
      f.bytes = kWordBytes;
    } else {
      f.outOfStep = true;
      f.active = false;
    }
    return;
  }
  if (f.word == kFinishWord) Lost(peer, "it finished while this rank still expected data");
  f.bytes = f.word;
  if (f.exact && f.bytes != f.capacity) {
    os::PrintErr("vismask: rank %d: rank %d sent %llu bytes, %llu expected\n", rank_, peer,
                 static_cast<unsigned long long>(f.bytes),
                 static_cast<unsigned long long>(f.capacity));
    CHECK_MSG(false, "Send/Recv sizes disagree");
  }
  if (f.bytes > f.capacity) {
    os::PrintErr("vismask: rank %d: rank %d sent %llu bytes, the buffer holds %llu\n", rank_, peer,
                 static_cast<unsigned long long>(f.bytes),
                 static_cast<unsigned long long>(f.capacity));
    CHECK_MSG(false, "receive buffer too small");
  }
}

void PipeTransport::WriteSome(int peer) {
  OutFrame& f = out_[peer];
  const uint64_t total = kWordBytes + f.bytes;
  while (f.done < total) {
    iovec iov[2];
    int count = 0;
    if (f.done < kWordBytes) {
      iov[count++] = {reinterpret_cast<uint8_t*>(&f.word) + f.done,
                      static_cast<size_t>(kWordBytes - f.done)};
      if (f.bytes > 0) iov[count++] = {const_cast<uint8_t*>(f.data), static_cast<size_t>(f.bytes)};
    } else {
      uint64_t sent = f.done - kWordBytes;
      iov[count++] = {const_cast<uint8_t*>(f.data) + sent, static_cast<size_t>(f.bytes - sent)};
    }
    ssize_t w = ::writev(peers_[peer].writeFd, iov, count);
    if (w < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return;
      Lost(peer, ErrnoReason(errno));
    }
    f.done += static_cast<uint64_t>(w);
  }
  f.active = false;
}

void PipeTransport::ReadSome(int peer) {
  InFrame& f = in_[peer];
  for (;;) {
    if (f.done >= kWordBytes && f.done - kWordBytes == f.bytes) {
      f.active = false;
      return;
    }
    ssize_t r;
    if (f.done < kWordBytes) {
      r = ::read(peers_[peer].readFd, reinterpret_cast<uint8_t*>(&f.word) + f.done,
                 kWordBytes - f.done);
    } else {
      uint64_t got = f.done - kWordBytes;
      r = ::read(peers_[peer].readFd, f.data + got, f.bytes - got);
    }
    if (r < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return;
      Lost(peer, ErrnoReason(errno));
    }
    if (r == 0) {
      if (f.atFinish) {
        f.eof = true;
        f.active = false;
        return;
      }
      Lost(peer, "connection closed");
    }
    bool hadWord = f.done >= kWordBytes;
    f.done += static_cast<uint64_t>(r);
    if (!hadWord && f.done == kWordBytes) {
      AcceptWord(peer);
      if (!f.active) return;
    }
  }
}

void PipeTransport::Pump(bool atFinish) {
  const double start = os::Seconds();
  const double limit = WaitLimit();
  double lastTurn = start;
  for (int p = 0; p < size_; ++p) heard_[p] = start;
  for (;;) {
    int n = 0;
    for (int p = 0; p < size_; ++p) {
      if (out_[p].active) {
        pollFds_[n] = {peers_[p].writeFd, POLLOUT, 0};
        pollPeer_[n++] = p;
      }
      if (in_[p].active) {
        pollFds_[n] = {peers_[p].readFd, POLLIN, 0};
        pollPeer_[n++] = p + kMaxPipeRanks;
      }
    }
    if (n == 0) {
      double waited = os::Seconds() - start;
      if (waited > longestWait_) longestWait_ = waited;
      return;
    }
    int ready = ::poll(pollFds_, static_cast<nfds_t>(n), kPollMs);
    if (ready < 0) CHECK_MSG(errno == EINTR, "poll failed");
    const double now = os::Seconds();
    // This rank was not running: its peers' silence is not theirs.
    if (now - lastTurn > kStoppedGap) {
      for (int p = 0; p < size_; ++p) heard_[p] = now;
    }
    lastTurn = now;
    if (ready == 0) {
      // At Finish, children are expected to exit: EOF tells the rest.
      if (!atFinish) CheckPeers();
    }
    for (int i = 0; ready > 0 && i < n; ++i) {
      if (pollFds_[i].revents == 0) continue;
      int peer = pollPeer_[i] % kMaxPipeRanks;
      heard_[peer] = now;
      if (pollPeer_[i] < kMaxPipeRanks) {
        WriteSome(peer);
      } else {
        ReadSome(peer);
      }
    }
    if (limit <= 0.0) continue;
    // A peer silent for longer than the limit ends the run; one this rank
    // waits to read from is named before one it only writes to.
    for (int pass = 0; pass < 2; ++pass) {
      for (int p = 0; p < size_; ++p) {
        bool awaited = pass == 0 ? in_[p].active : out_[p].active;
        if (awaited && now - heard_[p] > limit) Silent(p, pass == 0, limit);
      }
    }
  }
}

void PipeTransport::AllToAll(const Span<const uint8_t>* send, const Span<uint8_t>* recv,
                             size_t* recvBytes) {
  CHECK_MSG(!finished_, "transport used after Finish");
  CheckPeers();
  for (int p = 0; p < size_; ++p) {
    if (p == rank_) continue;
    out_[p] = OutFrame();
    out_[p].active = true;
    out_[p].word = send[p].size();
    out_[p].data = send[p].data();
    out_[p].bytes = send[p].size();
    in_[p] = InFrame();
    in_[p].active = true;
    in_[p].data = recv[p].data();
    in_[p].capacity = recv[p].size();
  }
  Pump(false);
  for (int p = 0; p < size_; ++p) recvBytes[p] = p == rank_ ? 0 : in_[p].bytes;
}

void PipeTransport::AllGather(const void* mine, size_t bytes, void* all) {
  uint8_t* allBytes = static_cast<uint8_t*>(all);
  for (int p = 0; p < size_; ++p) {
    gatherSend_[p] = Span<const uint8_t>(static_cast<const uint8_t*>(mine), bytes);
    gatherRecv_[p] = Span<uint8_t>(allBytes + static_cast<size_t>(p) * bytes, bytes);
  }
  AllToAll(gatherSend_, gatherRecv_, gatherBytes_);
  for (int p = 0; p < size_; ++p) {
    if (p != rank_) CHECK_MSG(gatherBytes_[p] == bytes, "AllGather block sizes disagree");
  }
  uint8_t* own = allBytes + static_cast<size_t>(rank_) * bytes;
  if (own != mine && bytes > 0) std::memmove(own, mine, bytes);
}

void PipeTransport::Send(int to, const void* data, size_t bytes) {
  CHECK_MSG(!finished_, "transport used after Finish");
  CHECK(to >= 0 && to < size_ && to != rank_);
  CheckPeers();
  out_[to] = OutFrame();
  out_[to].active = true;
  out_[to].word = bytes;
  out_[to].data = static_cast<const uint8_t*>(data);
  out_[to].bytes = bytes;
  Pump(false);
}

void PipeTransport::Recv(int from, void* data, size_t bytes) {
  CHECK_MSG(!finished_, "transport used after Finish");
  CHECK(from >= 0 && from < size_ && from != rank_);
  CheckPeers();
  in_[from] = InFrame();
  in_[from].active = true;
  in_[from].exact = true;
  in_[from].data = static_cast<uint8_t*>(data);
  in_[from].capacity = bytes;
  Pump(false);
}

void PipeTransport::FinishChild(int exitCode) {
  finished_ = true;
  int64_t code = exitCode;
  out_[0] = OutFrame();
  out_[0].active = true;
  out_[0].word = kFinishWord;
  out_[0].data = reinterpret_cast<const uint8_t*>(&code);
  out_[0].bytes = sizeof code;
  Pump(false);
  // Only what this child wrote itself: the buffers were flushed before the fork.
  std::fflush(nullptr);
  ::_exit(exitCode & 0xff);
}

int PipeTransport::Finish(int exitCode) {
  CHECK_MSG(!finished_, "Finish called twice");
  if (rank_ != 0) FinishChild(exitCode);
  finished_ = true;
  if (size_ == 1) {
    RestoreSigpipe();
    return exitCode;
  }

  // Collect a finish frame (or EOF) from every child, then hang up and reap them.
  for (int p = 1; p < size_; ++p) {
    in_[p] = InFrame();
    in_[p].active = true;
    in_[p].atFinish = true;
    in_[p].data = reinterpret_cast<uint8_t*>(&finishCodes_[p]);
    in_[p].capacity = sizeof finishCodes_[p];
  }
  Pump(true);
  CloseAll();
  int worst = exitCode;
  for (int p = 1; p < size_; ++p) {
    if (in_[p].outOfStep && !peers_[p].reaped) ::kill(peers_[p].pid, SIGTERM);
    ReapChild(p, true);
    int st = peers_[p].status;
    bool finished = !in_[p].eof && !in_[p].outOfStep;
    if (finished && WIFEXITED(st) && WEXITSTATUS(st) == (finishCodes_[p] & 0xff)) {
      if (finishCodes_[p] > worst) worst = static_cast<int>(finishCodes_[p]);
      continue;
    }
    char why[96];
    if (in_[p].outOfStep) {
      std::snprintf(why, sizeof why, "it sent data while rank 0 finished");
    } else {
      DescribeWaitStatus(st, why, sizeof why);
    }
    os::PrintErr("vismask: rank 0: lost rank %d (%s)\n", p, why);
    if (worst < kExitLostRank) worst = kExitLostRank;
  }
  RestoreSigpipe();
  return worst;
}

void PipeTransport::CloseAll() {
  for (int p = 0; p < size_; ++p) {
    if (peers_[p].readFd >= 0) ::close(peers_[p].readFd);
    if (peers_[p].writeFd >= 0) ::close(peers_[p].writeFd);
    peers_[p].readFd = -1;
    peers_[p].writeFd = -1;
  }
}

void PipeTransport::RestoreSigpipe() {
  if (sigusr1Saved_) ::sigaction(SIGUSR1, &oldSigusr1_, nullptr);
  sigusr1Saved_ = false;
  if (!sigpipeSaved_) return;
  ::sigaction(SIGPIPE, &oldSigpipe_, nullptr);
  sigpipeSaved_ = false;
}

}  // namespace

std::unique_ptr<Transport> MakePipeTransport(int ranks, double rankTimeout, Status* error) {
  auto transport = std::make_unique<PipeTransport>();
  Status s = transport->Start(ranks, rankTimeout);
  if (!s.ok()) {
    *error = s;
    return nullptr;
  }
  return transport;
}

}  // namespace vismask
