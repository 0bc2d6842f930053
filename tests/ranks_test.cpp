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

#include "ranks_test_util.h"
#include "test_util.h"

namespace vismask {
namespace {

using test::HaveMpi;
using test::MpiCommand;
using test::ReadFile;
using test::RunMain;
using test::TempDir;

const std::vector<std::string> kBase = test::Words(
    "render scenes/cornell.obj --envs 4x1x2 --rays 512 --max-shots 1200 --width 96 --height 96 "
    "--mask-res 24 --patch-size 50 --quiet");

// `kBase` with --mask-method `method`: the same bytes on one process, on
// forked processes (`pipeRanks`) and under mpirun (`mpiRanks`, when built).
void ExpectSameBytesEverywhere(const char* method, std::vector<const char*> pipeRanks,
                               std::vector<const char*> mpiRanks,
                               const std::vector<std::string>& base = kBase);

// `base` with `extra` into dir/`out` (and, with `glb`, --export
// dir/`out`/scene.glb), in this process: it must succeed.
void RenderInto(const TempDir& dir, const std::vector<std::string>& base, const std::string& out,
                const std::vector<std::string>& extra, bool glb = false) {
  auto args = base;
  args.insert(args.end(), {"--out", dir.File(out)});
  if (glb) args.insert(args.end(), {"--export", dir.File(out + "/scene.glb")});
  args.insert(args.end(), extra.begin(), extra.end());
  auto r = RunMain(args);
  ASSERT_EQ(r.code, 0) << out << ": " << r.err;
}

// The same under mpirun on `ranks` ranks (its output in dir/mpi.log).
void RunMpi(const TempDir& dir, const std::string& ranks, const std::vector<std::string>& base,
            const std::string& out, bool glb = false) {
  std::string cmd = MpiCommand(ranks);
  for (const auto& a : base) cmd += " " + a;
  cmd += " --out " + dir.File(out);
  if (glb) cmd += " --export " + dir.File(out) + "/scene.glb";
  cmd += " >" + dir.File("mpi.log") + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd << "\n" << ReadFile(dir.File("mpi.log"));
}

// Each of `files` in dir/loop is there and is the same in dir/`out` for
// each of `outs` (failures prefixed with `what`).
void ExpectSameFiles(const TempDir& dir, std::initializer_list<const char*> files,
                     const std::vector<std::string>& outs, const std::string& what) {
  for (const char* f : files) {
    std::string ref = ReadFile(dir.File(std::string("loop/") + f));
    ASSERT_GT(ref.size(), 100u);
    for (const auto& o : outs)
      EXPECT_EQ(ref, ReadFile(dir.File(o + "/" + f))) << what << o << "/" << f;
  }
}

// The default allocation (rays in proportion to power, partial shots, the
// rounding drawn from each shot's stream), Sobol' samples, sub-patch
// elements, antialiasing and the cut vertices shared across environments:
// still the same bytes everywhere.
const std::vector<std::string> kPowerBase = test::Words(
    "render scenes/cornell.obj --envs 2x1x2 --emitted-rays 400000 --max-rays 2048 "
    "--stop-unshot 2e-2 --width 96 --height 96 --mask-res 24 --patch-size 50 --quiet");

TEST(RanksTest, PowerAllocationAndElementsGiveTheSameBytesEverywhere) {
  ExpectSameBytesEverywhere("R", {"2", "4"}, {"4"}, kPowerBase);
  ExpectSameBytesEverywhere("B", {"3"}, {"2"}, kPowerBase);
  // B's shots there go both ways (--centre-rays auto, the default): some
  // decide only the pixels read downstream, some every open pixel.
  TempDir dir;
  std::vector<std::string> b = kPowerBase;
  b.insert(b.end(), {"--mask-method", "B"});
  RenderInto(dir, b, "b", {});
  const std::string json = ReadFile(dir.File("b/run.json"));
  auto field = [&](const std::string& key) {
    size_t at = json.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key;
    return at == std::string::npos ? 0ull
                                   : std::strtoull(json.c_str() + at + key.size() + 4, nullptr, 10);
  };
  EXPECT_GT(field("centre_read_shots"), 0ull);
  EXPECT_LT(field("centre_read_shots"), field("local_shots"));
}

// --emission-rays given with several environments: the light's shots trace
// a quarter of their worth, and their foreign shots what the header says:
// still the same bytes everywhere.
TEST(RanksTest, EmissionRaysGiveTheSameBytesEverywhere) {
  std::vector<std::string> base = kPowerBase;
  base.insert(base.end(), {"--emission-rays", "0.25"});
  ExpectSameBytesEverywhere("R", {"2"}, {"2"}, base);
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
const std::vector<std::string> kTexturedBase = test::Words(
    "render scenes/textured/room.obj --envs 2x1x1 --emitted-rays 300000 --max-rays 2048 "
    "--stop-unshot 2e-2 --width 96 --height 96 --mask-res 24 --patch-size 1 --quiet");

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

// --sky and --sun: outside shooters on the box faces of the environments
// that lie on them (tiles for B), their packets and routes like a patch's.
TEST(RanksTest, SkyAndSunGiveTheSameBytesEverywhere) {
  const std::vector<std::string> lit = test::Words(
      "render scenes/skylight.obj --sky 0.3,0.4,0.5 --sun 1,4,0.5,3,3,2.5 --envs 2x1x2 "
      "--emitted-rays 200000 --width 64 --height 64 --mask-res 24 --quiet "
      "--camera 0.4,2.2,0.4,3,0.3,3,0,1,0,70");
  ExpectSameBytesEverywhere("R", {"2", "3"}, {"4"}, lit);
  ExpectSameBytesEverywhere("B", {"4"}, {"2"}, lit);
}

// --sky FILE.hdr: each ray's share from the map, normalised over the shot's
// rays by every environment that traces one of them.
TEST(RanksTest, SkyMapGivesTheSameBytesEverywhere) {
  const std::vector<std::string> lit = test::Words(
      "render scenes/skylight.obj --sky scenes/skies/two-colour.hdr --sun 1,4,0.5,3,3,2.5 "
      "--envs 2x1x2 --emitted-rays 200000 --width 64 --height 64 --mask-res 24 --quiet "
      "--camera 0.4,2.2,0.4,3,0.3,3,0,1,0,70");
  ExpectSameBytesEverywhere("R", {"2", "3"}, {"4"}, lit);
  ExpectSameBytesEverywhere("B", {"4"}, {"2"}, lit);
}

// Smoothing shares display values between polygons in different
// environments and ranks, summed in an order that does not depend on them.
TEST(RanksTest, SmoothingGivesTheSameBytesEverywhere) {
  const std::vector<std::string> smooth = test::Words(
      "render scenes/smooth/sphere-vn.obj --envs 2x2x1 --emitted-rays 300000 --width 96 "
      "--height 96 --mask-res 24 --quiet --camera 0,0.3,4,0,0,0,0,1,0,35");
  ExpectSameBytesEverywhere("R", {"2", "3", "4"}, {"2"}, smooth);
}

// Issue 20: the default rounds, sized by work (--round-work, chosen
// at init from the scene), on balanced environments (--envs auto:4): the
// rounds end at the same shot everywhere, so the bytes are the same on
// one process, pipes 1/2/4 and mpirun 1/2/4. The rounds hold many shots
// (else this would test nothing new).
TEST(RanksTest, DefaultWorkRoundsOnBalancedEnvironmentsGiveTheSameBytesEverywhere) {
  const std::vector<std::string> base = test::Words(
      "render scenes/cornell.obj --envs auto:4 --emitted-rays 400000 --max-rays 2048 "
      "--stop-unshot 2e-2 --width 96 --height 96 --mask-res 24 --patch-size 50 --quiet");
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
  // The work the rounds are sized by: grid steps plus the charges of
  // work.h, so more than the steps; on one process a rank's round is all
  // four environments', and the most any one did is at least the mean.
  const double work = number("work"), envWork = number("critical_env_work");
  EXPECT_GT(work, number("grid_steps"));
  EXPECT_EQ(number("critical_rank_work"), work);
  EXPECT_GE(4 * envWork, work);
  EXPECT_LT(envWork, work);
  // Every round but the last is cut by its work, so the rounds are about
  // the work over 4 x the round's.
  EXPECT_GE(number("rounds"), work / (4 * number("round_work")) * 0.5) << json;
  EXPECT_NE(json.find("\"envs_auto\": 4"), std::string::npos);
}

// Issue 20, parallel by default: `--ranks 2` and `mpirun -np 2` with no
// --envs run --envs auto:2, the same bytes as one process given auto:2.
TEST(RanksTest, RanksWithoutEnvsGiveTheBytesOfEnvsAuto) {
  const std::vector<std::string> base = test::Words(
      "render scenes/cornell.obj --patch-size 50 --stop-unshot 5e-2 --width 48 --height 48 "
      "--quiet");
  TempDir dir;
  RenderInto(dir, base, "loop", {"--envs", "auto:2"});
  RenderInto(dir, base, "pipe", {"--ranks", "2"});
  std::vector<std::string> outs = {"pipe"};
  if (HaveMpi()) {
    ASSERT_NO_FATAL_FAILURE(RunMpi(dir, "2", base, "mpi"));
    outs.push_back("mpi");
  }
  ASSERT_NO_FATAL_FAILURE(ExpectSameFiles(dir, {"image.pfm", "patches.csv"}, outs, ""));
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
  RenderInto(dir, base, "loop", {"--transport", "loop"}, true);
  std::vector<std::string> outs;
  for (const char* n : pipeRanks) {
    RenderInto(dir, base, std::string("pipe") + n, {"--ranks", n}, true);
    outs.push_back(std::string("pipe") + n);
  }
  // Under Open MPI too, when build/vismask-mpi exists (make MPI=1).
  bool mpi = HaveMpi();
  if (mpi) {
    for (const char* n : mpiRanks) {
      ASSERT_NO_FATAL_FAILURE(RunMpi(dir, n, base, std::string("mpi") + n, true));
      outs.push_back(std::string("mpi") + n);
    }
  }
  // --export's .glb too (rank 0 writes it from every rank's vertices).
  ASSERT_NO_FATAL_FAILURE(ExpectSameFiles(dir, {"image.pfm", "patches.csv", "scene.glb"}, outs,
                                          std::string(method) + ": "));
  std::string last = outs.front();
  std::string json = ReadFile(dir.File(last + "/run.json"));
  EXPECT_NE(json.find("\"ranks\": " + last.substr(4)), std::string::npos) << json;
  EXPECT_NE(json.find(std::string("\"mask_method\": \"") + method + "\""), std::string::npos);
  if (!mpi) std::printf("note: build/vismask-mpi or mpirun missing; the MPI runs were skipped\n");
}

}  // namespace
}  // namespace vismask
