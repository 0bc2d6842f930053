// The same render on one process, on 1-8 forked processes over pipes and (if
// built) under mpirun gives the same bytes; a rank that dies ends the run.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <thread>

#include <gtest/gtest.h>

#include "test_util.h"

namespace vismask {
namespace {

using test::FileExists;
using test::ReadFile;
using test::RunMain;
using test::TempDir;

const std::vector<std::string> kBase = {
    "render", "scenes/cornell.obj", "--envs", "4x1x2", "--rays", "512", "--max-shots", "1200",
    "--width", "96", "--height", "96", "--mask-res", "24", "--patch-size", "50", "--quiet"};

std::string Bin() {
  const char* b = std::getenv("VISMASK_BIN");
  return b ? b : "build/vismask";
}

// `kBase` with --mask-method `method`: the same bytes on one process, on
// forked processes (`pipeRanks`) and under mpirun (`mpiRanks`, when built).
void ExpectSameBytesEverywhere(const char* method, std::vector<const char*> pipeRanks,
                               std::vector<const char*> mpiRanks,
                               const std::vector<std::string>& base = kBase);

// The default allocation (rays in proportion to power, partial shots, the
// rounding drawn from each shot's stream), Sobol' samples, sub-patch
// elements, antialiasing and the cut vertices shared across environments:
// still the same bytes everywhere.
const std::vector<std::string> kPowerBase = {
    "render", "scenes/cornell.obj", "--envs", "2x1x2", "--emitted-rays", "400000", "--max-rays",
    "2048", "--stop-unshot", "2e-2", "--width", "96", "--height", "96", "--mask-res", "24",
    "--patch-size", "50", "--quiet"};

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
const std::vector<std::string> kTexturedBase = {
    "render", "scenes/textured/room.obj", "--envs", "2x1x1", "--emitted-rays", "300000",
    "--max-rays", "2048", "--stop-unshot", "2e-2", "--width", "96", "--height", "96",
    "--mask-res", "24", "--patch-size", "1", "--quiet"};

TEST(RanksTest, TexturedSceneGivesTheSameBytesEverywhere) {
  ExpectSameBytesEverywhere("B", {"2"}, {"2"}, kTexturedBase);
  std::vector<std::string> point = kTexturedBase;
  point.insert(point.end(), {"--envs", "2x1x2", "--aa", "off"});
  ExpectSameBytesEverywhere("R", {"2", "4"}, {"4"}, point);
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
  const std::vector<std::string> smooth = {
      "render", "scenes/smooth/sphere-vn.obj", "--envs", "2x2x1", "--emitted-rays", "300000",
      "--width", "96", "--height", "96", "--mask-res", "24", "--quiet",
      "--camera", "0,0.3,4,0,0,0,0,1,0,35"};
  ExpectSameBytesEverywhere("R", {"2", "3", "4"}, {"2"}, smooth);
}

void ExpectSameBytesEverywhere(const char* method, std::vector<const char*> pipeRanks,
                               std::vector<const char*> mpiRanks,
                               const std::vector<std::string>& kindOf) {
  TempDir dir;
  std::vector<std::string> base = kindOf;
  base.insert(base.end(), {"--mask-method", method});
  auto run = [&](const std::string& out, std::vector<std::string> extra) {
    auto args = base;
    args.insert(args.end(), {"--out", dir.File(out)});
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
  std::string mpiBin = Bin() + "-mpi";
  bool mpi = FileExists(mpiBin) && std::system("command -v mpirun >/dev/null 2>&1") == 0;
  if (mpi) {
    for (const char* n : mpiRanks) {
      // detect_leaks=0: under SAN=1, LeakSanitizer reports Open MPI's own
      // allocations from MPI_Init, which it never frees.
      std::string cmd = "ASAN_OPTIONS=detect_leaks=0 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun -np " +
                        std::string(n) + " --oversubscribe " + mpiBin;
      for (const auto& a : base) cmd += " " + a;
      cmd += " --out " + dir.File(std::string("mpi") + n) + " >" + dir.File("mpi.log") + " 2>&1";
      ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd << "\n" << ReadFile(dir.File("mpi.log"));
      outs.push_back(std::string("mpi") + n);
    }
  }
  for (const char* f : {"image.pfm", "patches.csv"}) {
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
  std::string cmd = Bin() + " render scenes/cornell.obj --envs 4 --ranks 4 --rays 256 --out " +
                    dir.File("out") + " --max-shots 100000000 --stop-unshot 0 --quiet 2>" +
                    dir.File("err");
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
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - killedAt).count();
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
  // No rank left behind.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  // "[/]tmp/..." matches the ranks' command lines but not this shell's own.
  std::string left = "pgrep -f '[/]" + dir.File("out").substr(1) + "' >/dev/null";
  EXPECT_NE(std::system(left.c_str()), 0) << "a rank outlived the run";
  std::printf("killed rank's run ended after %.2f s\n", seconds);
}

}  // namespace
}  // namespace vismask
