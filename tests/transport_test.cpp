// Tests of the transports linked into build/vismask: `loop`, and `pipe` run
// from a process forked by the test, so the gtest process is never a rank.
// Each rank reports pass/fail through its Finish code; rank 0's exit status
// is the run's result.
#include "vismask/parallel/transport.h"

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

namespace vismask {
namespace {

using test::ExitCode;
using test::RankRun;
using test::RunPipeRanks;

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

}  // namespace
}  // namespace vismask
