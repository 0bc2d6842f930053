// The pipe transport's process lifecycle (pipe_internal.h): Start creates
// the pipes and forks the ranks; the signal handlers that tell a child of
// rank 0's death and rank 0 of a child that ended the run; Lost and Silent,
// which end the run; reaping and checking the children; Finish, which
// collects every child's exit code and reports the worst; closing the pipes
// and restoring the signal dispositions.
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "pipe_internal.h"
#include "rank_wait.h"
#include "vismask/core/check.h"
#include "vismask/core/os.h"
#include "vismask/core/status.h"
#include "vismask/parallel/transport.h"

namespace vismask {
namespace {

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
    os::RemoveTempFiles();  // a checkpoint file this rank was writing (checkpoint.h)
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

}  // namespace

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
  PrintSilent(peer, reading, limit);
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

}  // namespace vismask
