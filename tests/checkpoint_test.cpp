// Checkpoint and resume (--checkpoint, --resume; checkpoint.h): a run
// killed anywhere, or ended by a signal, and resumed from its checkpoint
// ends with the bytes of a run never stopped, on any transport and rank
// count; a kill while a checkpoint is written leaves the one before it
// usable; a checkpoint of another run is refused.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "ranks_test_util.h"
#include "test_util.h"

namespace vismask {
namespace {

using test::FileExists;
using test::ReadFile;
using test::ShellOutput;
using test::TempDir;
using test::VismaskBin;

// 2x2x1 environments (small: patches of 60 units), 8 rounds of at most 4 shots each: with
// --checkpoint-every 0 a checkpoint at each of the 7 round ends before the
// last, of 5 files on one process (4 environments and the manifest).
const char kRun[] =
    " render scenes/cornell.obj --envs 2x2x1 --max-shots 120 --round-shots 4 --width 64 "
    "--height 64 --patch-size 60 --quiet";
constexpr int kFilesPerCheckpoint = 5;
constexpr int kCheckpoints = 7;
const char* const kStages[] = {"write", "sync", "rename", "renamed"};

// `cmd`, a shell command line (no single quote in it), run to its end
// (at most 120 s): its exit status, its output in *log.
int Shell(const std::string& cmd, std::string* log) {
  return ShellOutput("sh -c '" + cmd + "'", 120, log);
}

// `cmd` (after the binary) run to its end: its exit status, output in *log.
int RunVismask(const std::string& cmd, std::string* log) {
  return Shell(VismaskBin() + cmd, log);
}

// The outputs that must be byte-identical.
void ExpectSameOutputs(const std::string& a, const std::string& b) {
  for (const char* name : {"image.pfm", "image.png", "patches.csv"}) {
    ASSERT_TRUE(FileExists(a + "/" + name)) << a << "/" << name;
    ASSERT_TRUE(FileExists(b + "/" + name)) << b << "/" << name;
    EXPECT_TRUE(ReadFile(a + "/" + name) == ReadFile(b + "/" + name))
        << name << " differs between " << a << " and " << b;
  }
}

// The manifest's `key` line's value, or "".
std::string ManifestLine(const std::string& dir, const std::string& key) {
  const std::string text = ReadFile(dir + "/manifest");
  size_t at = text.find("\n" + key + " ");
  if (at == std::string::npos) return "";
  at += key.size() + 2;
  return text.substr(at, text.find('\n', at) - at);
}

std::vector<std::string> TempFiles(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().filename().string().find(".tmp.") != std::string::npos)
      names.push_back(e.path().filename().string());
  return names;
}

// Runs kRun + `ranks` with the checkpoint test hook killing the process at
// call `k`'s `stage` (os::WriteFileAtomic), then resumes a copy of the
// checkpoint with each of `resumes` (rank options; "mpi2" under mpirun)
// and compares every resumed run's outputs with `ref`'s.
void KillAndResume(const TempDir& dir, const std::string& ref, const std::string& launch,
                   const std::string& ranks, const char* stage, int k,
                   const std::vector<std::string>& resumes, const std::string& run = kRun) {
  SCOPED_TRACE(std::string("killed at ") + stage + ":" + std::to_string(k) + " " + launch + ranks);
  const std::string ck = dir.File("ck");
  std::filesystem::remove_all(ck);
  std::string log;
  const int code = Shell("VISMASK_TEST_CHECKPOINT_KILL=" + std::string(stage) + ":" +
                             std::to_string(k) + " " + launch + run + ranks + " --out " +
                             dir.File("killed") + " --checkpoint " + ck + " --checkpoint-every 0",
                         &log);
  ASSERT_NE(code, 0) << "the run was not killed\n" << log;
  ASSERT_FALSE(FileExists(dir.File("killed") + "/run.json")) << log;
  ASSERT_NE(ManifestLine(ck, "generation"), "") << "no complete checkpoint\n" << log;
  for (size_t i = 0; i < resumes.size(); ++i) {
    const std::string copy = dir.File("ck" + std::to_string(i));
    const std::string out = dir.File("resumed" + std::to_string(i));
    std::filesystem::remove_all(copy);
    std::filesystem::remove_all(out);
    std::filesystem::copy(ck, copy);
    std::string rlog;
    const std::string cmd =
        resumes[i] == "mpi2" ? test::MpiCommand("2") + run : VismaskBin() + run + resumes[i];
    ASSERT_EQ(Shell(cmd + " --out " + out + " --resume " + copy, &rlog), 0) << resumes[i] << "\n"
                                                                            << rlog;
    ExpectSameOutputs(ref, out);
    // The killed run's temporary checkpoint file, removed by the resumed run
    // (one process: with several, a rank may outlive rank 0 by a moment,
    // and a live process's files are left).
    if (launch == VismaskBin() && ranks.empty()) {
      EXPECT_TRUE(TempFiles(copy).empty()) << "a killed run's temporary file was left";
    }
  }
}

class CheckpointTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string log;
    ASSERT_EQ(RunVismask(std::string(kRun) + " --out " + ref(), &log), 0) << log;
  }
  std::string ref() const { return dir.File("ref"); }
  TempDir dir;
};

// One process, killed by SIGKILL at a random round's checkpoint (a random
// file of it, at a random step of its writing), for each mask method: the
// outputs of the run resumed (on one process; for R also on two pipe ranks)
// are the uninterrupted run's. The seed is printed, so a failure can be rerun.
TEST_F(CheckpointTest, LoopKilledAtARandomRoundResumesIdentically) {
  const unsigned seed = std::random_device{}();
  std::printf("seed %u\n", seed);
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937 rng(seed);
  for (const std::string method :
       {"", " --mask-method A --mask-res 20", " --mask-method B --mask-res 20",
        " --mask-method C --mask-res 20"}) {
    SCOPED_TRACE(method);
    const std::string run = kRun + method;
    std::string log;
    if (!method.empty()) {
      ASSERT_EQ(RunVismask(run + " --out " + ref() + "m", &log), 0) << log;
    }
    // After the first checkpoint is complete: one before that has nothing to resume.
    const int k = std::uniform_int_distribution<int>(kFilesPerCheckpoint + 1,
                                                     kFilesPerCheckpoint * kCheckpoints)(rng);
    const char* stage = kStages[std::uniform_int_distribution<int>(0, 3)(rng)];
    // Resumed on two pipe ranks too for the default method (R).
    std::vector<std::string> resumes = {""};
    if (method.empty()) resumes.push_back(" --ranks 2");
    KillAndResume(dir, method.empty() ? ref() : ref() + "m", VismaskBin(), "", stage, k, resumes,
                  run);
  }
}

// Light from outside (--sky, --sun): the outside shooters' unshot power is
// part of the state. Killed at the fourth checkpoint's first file, resumed
// on one process and on two pipe ranks.
TEST_F(CheckpointTest, SkyAndSunResumeIdentically) {
  const std::string run =
      " render scenes/skylight.obj --sky 0.4,0.5,0.7 --sun 0.3,1,0.2,400,380,360 --envs 2x1x2 "
      "--max-shots 120 --round-shots 4 --width 64 --height 64 --patch-size 0.8 --quiet";
  std::string log;
  ASSERT_EQ(RunVismask(run + " --out " + ref() + "s", &log), 0) << log;
  KillAndResume(dir, ref() + "s", VismaskBin(), "", "write", 3 * kFilesPerCheckpoint + 1,
                {"", " --ranks 2"}, run);
}

// --sky FILE.hdr: the map is read again on resume (its bytes are part of
// the checkpoint's identity); killed and resumed as above.
TEST_F(CheckpointTest, SkyMapResumesIdentically) {
  const std::string run =
      " render scenes/skylight.obj --sky scenes/skies/two-colour.hdr --envs 2x1x2 "
      "--max-shots 120 --round-shots 4 --width 64 --height 64 --patch-size 0.8 --quiet";
  std::string log;
  ASSERT_EQ(RunVismask(run + " --out " + ref() + "sm", &log), 0) << log;
  KillAndResume(dir, ref() + "sm", VismaskBin(), "", "write", 3 * kFilesPerCheckpoint + 1,
                {"", " --ranks 2"}, run);
}

// The sky map's bytes are part of the identity: the same path with other
// bytes is refused, naming sky_map; the same bytes resume.
TEST_F(CheckpointTest, CheckpointWithAnotherSkyMapIsRefused) {
  const std::string sky = dir.File("sky.hdr"), ck = dir.File("ck");
  test::WriteFile(sky, ReadFile("scenes/skies/two-colour.hdr"));
  const std::string run = " render scenes/skylight.obj --sky " + sky +
                          " --envs 2x1x2 --max-shots 120 --round-shots 4 --width 32 --height 32 "
                          "--patch-size 0.8 --quiet";
  std::string log;
  ASSERT_NE(
      Shell("VISMASK_TEST_CHECKPOINT_KILL=rename:" + std::to_string(3 * kFilesPerCheckpoint + 1) +
                " " + VismaskBin() + run + " --out " + dir.File("killed") + " --checkpoint " + ck +
                " --checkpoint-every 0",
            &log),
      0)
      << log;
  std::string other = ReadFile(sky);
  other[other.size() - 2] ^= 1;  // a texel's green
  test::WriteFile(sky, other);
  log.clear();
  EXPECT_EQ(RunVismask(run + " --out " + dir.File("refused") + " --resume " + ck, &log), 2) << log;
  EXPECT_NE(log.find("the checkpoint is of another run"), std::string::npos) << log;
  EXPECT_NE(log.find("sky_map: "), std::string::npos) << log;
  test::WriteFile(sky, ReadFile("scenes/skies/two-colour.hdr"));
  log.clear();
  EXPECT_EQ(RunVismask(run + " --out " + dir.File("resumed") + " --resume " + ck, &log), 0) << log;
}

// Two pipe ranks killed at a random round (whichever rank reaches the call
// first: rank 0 writes 3 files a checkpoint, rank 1 two), resumed on one
// process and on three ranks.
TEST_F(CheckpointTest, PipeRanksKilledAtARandomRoundResumeOnOneAndThreeRanks) {
  const unsigned seed = std::random_device{}();
  std::printf("seed %u\n", seed);
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937 rng(seed);
  const int k = std::uniform_int_distribution<int>(4, 2 * kCheckpoints)(rng);
  const char* stage = kStages[std::uniform_int_distribution<int>(0, 3)(rng)];
  KillAndResume(dir, ref(), VismaskBin(), " --ranks 2", stage, k, {"", " --ranks 3"});
}

// Under mpirun (skipped when build/vismask-mpi or mpirun is missing): two
// ranks killed at a random round, resumed on two.
TEST_F(CheckpointTest, MpiRanksKilledAtARandomRoundResumeOnTwo) {
  if (!test::HaveMpi()) GTEST_SKIP() << "build/vismask-mpi or mpirun missing";
  const unsigned seed = std::random_device{}();
  std::printf("seed %u\n", seed);
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937 rng(seed);
  const int k = std::uniform_int_distribution<int>(4, 2 * kCheckpoints)(rng);
  const char* stage = kStages[std::uniform_int_distribution<int>(0, 3)(rng)];
  KillAndResume(dir, ref(), test::MpiCommand("2"), "", stage, k, {"mpi2"});
}

// A kill at each step of writing a file of the third checkpoint (an
// environment's, and the manifest) leaves the second usable (or, once the
// manifest is renamed, the third): the manifest names a complete one, and
// resuming from it gives the uninterrupted run's outputs.
TEST_F(CheckpointTest, KillWhileWritingACheckpointLeavesThePreviousOneUsable) {
  const int firstFile = 2 * kFilesPerCheckpoint + 1, manifest = 3 * kFilesPerCheckpoint;
  for (int k : {firstFile, manifest}) {
    for (const char* stage : kStages) {
      KillAndResume(dir, ref(), VismaskBin(), "", stage, k, {""});
      const bool third = k == manifest && std::string(stage) == "renamed";
      EXPECT_EQ(ManifestLine(dir.File("ck"), "generation"), third ? "3" : "2") << stage << ":" << k;
      // The killed write's temporary file: half written, synced or not, never renamed.
      const bool leftTemp = std::string(stage) != "renamed";
      EXPECT_EQ(TempFiles(dir.File("ck")).size(), leftTemp ? 1u : 0u) << stage << ":" << k;
    }
  }
}

// SIGINT (to rank 0 alone) writes a checkpoint at the round's end and ends
// the run with 130 and no outputs; resuming finishes with the bytes of a
// run never stopped. One process and two pipe ranks.
TEST(CheckpointSignalTest, SigintWritesACheckpointAndExits130) {
  TempDir dir;
  const std::string run =
      " render scenes/cornell.obj --envs 2x2x1 --max-shots 2000 --round-shots 4 --width 64 "
      "--height 64 --emitted-rays 400000";
  std::string log;
  ASSERT_EQ(RunVismask(run + " --quiet --out " + dir.File("ref"), &log), 0) << log;
  for (const std::string ranks : {"", " --ranks 2"}) {
    SCOPED_TRACE(ranks);
    const std::string ck = dir.File("ck"), out = dir.File("out"),
                      err = dir.File("err" + std::to_string(ranks.size()));
    std::filesystem::remove_all(ck);
    std::filesystem::remove_all(out);
    pid_t pid = test::StartCommand(VismaskBin() + run + ranks + " --out " + out + " --checkpoint " +
                                   ck + " --checkpoint-every 1000 2>" + err);
    ASSERT_GT(pid, 0);
    // In the solve: its first progress line.
    for (int i = 0; i < 1000 && ReadFile(err).find("vismask: shot") == std::string::npos; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ASSERT_NE(ReadFile(err).find("vismask: shot"), std::string::npos) << ReadFile(err);
    ASSERT_EQ(kill(pid, SIGINT), 0);
    int status = 0;
    double took = 0.0;
    ASSERT_TRUE(test::WaitForExit(pid, 30.0, &status, &took)) << ReadFile(err);
    ASSERT_TRUE(WIFEXITED(status)) << status;
    EXPECT_EQ(WEXITSTATUS(status), 130) << ReadFile(err);
    EXPECT_NE(ReadFile(err).find("--resume"), std::string::npos) << ReadFile(err);
    EXPECT_FALSE(FileExists(out + "/run.json"));
    EXPECT_TRUE(TempFiles(out).empty());
    const std::string shots = ManifestLine(ck, "shots");
    ASSERT_NE(shots, "") << ReadFile(err);
    EXPECT_LT(std::stoi(shots), 2000) << "the checkpoint is of the run's end";
    ASSERT_EQ(RunVismask(run + ranks + " --quiet --out " + out + " --resume " + ck, &log), 0)
        << log;
    ExpectSameOutputs(dir.File("ref"), out);
  }
}

// A checkpoint of another scene, other environments or another
// result-changing option is refused (exit 2, the difference named, no
// output); one with only result-neutral options changed resumes.
TEST_F(CheckpointTest, CheckpointOfAnotherRunIsRefused) {
  const std::string ck = dir.File("ck");
  std::string log;
  ASSERT_NE(
      Shell("VISMASK_TEST_CHECKPOINT_KILL=rename:" + std::to_string(3 * kFilesPerCheckpoint + 1) +
                " " + VismaskBin() + kRun + " --out " + dir.File("killed") + " --checkpoint " + ck +
                " --checkpoint-every 0",
            &log),
      0)
      << log;
  // Another scene: the same file with one more comment line.
  std::filesystem::copy("scenes/cornell.obj", dir.File("cornell.obj"));
  std::filesystem::copy("scenes/cornell.mtl", dir.File("cornell.mtl"));
  test::WriteFile(dir.File("cornell.obj"), ReadFile("scenes/cornell.obj") + "# edited\n");
  std::string other = kRun;
  other.replace(other.find("scenes/cornell.obj"), 18, dir.File("cornell.obj"));
  struct Case {
    std::string cmd, names;
  } cases[] = {{std::string(kRun) + " --seed 7", "options: "},
               {std::string(kRun) + " --min-rays 8", "options: "},
               {other, "scene: "},
               {std::string(kRun) + " --envs 4x1x1", "environments: "}};
  for (const Case& c : cases) {
    const std::string out = dir.File("refused");
    log.clear();
    EXPECT_EQ(RunVismask(c.cmd + " --out " + out + " --resume " + ck, &log), 2) << c.cmd << "\n"
                                                                                << log;
    EXPECT_NE(log.find("the checkpoint is of another run"), std::string::npos) << log;
    EXPECT_NE(log.find(c.names), std::string::npos) << log;
    EXPECT_FALSE(FileExists(out + "/run.json"));
    EXPECT_TRUE(TempFiles(out).empty());
  }
  // A damaged environment file is refused too.
  {
    std::filesystem::copy(ck, dir.File("damaged"));
    const std::string slot = ManifestLine(ck, "slot");
    const std::string file = dir.File("damaged") + "/env-00002." + slot;
    std::string bytes = ReadFile(file);
    ASSERT_GT(bytes.size(), 1000u);
    bytes[bytes.size() / 2] ^= 1;
    test::WriteFile(file, bytes);
    log.clear();
    EXPECT_EQ(RunVismask(std::string(kRun) + " --out " + dir.File("refused") + " --resume " +
                             dir.File("damaged"),
                         &log),
              2)
        << log;
    EXPECT_NE(log.find("damaged"), std::string::npos) << log;
  }
  // No checkpoint at all.
  log.clear();
  EXPECT_EQ(RunVismask(std::string(kRun) + " --out " + dir.File("refused") + " --resume " +
                           dir.File("none"),
                       &log),
            2);
  EXPECT_NE(log.find("no complete checkpoint"), std::string::npos) << log;
  // Options that leave the result as it is may differ.
  log.clear();
  ASSERT_EQ(RunVismask(std::string(kRun) +
                           " --ranks 2 --transport pipe --rank-timeout 30 --mem-budget 1G "
                           "--checkpoint-every 5 --out " +
                           dir.File("neutral") + " --resume " + ck,
                       &log),
            0)
      << log;
  ExpectSameOutputs(ref(), dir.File("neutral"));
}

// `vismask footprint` gives each rank's checkpoint bytes before the run:
// what its environments' files take on the disk, and what run.json says.
TEST_F(CheckpointTest, FootprintGivesEachRanksCheckpointBytes) {
  std::string run = kRun;
  run.replace(run.find(" render "), 8, " footprint ");
  std::string json;
  ASSERT_EQ(RunVismask(run + " --ranks 2 --json", &json), 0) << json;
  std::vector<unsigned long long> predicted;
  for (size_t at = json.find("\"checkpoint_bytes\": "); at != std::string::npos;
       at = json.find("\"checkpoint_bytes\": ", at + 1))
    predicted.push_back(std::stoull(json.substr(at + 20)));
  ASSERT_EQ(predicted.size(), 2u) << json;
  const std::string ck = dir.File("ck"), out = dir.File("out");
  std::string log;
  ASSERT_EQ(RunVismask(std::string(kRun) + " --ranks 2 --out " + out + " --checkpoint " + ck +
                           " --checkpoint-every 0",
                       &log),
            0)
      << log;
  // Two environments a rank (2x2x1 on 2 ranks): 0 and 1 on rank 0, 2 and 3 on rank 1.
  for (int rank = 0; rank < 2; ++rank) {
    unsigned long long bytes = 0;
    for (int e = 2 * rank; e < 2 * rank + 2; ++e)
      bytes += std::filesystem::file_size(ck + "/env-0000" + std::to_string(e) + ".a");
    EXPECT_EQ(bytes, predicted[rank]) << "rank " << rank;
  }
  const std::string runJson = ReadFile(out + "/run.json");
  EXPECT_NE(runJson.find("\"rank_bytes\": [" + std::to_string(predicted[0]) + ", " +
                         std::to_string(predicted[1]) + "]"),
            std::string::npos)
      << runJson;
}

}  // namespace
}  // namespace vismask
