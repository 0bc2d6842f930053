// The pipe transport when a rank fails: Finish codes, a child that exits,
// is killed or falls silent, and the run ending on every survivor.
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
#include "transport_test_util.h"
#include "vismask/core/os.h"
#include "vismask/parallel/transport.h"

namespace vismask {
namespace {

using test::ExitCode;
using test::RankRun;
using test::RunPipeRanks;

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
