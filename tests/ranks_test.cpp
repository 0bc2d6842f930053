// The same render on one process, on 1-8 forked processes over pipes and (if
// built) under mpirun gives the same bytes (image.pfm, patches.csv and the
// --export .glb); a rank that dies ends the run.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "test_util.h"

namespace vismask {
namespace {

using test::FileExists;
using test::ReadFile;
using test::RunMain;
using test::TempDir;
using test::VismaskBin;

const std::vector<std::string> kBase = {"render",       "scenes/cornell.obj",
                                        "--envs",       "4x1x2",
                                        "--rays",       "512",
                                        "--max-shots",  "1200",
                                        "--width",      "96",
                                        "--height",     "96",
                                        "--mask-res",   "24",
                                        "--patch-size", "50",
                                        "--quiet"};

// `kBase` with --mask-method `method`: the same bytes on one process, on
// forked processes (`pipeRanks`) and under mpirun (`mpiRanks`, when built).
void ExpectSameBytesEverywhere(const char* method, std::vector<const char*> pipeRanks,
                               std::vector<const char*> mpiRanks,
                               const std::vector<std::string>& base = kBase);
bool HaveMpi();

// The default allocation (rays in proportion to power, partial shots, the
// rounding drawn from each shot's stream), Sobol' samples, sub-patch
// elements, antialiasing and the cut vertices shared across environments:
// still the same bytes everywhere.
const std::vector<std::string> kPowerBase = {"render",         "scenes/cornell.obj",
                                             "--envs",         "2x1x2",
                                             "--emitted-rays", "400000",
                                             "--max-rays",     "2048",
                                             "--stop-unshot",  "2e-2",
                                             "--width",        "96",
                                             "--height",       "96",
                                             "--mask-res",     "24",
                                             "--patch-size",   "50",
                                             "--quiet"};

TEST(RanksTest, PowerAllocationAndElementsGiveTheSameBytesEverywhere) {
  ExpectSameBytesEverywhere("R", {"2", "4"}, {"4"}, kPowerBase);
  ExpectSameBytesEverywhere("B", {"3"}, {"2"}, kPowerBase);
}

// Two-sided: twins in every environment, both sides of the light emitting.
TEST(RanksTest, TwoSidedGivesTheSameBytesEverywhere) {
  std::vector<std::string> base = kPowerBase;
  base[1] = "scenes/miswound.obj";
  base.insert(base.end(), {"--two-sided", "--two-sided-emitters"});
  ExpectSameBytesEverywhere("B", {"2", "4"}, {"2"}, base);
  ExpectSameBytesEverywhere("R", {"3"}, {"4"}, base);
}

// Textures: the patch means at init and the per-pixel lookups of each
// rank's own patches, composited, do not depend on where they ran.
const std::vector<std::string> kTexturedBase = {"render",         "scenes/textured/room.obj",
                                                "--envs",         "2x1x1",
                                                "--emitted-rays", "300000",
                                                "--max-rays",     "2048",
                                                "--stop-unshot",  "2e-2",
                                                "--width",        "96",
                                                "--height",       "96",
                                                "--mask-res",     "24",
                                                "--patch-size",   "1",
                                                "--quiet"};

TEST(RanksTest, TexturedSceneGivesTheSameBytesEverywhere) {
  ExpectSameBytesEverywhere("B", {"2"}, {"2"}, kTexturedBase);
  std::vector<std::string> point = kTexturedBase;
  point.insert(point.end(), {"--envs", "2x1x2", "--aa", "off"});
  ExpectSameBytesEverywhere("R", {"2", "4"}, {"4"}, point);
}

// Antialiased pixels sum the pieces of one polygon across environments and
// keep the nearest kFragments: in a building of small patches (16
// environments, 32 x 32 pixels, several environments to a rank) the image
// once depended on which rank drew which environment.
TEST(RanksTest, ManyEnvironmentsToARankGiveTheSameAntialiasedBytes) {
  TempDir dir;
  const std::string scene = dir.File("building.obj");
  const std::string gen = "tools/gen-building --rooms 2x2 --floors 1 --tile 0.5 --out " + scene +
                          " >" + dir.File("gen.log") + " 2>&1";
  ASSERT_EQ(std::system(gen.c_str()), 0) << ReadFile(dir.File("gen.log"));
  const std::vector<std::string> base = {
      "render",       scene, "--envs",   "4x1x4",
      "--patch-size", "2",   "--rays",   "64",
      "--max-shots",  "16",  "--width",  "32",
      "--height",     "32",  "--camera", "0.5,1.6,0.5,8,1.2,8,0,1,0,70",
      "--quiet"};
  ExpectSameBytesEverywhere("B", {"2", "3"}, {"3"}, base);
}

TEST(RanksTest, EveryTransportAndRankCountGivesTheSameBytes) {
  ExpectSameBytesEverywhere("B", {"1", "2", "4", "8"}, {"1", "2", "4"});
}

// Method C fills its masks from the rays' hits and passes, Method R carries
// one bit per ray: neither may depend on where an environment runs.
TEST(RanksTest, MethodsCAndRGiveTheSameBytesEverywhere) {
  ExpectSameBytesEverywhere("C", {"4"}, {"2"});
  ExpectSameBytesEverywhere("R", {"2", "8"}, {"4"});
}

// Smoothing shares display values between polygons in different
// environments and ranks, summed in an order that does not depend on them.
TEST(RanksTest, SmoothingGivesTheSameBytesEverywhere) {
  const std::vector<std::string> smooth = {"render",
                                           "scenes/smooth/sphere-vn.obj",
                                           "--envs",
                                           "2x2x1",
                                           "--emitted-rays",
                                           "300000",
                                           "--width",
                                           "96",
                                           "--height",
                                           "96",
                                           "--mask-res",
                                           "24",
                                           "--quiet",
                                           "--camera",
                                           "0,0.3,4,0,0,0,0,1,0,35"};
  ExpectSameBytesEverywhere("R", {"2", "3", "4"}, {"2"}, smooth);
}

// Issue 20: the default rounds, sized by grid steps (--round-work, chosen
// at init from the scene), on balanced environments (--envs auto:4): the
// rounds end at the same shot everywhere, so the bytes are the same on
// one process, pipes 1/2/4 and mpirun 1/2/4. The rounds hold many shots
// (else this would test nothing new).
TEST(RanksTest, DefaultWorkRoundsOnBalancedEnvironmentsGiveTheSameBytesEverywhere) {
  const std::vector<std::string> base = {"render",         "scenes/cornell.obj",
                                         "--envs",         "auto:4",
                                         "--emitted-rays", "400000",
                                         "--max-rays",     "2048",
                                         "--stop-unshot",  "2e-2",
                                         "--width",        "96",
                                         "--height",       "96",
                                         "--mask-res",     "24",
                                         "--patch-size",   "50",
                                         "--quiet"};
  ExpectSameBytesEverywhere("B", {"1", "2", "4"}, {"1", "2", "4"}, base);
  TempDir dir;
  auto args = base;
  args.insert(args.end(), {"--out", dir.path()});
  ASSERT_EQ(RunMain(args).code, 0);
  std::string json = ReadFile(dir.File("run.json"));
  auto number = [&](const std::string& key) {
    size_t at = json.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key;
    return at == std::string::npos ? 0.0 : std::atof(json.c_str() + at + key.size() + 4);
  };
  EXPECT_GT(number("round_work"), 0.0);
  EXPECT_GT(number("shots"), 4 * 4 * number("rounds")) << "rounds of a few shots: " << json;
  EXPECT_NE(json.find("\"envs_auto\": 4"), std::string::npos);
}

// Issue 20, parallel by default: `--ranks 2` and `mpirun -np 2` with no
// --envs run --envs auto:2, the same bytes as one process given auto:2.
TEST(RanksTest, RanksWithoutEnvsGiveTheBytesOfEnvsAuto) {
  const std::vector<std::string> base = {
      "render", "scenes/cornell.obj", "--patch-size", "50",     "--stop-unshot", "5e-2", "--width",
      "48",     "--height",           "48",           "--quiet"};
  TempDir dir;
  auto run = [&](const std::string& out, std::vector<std::string> extra) {
    auto args = base;
    args.insert(args.end(), {"--out", dir.File(out)});
    args.insert(args.end(), extra.begin(), extra.end());
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << out << ": " << r.err;
  };
  run("loop", {"--envs", "auto:2"});
  run("pipe", {"--ranks", "2"});
  std::vector<std::string> outs = {"pipe"};
  if (HaveMpi()) {
    std::string cmd =
        "ASAN_OPTIONS=detect_leaks=0 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
        "mpirun -np 2 --oversubscribe " +
        VismaskBin() + "-mpi";
    for (const auto& a : base) cmd += " " + a;
    cmd += " --out " + dir.File("mpi") + " >" + dir.File("mpi.log") + " 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd << "\n" << ReadFile(dir.File("mpi.log"));
    outs.push_back("mpi");
  }
  for (const char* f : {"image.pfm", "patches.csv"}) {
    std::string ref = ReadFile(dir.File(std::string("loop/") + f));
    ASSERT_GT(ref.size(), 100u);
    for (const auto& o : outs) EXPECT_EQ(ref, ReadFile(dir.File(o + "/" + f))) << o << "/" << f;
  }
  for (const auto& o : outs) {
    std::string json = ReadFile(dir.File(o + "/run.json"));
    EXPECT_NE(json.find("\"envs_auto\": 2"), std::string::npos) << o << ": " << json;
  }
}

void ExpectSameBytesEverywhere(const char* method, std::vector<const char*> pipeRanks,
                               std::vector<const char*> mpiRanks,
                               const std::vector<std::string>& kindOf) {
  TempDir dir;
  std::vector<std::string> base = kindOf;
  base.insert(base.end(), {"--mask-method", method});
  auto run = [&](const std::string& out, std::vector<std::string> extra) {
    auto args = base;
    args.insert(args.end(), {"--out", dir.File(out), "--export", dir.File(out + "/scene.glb")});
    args.insert(args.end(), extra.begin(), extra.end());
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << out << ": " << r.err;
  };
  run("loop", {"--transport", "loop"});
  std::vector<std::string> outs;
  for (const char* n : pipeRanks) {
    run(std::string("pipe") + n, {"--ranks", n});
    outs.push_back(std::string("pipe") + n);
  }
  // Under Open MPI too, when build/vismask-mpi exists (make MPI=1).
  std::string mpiBin = VismaskBin() + "-mpi";
  bool mpi = FileExists(mpiBin) && std::system("command -v mpirun >/dev/null 2>&1") == 0;
  if (mpi) {
    for (const char* n : mpiRanks) {
      // detect_leaks=0: under SAN=1, LeakSanitizer reports Open MPI's own
      // allocations from MPI_Init, which it never frees.
      std::string cmd =
          "ASAN_OPTIONS=detect_leaks=0 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
          "mpirun -np " +
          std::string(n) + " --oversubscribe " + mpiBin;
      for (const auto& a : base) cmd += " " + a;
      const std::string out = dir.File(std::string("mpi") + n);
      cmd += " --out " + out + " --export " + out + "/scene.glb >" + dir.File("mpi.log") + " 2>&1";
      ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd << "\n" << ReadFile(dir.File("mpi.log"));
      outs.push_back(std::string("mpi") + n);
    }
  }
  // --export's .glb too (rank 0 writes it from every rank's vertices).
  for (const char* f : {"image.pfm", "patches.csv", "scene.glb"}) {
    std::string ref = ReadFile(dir.File(std::string("loop/") + f));
    ASSERT_GT(ref.size(), 100u);
    for (const auto& o : outs)
      EXPECT_EQ(ref, ReadFile(dir.File(o + "/" + f))) << method << ": " << o << "/" << f;
  }
  std::string last = outs.front();
  std::string json = ReadFile(dir.File(last + "/run.json"));
  EXPECT_NE(json.find("\"ranks\": " + last.substr(4)), std::string::npos) << json;
  EXPECT_NE(json.find(std::string("\"mask_method\": \"") + method + "\""), std::string::npos);
  if (!mpi) std::printf("note: build/vismask-mpi or mpirun missing; the MPI runs were skipped\n");
}

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

// Starts `cmd` under /bin/sh; the pid is the command's own (exec).
pid_t StartCommand(const std::string& cmd) {
  std::fflush(nullptr);
  pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// Waits up to `seconds` for `pid` to end; kills it (SIGKILL) if it does not.
// True if it ended by itself; *status is its wait status, *took the seconds.
bool WaitForExit(pid_t pid, double seconds, int* status, double* took) {
  auto start = std::chrono::steady_clock::now();
  for (;;) {
    *took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (waitpid(pid, status, WNOHANG) == pid) return true;
    if (*took > seconds) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(pid, SIGKILL);
  waitpid(pid, status, 0);
  return false;
}

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

// The children of `parent`, by pid (fork order: rank 1, 2, ... for pipe ranks).
std::vector<pid_t> ChildrenOf(pid_t parent, const TempDir& dir) {
  std::string list = dir.File("children");
  std::string cmd = "pgrep -P " + std::to_string(parent) + " > " + list;
  std::vector<pid_t> pids;
  if (std::system(cmd.c_str()) != 0) return pids;
  std::ifstream in(list);
  for (long pid; in >> pid;) pids.push_back(static_cast<pid_t>(pid));
  std::sort(pids.begin(), pids.end());
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

bool HaveMpi() {
  return FileExists(VismaskBin() + "-mpi") && std::system("command -v mpirun >/dev/null 2>&1") == 0;
}

MpiRun SignalOneMpiRank(int victim, int sig) {
  MpiRun run;
  TempDir dir;
  std::string out = dir.File("out");
  pid_t pid = StartCommand(
      "env ASAN_OPTIONS=detect_leaks=0 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
      "mpirun -np 3 --oversubscribe " +
      VismaskBin() + "-mpi" + kEndless + " --envs 3 --out " + out + " >" + dir.File("log") +
      " 2>&1");
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
