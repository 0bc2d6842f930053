// A rank that dies, stops or is signalled ends the run: every process gone,
// the status the README gives, the rank named, and no output and no
// temporary file left.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "ranks_test_util.h"
#include "test_util.h"

namespace vismask {
namespace {

using test::FileExists;
using test::HaveMpi;
using test::MpiCommand;
using test::ReadFile;
using test::StartCommand;
using test::TempDir;
using test::VismaskBin;
using test::WaitForExit;

// Starts the real binary on 4 ranks, kills one child, and expects every
// process gone within 5 s, exit status 3, a message naming the lost rank,
// and no image written.
TEST(RanksTest, KilledPipeChildEndsTheRunWithExitThree) {
  TempDir dir;
  std::string cmd =
      VismaskBin() + " render scenes/cornell.obj --envs 4 --ranks 4 --rays 256 --out " +
      dir.File("out") + " --max-shots 100000000 --stop-unshot 0 --quiet 2>" + dir.File("err");
  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // well into the solve
  std::string children = dir.File("children");
  std::string find = "pgrep -P " + std::to_string(pid) + " > " + children;
  ASSERT_EQ(std::system(find.c_str()), 0) << "no child ranks found";
  pid_t victim = static_cast<pid_t>(std::atol(ReadFile(children).c_str()));
  ASSERT_GT(victim, 0);
  auto killedAt = std::chrono::steady_clock::now();
  ASSERT_EQ(kill(victim, SIGKILL), 0);
  int status = 0;
  bool ended = false;
  while (std::chrono::steady_clock::now() - killedAt < std::chrono::seconds(10)) {
    if (waitpid(pid, &status, WNOHANG) == pid) {
      ended = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - killedAt).count();
  if (!ended) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  ASSERT_TRUE(ended) << "rank 0 still running 10 s after a child was killed";
  EXPECT_LT(seconds, 5.0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3);
  std::string err = ReadFile(dir.File("err"));
  EXPECT_NE(err.find("lost rank"), std::string::npos) << err;
  EXPECT_FALSE(FileExists(dir.File("out/image.png")));
  EXPECT_FALSE(FileExists(dir.File("out/image.pfm")));
  // Rank 0 removed its temporary files before it exited.
  for (const auto& e : std::filesystem::directory_iterator(dir.File("out")))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  // No rank left behind.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  // "[/]tmp/..." matches the ranks' command lines but not this shell's own.
  std::string left = "pgrep -f '[/]" + dir.File("out").substr(1) + "' >/dev/null";
  EXPECT_NE(std::system(left.c_str()), 0) << "a rank outlived the run";
  std::printf("killed rank's run ended after %.2f s\n", seconds);
}

// A rank that stops (SIGSTOP) or hangs, issue 17 item 12, and one that dies
// under mpirun, item 13: the run ends with the status the README gives,
// naming the rank, and --out holds no output and no temporary file.

// Names in `dir` with ".tmp" in them (rank 0's temporary outputs).
std::vector<std::string> TempFilesIn(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    std::string name = e.path().filename().string();
    if (name.find(".tmp") != std::string::npos) names.push_back(name);
  }
  return names;
}

// Waits (up to 20 s) until rank 0 has opened its outputs, the end of init,
// then a little longer, so that the ranks are in the solve.
bool WaitForTheSolve(const std::string& out) {
  for (int i = 0; i < 1000 && TempFilesIn(out).empty(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  return !TempFilesIn(out).empty();
}

// The children of `parent` in fork order (rank 1, 2, ... for pipe ranks):
// pids count up from the parent's and wrap at pid_max, which a machine
// that has run many processes reaches (32768 by default), so they are
// ordered by their distance past the parent's pid, not by value.
std::vector<pid_t> ChildrenOf(pid_t parent, const TempDir& dir) {
  std::string list = dir.File("children");
  std::string cmd = "pgrep -P " + std::to_string(parent) + " > " + list;
  std::vector<pid_t> pids;
  if (std::system(cmd.c_str()) != 0) return pids;
  std::ifstream in(list);
  for (long pid; in >> pid;) pids.push_back(static_cast<pid_t>(pid));
  long pidMax = 0;
  std::ifstream("/proc/sys/kernel/pid_max") >> pidMax;
  if (pidMax <= 0) pidMax = 4194304;  // the kernel's largest
  auto after = [&](pid_t p) { return ((long(p) - parent) % pidMax + pidMax) % pidMax; };
  std::sort(pids.begin(), pids.end(), [&](pid_t a, pid_t b) { return after(a) < after(b); });
  return pids;
}

// Whether a process whose command line mentions `out` is still running
// ("[/]tmp/..." matches the ranks but not the shell that runs pgrep).
bool RankLeft(const std::string& out) {
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  std::string cmd = "pgrep -f '[/]" + out.substr(1) + "' >/dev/null";
  return std::system(cmd.c_str()) == 0;
}

const char kEndless[] =
    " render scenes/cornell.obj --rays 256 --max-shots 100000000 --stop-unshot 0 --quiet"
    " --rank-timeout 2";

// Stops rank `victim` of a 4-rank pipe run (0: rank 0 itself, which a child
// then ends with SIGUSR1).
void StopOnePipeRank(int victim) {
  TempDir dir;
  std::string out = dir.File("out");
  pid_t pid = StartCommand(VismaskBin() + kEndless + " --envs 4 --ranks 4 --out " + out + " 2>" +
                           dir.File("err"));
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(WaitForTheSolve(out)) << ReadFile(dir.File("err"));
  std::vector<pid_t> children = ChildrenOf(pid, dir);
  ASSERT_EQ(children.size(), 3u);
  ASSERT_EQ(kill(victim == 0 ? pid : children[victim - 1], SIGSTOP), 0);
  int status = 0;
  double took = 0.0;
  // The limit is 2 s, or 10 times the longest wait so far if that is longer
  // (the init's, on a loaded machine); then rank 0 is ended at once.
  bool ended = WaitForExit(pid, 15.0, &status, &took);
  std::string err = ReadFile(dir.File("err"));
  ASSERT_TRUE(ended) << "still running 15 s after rank " << victim << " was stopped\n" << err;
  EXPECT_LT(took, 10.0) << err;
  ASSERT_TRUE(WIFEXITED(status)) << status << "\n" << err;
  EXPECT_EQ(WEXITSTATUS(status), 3) << err;
  std::string named = ": rank " + std::to_string(victim) + " sent nothing for ";
  EXPECT_NE(err.find(named), std::string::npos) << named << "\n" << err;
  EXPECT_NE(err.find(" s (--rank-timeout); ending the run\n"), std::string::npos) << err;
  EXPECT_FALSE(FileExists(out + "/image.png"));
  EXPECT_FALSE(FileExists(out + "/run.json"));
  EXPECT_TRUE(TempFilesIn(out).empty()) << TempFilesIn(out).front();
  EXPECT_FALSE(RankLeft(out)) << "a rank outlived the run (the stopped one?)";
  std::printf("rank %d stopped: the run ended after %.2f s\n%s", victim, took, err.c_str());
}

TEST(RanksTest, StoppedPipeChildEndsTheRunWithExitThree) {
  StopOnePipeRank(2);
}

TEST(RanksTest, StoppedPipeRankZeroEndsTheRunWithExitThree) {
  StopOnePipeRank(0);
}

// SIGTERM (or Ctrl-C) to a run: no output, no temporary file (the --export
// .glb's, outside --out, included), and the signal's own status.
TEST(RanksTest, SigtermLeavesNoTemporaryFiles) {
  TempDir dir;
  std::string out = dir.File("out");
  pid_t pid = StartCommand(VismaskBin() + kEndless + " --envs 2 --ranks 2 --out " + out +
                           " --export " + dir.File("scene.glb") + " 2>" + dir.File("err"));
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(WaitForTheSolve(out)) << ReadFile(dir.File("err"));
  ASSERT_EQ(kill(pid, SIGTERM), 0);
  int status = 0;
  double took = 0.0;
  ASSERT_TRUE(WaitForExit(pid, 10.0, &status, &took));
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  EXPECT_TRUE(TempFilesIn(out).empty()) << TempFilesIn(out).front();
  EXPECT_FALSE(FileExists(out + "/run.json"));
  EXPECT_FALSE(RankLeft(out));
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find("scene.glb"), std::string::npos) << e.path();
}

// Under mpirun (skipped when build/vismask-mpi or mpirun is missing): rank
// `victim` of 3 gets `sig`. The pids of the ranks are mpirun's children,
// each with its rank in OMPI_COMM_WORLD_RANK.
struct MpiRun {
  int status = 0;
  double took = 0.0;
  std::string log;
  std::vector<std::string> temp;  // temporary files left in --out
  bool outputs = false;           // run.json or image.png written
  bool left = false;              // a rank outlived mpirun
};

MpiRun SignalOneMpiRank(int victim, int sig) {
  MpiRun run;
  TempDir dir;
  std::string out = dir.File("out");
  pid_t pid = StartCommand("env " + MpiCommand("3") + kEndless + " --envs 3 --out " + out + " >" +
                           dir.File("log") + " 2>&1");
  EXPECT_GT(pid, 0);
  if (!WaitForTheSolve(out)) {
    ADD_FAILURE() << "no temporary outputs 20 s after the start\n" << ReadFile(dir.File("log"));
  }
  pid_t target = 0;
  for (pid_t child : ChildrenOf(pid, dir)) {
    std::string env = ReadFile("/proc/" + std::to_string(child) + "/environ");
    std::string key = std::string("OMPI_COMM_WORLD_RANK=") + std::to_string(victim);
    for (size_t at = 0; at < env.size(); at = env.find('\0', at) + 1) {
      if (env.compare(at, key.size() + 1, key + '\0') == 0) target = child;
      if (env.find('\0', at) == std::string::npos) break;
    }
  }
  EXPECT_GT(target, 0) << "no process of rank " << victim << " among mpirun's children";
  if (target > 0) kill(target, sig);
  bool ended = WaitForExit(pid, 20.0, &run.status, &run.took);
  run.log = ReadFile(dir.File("log"));
  EXPECT_TRUE(ended) << "mpirun still running 20 s after the signal\n" << run.log;
  run.temp = TempFilesIn(out);
  run.outputs = FileExists(out + "/run.json") || FileExists(out + "/image.png");
  run.left = RankLeft(out);
  std::printf("mpirun -np 3, rank %d got signal %d: ended after %.2f s, wait status %d\n%s", victim,
              sig, run.took, run.status, run.log.c_str());
  return run;
}

TEST(RanksTest, StoppedMpiRankEndsTheRunWithExitThree) {
  if (!HaveMpi()) GTEST_SKIP() << "build/vismask-mpi or mpirun missing";
  MpiRun run = SignalOneMpiRank(2, SIGSTOP);
  EXPECT_LT(run.took, 12.0);
  ASSERT_TRUE(WIFEXITED(run.status)) << run.status;
  EXPECT_EQ(WEXITSTATUS(run.status), 3);
  // A rank that waits for rank 2 names it: as silent (it sent nothing) or,
  // when the waiter was sending to it, as taking none of its bytes; which
  // rank times out first depends on where each was in the round.
  EXPECT_TRUE(run.log.find(": rank 2 sent nothing for ") != std::string::npos ||
              run.log.find(": rank 2 took none of this rank's bytes for ") != std::string::npos)
      << run.log;
  // (Not Open MPI's own "MPI_ABORT was invoked" notice: when two ranks abort
  // at once, mpirun may print "Data unpack would read past end of buffer"
  // instead.)
  EXPECT_TRUE(run.temp.empty()) << run.temp.front();
  EXPECT_FALSE(run.outputs);
  EXPECT_FALSE(run.left) << "a rank outlived mpirun";
}

// What the README says of a rank that dies under mpirun: mpirun names it
// and exits with 128 + its signal; rank 0 removes its temporary files.
TEST(RanksTest, KilledMpiRankLeavesNoTemporaryFiles) {
  if (!HaveMpi()) GTEST_SKIP() << "build/vismask-mpi or mpirun missing";
  MpiRun run = SignalOneMpiRank(1, SIGKILL);
  EXPECT_LT(run.took, 5.0);
  ASSERT_TRUE(WIFEXITED(run.status)) << run.status;
  EXPECT_EQ(WEXITSTATUS(run.status), 128 + SIGKILL);
  EXPECT_NE(run.log.find("mpirun noticed that process rank 1"), std::string::npos);
  EXPECT_NE(run.log.find("exited on signal 9"), std::string::npos);
  EXPECT_TRUE(run.temp.empty()) << run.temp.front();
  EXPECT_FALSE(run.outputs);
  EXPECT_FALSE(run.left) << "a rank outlived mpirun";
}

}  // namespace
}  // namespace vismask
