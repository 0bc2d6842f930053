// Tests of the transports linked into build/vismask: `loop`, and `pipe` run
// from a process forked by the test, so the gtest process is never a rank.
// Each rank reports pass/fail through its Finish code; rank 0's exit status
// is the run's result.
#include "vismask/transport.h"

#include <errno.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/os.h"

namespace vismask {
namespace {

// A byte that depends on who sent it to whom, where, and in which call.
uint8_t Pattern(int from, int to, size_t index, int call) {
  uint32_t x = static_cast<uint32_t>(from + 1) * 2654435761u ^
               static_cast<uint32_t>(to + 7) * 40503u ^ static_cast<uint32_t>(index) * 2246822519u ^
               static_cast<uint32_t>(call + 3) * 3266489917u;
  x ^= x >> 15;
  x *= 2246822519u;
  x ^= x >> 13;
  return static_cast<uint8_t>(x);
}

void Fill(std::vector<uint8_t>& v, int from, int to, int call) {
  for (size_t i = 0; i < v.size(); ++i) v[i] = Pattern(from, to, i, call);
}

// Index of the first byte of data[0, n) that is not Pattern(from, to, i, call); n if none.
size_t FirstMismatch(const uint8_t* data, size_t n, int from, int to, int call) {
  for (size_t i = 0; i < n; ++i) {
    if (data[i] != Pattern(from, to, i, call)) return i;
  }
  return n;
}

// Block size from -> to in AllToAll call `call`: above the 64 KiB pipe buffer,
// different in every direction; call 2 mixes in empty blocks.
size_t BlockBytes(int from, int to, int call) {
  if (call == 2 && (from + to) % 2 == 1) return 0;
  return 70000 + 4099 * static_cast<size_t>(from) + 517 * static_cast<size_t>(to) +
         33331 * static_cast<size_t>(call);
}

struct RankRun {
  int status = -1;  // rank 0's wait status; -1 if it had to be killed
  std::string err;  // everything every rank wrote to stderr
};

// Runs `body` as every rank of a `pipe` transport of `ranks` ranks, in a
// process forked from the test, and finishes each rank with body's result.
RankRun RunPipeRanks(int ranks, const std::function<int(Transport&)>& body,
                     double timeoutSeconds = 60.0, double rankTimeout = kDefaultRankTimeout) {
  test::TempDir dir;
  std::string errPath = dir.File("stderr");
  RankRun run;
  std::fflush(nullptr);
  pid_t helper = fork();
  if (helper == 0) {
    int fd = open(errPath.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd < 0 || dup2(fd, 2) < 0) _exit(100);
    Status error;
    std::unique_ptr<Transport> t = MakeTransport({"pipe", ranks, rankTimeout}, &error);
    if (!t) {
      os::PrintErr("MakeTransport: %s\n", error.ToString().c_str());
      _exit(101);
    }
    int code = body(*t);
    _exit(t->Finish(code));
  }
  double deadline = os::Seconds() + timeoutSeconds;
  for (;;) {
    int status;
    pid_t r = waitpid(helper, &status, WNOHANG);
    if (r == helper) {
      run.status = status;
      break;
    }
    if (os::Seconds() > deadline) {
      kill(helper, SIGKILL);  // its children get SIGTERM (PR_SET_PDEATHSIG)
      waitpid(helper, &status, 0);
      break;
    }
    usleep(2000);
  }
  run.err = test::ReadFile(errPath);
  return run;
}

int ExitCode(const RankRun& run) {
  return run.status >= 0 && WIFEXITED(run.status) ? WEXITSTATUS(run.status) : -1;
}

// Three AllToAll calls with blocks above the pipe buffer in every direction.
int AllToAllBody(Transport& t) {
  const int n = t.size();
  const int me = t.rank();
  std::vector<std::vector<uint8_t>> sendBufs(n), recvBufs(n);
  std::vector<Span<const uint8_t>> send(n);
  std::vector<Span<uint8_t>> recv(n);
  std::vector<size_t> recvBytes(n);
  for (int call = 0; call < 3; ++call) {
    for (int p = 0; p < n; ++p) {
      sendBufs[p].assign(BlockBytes(me, p, call), 0);
      Fill(sendBufs[p], me, p, call);
      recvBufs[p].assign(BlockBytes(p, me, call) + 100, 0xEE);  // room to spare
      send[p] = Span<const uint8_t>(sendBufs[p].data(), sendBufs[p].size());
      recv[p] = Span<uint8_t>(recvBufs[p].data(), recvBufs[p].size());
      recvBytes[p] = 12345;
    }
    t.AllToAll(send.data(), recv.data(), recvBytes.data());
    for (int p = 0; p < n; ++p) {
      size_t expect = p == me ? 0 : BlockBytes(p, me, call);
      if (recvBytes[p] != expect) {
        os::PrintErr("rank %d call %d: %zu bytes from %d, expected %zu\n", me, call, recvBytes[p],
                     p, expect);
        return 1;
      }
      if (p == me) continue;
      size_t bad = FirstMismatch(recvBufs[p].data(), expect, p, me, call);
      if (bad != expect) {
        os::PrintErr("rank %d call %d: byte %zu from %d differs\n", me, call, bad, p);
        return 1;
      }
    }
  }
  return 0;
}

int AllGatherBody(Transport& t) {
  const int n = t.size();
  const size_t bytes = 150000;
  std::vector<uint8_t> mine(bytes), all(bytes * n, 0xEE);
  Fill(mine, t.rank(), -1, 9);
  t.AllGather(mine.data(), bytes, all.data());
  for (int p = 0; p < n; ++p) {
    if (FirstMismatch(all.data() + p * bytes, bytes, p, -1, 9) != bytes) {
      os::PrintErr("rank %d: AllGather block of rank %d differs\n", t.rank(), p);
      return 1;
    }
  }
  // Ranks are 0..n-1, each once.
  int me = t.rank();
  std::vector<int> ranks(n, -1);
  t.AllGather(&me, sizeof me, ranks.data());
  for (int p = 0; p < n; ++p) {
    if (ranks[p] != p) return 1;
  }
  return 0;
}

// 5 MB around the ring 0 -> 1 -> ... -> n-1 -> 0, one hop at a time.
int SendRecvBody(Transport& t) {
  const int n = t.size();
  const int me = t.rank();
  const size_t bytes = 5u << 20;
  std::vector<uint8_t> out(bytes), in(bytes);
  Fill(out, me, (me + 1) % n, 5);
  int prev = (me + n - 1) % n;
  if (me == 0) t.Send(1 % n, out.data(), bytes);
  t.Recv(prev, in.data(), bytes);
  if (me != 0) t.Send((me + 1) % n, out.data(), bytes);
  if (FirstMismatch(in.data(), bytes, prev, me, 5) != bytes) {
    os::PrintErr("rank %d: Recv from %d differs\n", me, prev);
    return 1;
  }
  return 0;
}

TEST(TransportTest, LoopBasics) {
  Status error;
  std::unique_ptr<Transport> t = MakeTransport({"loop", 1}, &error);
  ASSERT_TRUE(t) << error.ToString();
  EXPECT_EQ(t->size(), 1);
  EXPECT_EQ(t->rank(), 0);
  EXPECT_STREQ(t->name(), "loop");

  uint8_t sendByte = 7, recvByte = 0;
  Span<const uint8_t> send(&sendByte, 1);
  Span<uint8_t> recv(&recvByte, 1);
  size_t recvBytes = 99;
  t->AllToAll(&send, &recv, &recvBytes);
  EXPECT_EQ(recvBytes, 0u);
  EXPECT_EQ(recvByte, 0);

  const char mine[] = "abcdef";
  char all[sizeof mine] = {};
  t->AllGather(mine, sizeof mine, all);
  EXPECT_STREQ(all, "abcdef");
  EXPECT_EQ(t->Finish(4), 4);
}

TEST(TransportTest, DefaultIsLoopForOneRank) {
  Status error;
  std::unique_ptr<Transport> t = MakeTransport({"", 1}, &error);
  ASSERT_TRUE(t) << error.ToString();
  EXPECT_STREQ(t->name(), "loop");
}

TEST(TransportTest, LoopSendIsABug) {
  Status error;
  std::unique_ptr<Transport> t = MakeTransport({"loop", 1}, &error);
  ASSERT_TRUE(t);
  uint8_t b = 0;
  EXPECT_DEATH(t->Send(0, &b, 1), "no other rank");
  EXPECT_DEATH(t->Recv(0, &b, 1), "no other rank");
}

TEST(TransportTest, RefusedRequests) {
  const TransportRequest bad[] = {{"mpi", 1},    {"loop", 2}, {"pipe", 0},
                                  {"pipe", 257}, {"", 300},   {"tcp", 2}};
  for (const TransportRequest& request : bad) {
    Status error;
    EXPECT_FALSE(MakeTransport(request, &error)) << request.name << " " << request.ranks;
    EXPECT_FALSE(error.ok());
    EXPECT_FALSE(error.message().empty());
  }
  Status error;
  MakeTransport({"loop", 2}, &error);
  EXPECT_NE(error.message().find("pipe"), std::string::npos) << error.message();
}

// One limit for every transport (issue 17: mpirun -np 257 ended in a CHECK
// on every rank); the MPI transport calls the same function on its world size.
TEST(TransportTest, RankLimitIsStatedOnce) {
  EXPECT_EQ(RankCountError(1, "--ranks"), "");
  EXPECT_EQ(RankCountError(kMaxRanks, "--ranks"), "");
  EXPECT_EQ(RankCountError(kMaxRanks + 1, "the MPI world size is"),
            "vismask: the MPI world size is 257: a run has 1 to 256 ranks");
  EXPECT_NE(RankCountError(0, "--ranks"), "");
  Status error;
  EXPECT_FALSE(MakeTransport({"pipe", kMaxRanks + 1}, &error));
  EXPECT_EQ(error.message(), "vismask: --ranks 257: a run has 1 to 256 ranks");
}

TEST(TransportTest, PipeOfOneRankIsLocal) {
  Status error;
  std::unique_ptr<Transport> t = MakeTransport({"pipe", 1}, &error);
  ASSERT_TRUE(t) << error.ToString();
  EXPECT_STREQ(t->name(), "pipe");
  EXPECT_EQ(t->size(), 1);
  int mine = 42, all = 0;
  t->AllGather(&mine, sizeof mine, &all);
  EXPECT_EQ(all, 42);
  EXPECT_EQ(t->Finish(0), 0);
}

TEST(TransportTest, PipeAllToAllLargeBlocks) {
  for (int ranks : {2, 3, 4}) {
    double start = os::Seconds();
    RankRun run = RunPipeRanks(ranks, AllToAllBody);
    EXPECT_EQ(ExitCode(run), 0) << ranks << " ranks:\n" << run.err;
    EXPECT_EQ(run.err, "");
    std::printf("[ info ] pipe AllToAll, %d ranks: %.3f s\n", ranks, os::Seconds() - start);
  }
}

TEST(TransportTest, PipeAllGather) {
  for (int ranks : {2, 3, 4}) {
    RankRun run = RunPipeRanks(ranks, AllGatherBody);
    EXPECT_EQ(ExitCode(run), 0) << ranks << " ranks:\n" << run.err;
  }
}

TEST(TransportTest, PipeSendRecvFiveMegabytes) {
  for (int ranks : {2, 3}) {
    RankRun run = RunPipeRanks(ranks, SendRecvBody);
    EXPECT_EQ(ExitCode(run), 0) << ranks << " ranks:\n" << run.err;
  }
}

TEST(TransportTest, PipeCallsInSequenceStayInStep) {
  RankRun run = RunPipeRanks(3, [](Transport& t) {
    int failed = SendRecvBody(t) + AllToAllBody(t) + AllGatherBody(t) + SendRecvBody(t);
    return failed ? 1 : 0;
  });
  EXPECT_EQ(ExitCode(run), 0) << run.err;
}

TEST(TransportTest, PipeDefaultForSeveralRanks) {
  test::TempDir dir;
  std::fflush(nullptr);
  pid_t helper = fork();
  if (helper == 0) {
    Status error;
    std::unique_ptr<Transport> t = MakeTransport({"", 3}, &error);
    if (!t) _exit(101);
    bool ok = std::strcmp(t->name(), "pipe") == 0 && t->size() == 3;
    _exit(t->Finish(ok ? 0 : 1));
  }
  int status = 0;
  ASSERT_EQ(waitpid(helper, &status, 0), helper);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
}

TEST(TransportTest, PipeFinishReturnsTheWorstCode) {
  RankRun ok = RunPipeRanks(3, [](Transport&) { return 0; });
  EXPECT_EQ(ExitCode(ok), 0) << ok.err;
  EXPECT_EQ(ok.err, "");

  RankRun two = RunPipeRanks(3, [](Transport& t) { return t.rank() == 2 ? 2 : 0; });
  EXPECT_EQ(ExitCode(two), 2) << two.err;
  EXPECT_EQ(two.err, "");
}

TEST(TransportTest, PipeFinishReportsAChildThatExitsOnItsOwn) {
  RankRun run = RunPipeRanks(3, [](Transport& t) {
    if (t.rank() == 1) _exit(7);
    return 0;
  });
  EXPECT_EQ(ExitCode(run), kExitLostRank) << run.err;
  EXPECT_NE(run.err.find("vismask: rank 0: lost rank 1 (exited with status 7)\n"),
            std::string::npos)
      << run.err;
}

TEST(TransportTest, PipeFinishReportsAKilledChild) {
  RankRun run = RunPipeRanks(3, [](Transport& t) {
    if (t.rank() == 2) raise(SIGKILL);
    return 0;
  });
  EXPECT_EQ(ExitCode(run), kExitLostRank) << run.err;
  EXPECT_NE(run.err.find("vismask: rank 0: lost rank 2 (killed by signal 9)\n"), std::string::npos)
      << run.err;
}

// A child that dies while rank 0 computes is noticed at rank 0's next call,
// even one that does not involve it.
TEST(TransportTest, PipeRankZeroNoticesADeadChildAtItsNextCall) {
  RankRun run = RunPipeRanks(3, [](Transport& t) {
    uint8_t b = 0;
    if (t.rank() == 2) raise(SIGKILL);
    if (t.rank() == 1) t.Recv(0, &b, 1);
    if (t.rank() == 0) {
      usleep(300000);  // "computing" while rank 2 dies
      t.Send(1, &b, 1);
    }
    return 0;
  });
  EXPECT_EQ(ExitCode(run), kExitLostRank) << run.err;
  EXPECT_NE(run.err.find("vismask: rank 0: lost rank 2 (killed by signal 9)\n"), std::string::npos)
      << run.err;
}

// A child that stops (SIGSTOP) in the middle of the run: rank 0 hears
// nothing from it for --rank-timeout, says so, kills it and ends the run.
TEST(TransportTest, PipeSilentChildEndsTheRun) {
  double start = os::Seconds();
  RankRun run = RunPipeRanks(
      3,
      [](Transport& t) {
        uint8_t all[3];
        uint8_t me = static_cast<uint8_t>(t.rank());
        t.AllGather(&me, 1, all);
        if (t.rank() == 2) raise(SIGSTOP);
        t.AllGather(&me, 1, all);
        return 0;
      },
      20.0, 1.0);
  double took = os::Seconds() - start;
  EXPECT_EQ(ExitCode(run), kExitLostRank) << run.err;
  EXPECT_NE(run.err.find("rank 2 sent nothing for 1 s (--rank-timeout); ending the run\n"),
            std::string::npos)
      << run.err;
  EXPECT_LT(took, 5.0) << run.err;
}

// The wait limit grows to 10 times the longest wait of the run: a first
// wait of 0.4 s lets a later one last 1.5 s with --rank-timeout 1.
TEST(TransportTest, PipeWaitLimitGrowsWithTheLongestWait) {
  RankRun run = RunPipeRanks(
      2,
      [](Transport& t) {
        uint8_t all[2];
        uint8_t me = static_cast<uint8_t>(t.rank());
        if (t.rank() == 1) usleep(400000);
        t.AllGather(&me, 1, all);
        if (t.rank() == 1) usleep(1500000);
        t.AllGather(&me, 1, all);
        return 0;
      },
      20.0, 1.0);
  EXPECT_EQ(ExitCode(run), 0) << run.err;
  EXPECT_EQ(run.err, "");
}

// Runs `ranks` ranks in an endless loop of AllToAll calls, kills rank `victim`
// with SIGKILL once every rank is in the loop, and checks that every survivor
// exits with kExitLostRank within 5 s, saying which rank it lost. The test
// process is a child subreaper meanwhile, so orphaned ranks report to it.
void KillOneRankMidAllToAll(int ranks, int victim) {
  struct Note {
    int32_t rank;
    int32_t pid;  // 0: "rank is in its AllToAll loop"
  };
  test::TempDir dir;
  std::string errPath = dir.File("stderr");
  int notes[2];
  ASSERT_EQ(pipe(notes), 0);
  ASSERT_EQ(prctl(PR_SET_CHILD_SUBREAPER, 1), 0);
  std::fflush(nullptr);
  pid_t helper = fork();
  if (helper == 0) {
    close(notes[0]);
    int fd = open(errPath.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd < 0 || dup2(fd, 2) < 0) _exit(100);
    Status error;
    std::unique_ptr<Transport> t = MakeTransport({"pipe", ranks}, &error);
    if (!t) _exit(101);
    Note note = {t->rank(), static_cast<int32_t>(getpid())};
    if (write(notes[1], &note, sizeof note) != sizeof note) _exit(102);
    const size_t bytes = 100000;
    std::vector<uint8_t> out(bytes * ranks, 1), in(bytes * ranks);
    std::vector<Span<const uint8_t>> send(ranks);
    std::vector<Span<uint8_t>> recv(ranks);
    std::vector<size_t> recvBytes(ranks);
    for (int p = 0; p < ranks; ++p) {
      send[p] = Span<const uint8_t>(out.data() + p * bytes, bytes);
      recv[p] = Span<uint8_t>(in.data() + p * bytes, bytes);
    }
    for (long long call = 0; call < (1LL << 40); ++call) {
      t->AllToAll(send.data(), recv.data(), recvBytes.data());
      if (call == 5) {
        note.pid = 0;
        if (write(notes[1], &note, sizeof note) != sizeof note) _exit(102);
      }
    }
    _exit(104);
  }
  close(notes[1]);

  // Wait until every rank has said where it is and that it is looping.
  std::map<int, pid_t> pidOfRank;
  int looping = 0;
  double deadline = os::Seconds() + 30.0;
  while ((static_cast<int>(pidOfRank.size()) < ranks || looping < ranks) &&
         os::Seconds() < deadline) {
    pollfd pfd = {notes[0], POLLIN, 0};
    if (poll(&pfd, 1, 100) <= 0) continue;
    Note note;
    if (read(notes[0], &note, sizeof note) != sizeof note) break;
    if (note.pid != 0) {
      pidOfRank[note.rank] = note.pid;
    } else {
      ++looping;
    }
  }
  close(notes[0]);
  EXPECT_EQ(static_cast<int>(pidOfRank.size()), ranks);
  EXPECT_EQ(looping, ranks);

  std::map<pid_t, int> rankOfPid;
  for (auto& [rank, pid] : pidOfRank) rankOfPid[pid] = rank;
  rankOfPid[helper] = 0;
  std::map<int, int> statusOfRank;
  std::map<int, double> secondsOfRank;
  double killedAt = os::Seconds();
  if (pidOfRank.count(victim)) kill(pidOfRank[victim], SIGKILL);
  // Rank 0 may reap a child itself (and then names it in its own lost line):
  // once rank 0 has exited, such a child's pid no longer exists.
  std::set<int> reapedByRankZero;
  auto survivorsLeft = [&]() {
    bool left = false;
    for (auto& [pid, rank] : rankOfPid) {
      if (rank == victim || statusOfRank.count(rank) || reapedByRankZero.count(rank)) continue;
      if (rank != 0 && statusOfRank.count(0) && kill(pid, 0) != 0 && errno == ESRCH) {
        reapedByRankZero.insert(rank);
        continue;
      }
      left = true;
    }
    return left;
  };
  deadline = killedAt + 10.0;
  while (survivorsLeft() && os::Seconds() < deadline) {
    int status;
    pid_t pid = waitpid(-1, &status, WNOHANG);
    if (pid <= 0) {
      usleep(1000);
      continue;
    }
    auto it = rankOfPid.find(pid);
    if (it == rankOfPid.end()) continue;
    statusOfRank[it->second] = status;
    secondsOfRank[it->second] = os::Seconds() - killedAt;
  }
  // Nothing outlives the test, whatever happened.
  for (auto& [pid, rank] : rankOfPid) {
    if (statusOfRank.count(rank) || rank == victim) continue;
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
  }
  // The victim is dead; it is this process's zombie unless rank 0 reaped it (ECHILD).
  if (pidOfRank.count(victim) && !statusOfRank.count(victim)) {
    waitpid(pidOfRank[victim], nullptr, 0);
  }
  prctl(PR_SET_CHILD_SUBREAPER, 0);

  std::string err = test::ReadFile(errPath);
  double slowest = 0.0;
  for (int r = 0; r < ranks; ++r) {
    if (r == victim) continue;
    std::string line = "vismask: rank " + std::to_string(r) + ": lost rank ";
    EXPECT_NE(err.find(line), std::string::npos) << line << "\n" << err;
    if (reapedByRankZero.count(r)) {
      // Its status is in rank 0's report, and it ended before rank 0 did.
      std::string report = "vismask: rank 0: lost rank " + std::to_string(r) +
                           " (exited with status " + std::to_string(kExitLostRank) + ")";
      EXPECT_NE(err.find(report), std::string::npos) << report << "\n" << err;
      continue;
    }
    ASSERT_TRUE(statusOfRank.count(r)) << "rank " << r << " still running 10 s after the kill\n"
                                       << err;
    int status = statusOfRank[r];
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == kExitLostRank)
        << "rank " << r << " status " << status << "\n"
        << err;
    EXPECT_LT(secondsOfRank[r], 5.0) << "rank " << r;
    if (secondsOfRank[r] > slowest) slowest = secondsOfRank[r];
  }
  std::printf("[ info ] %d ranks, rank %d killed: the last survivor exited after %.3f s\n", ranks,
              victim, slowest);
  std::printf("%s", err.c_str());
}

TEST(TransportTest, PipeSurvivorsExitWhenAChildIsKilled) {
  KillOneRankMidAllToAll(4, 2);
}

TEST(TransportTest, PipeChildrenExitWhenRankZeroIsKilled) {
  KillOneRankMidAllToAll(3, 0);
}

}  // namespace
}  // namespace vismask
