// The render command's options: bad options and scenes exit 2 naming what is
// wrong, --help lists every option, and the defaults chosen at init.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "render_test_util.h"
#include "test_util.h"
#include "vismask/app/options.h"
#include "vismask/solve/packet.h"
#include "vismask/solve/work.h"

namespace vismask {
namespace {

using namespace test;

TEST(RenderTest, BadOptionsExitTwoAndWriteNothing) {
  TempDir dir;
  std::string out = dir.File("out");
  // Options after "render scenes/cornell.obj".
  const BadCase onCornell[] = {
      {{"--rays", "0"}, "--rays"},
      {{"--rays", "12x"}, "--rays"},
      {{"--patch-size", "nan"}, "--patch-size"},
      {{"--patch-size", "-3"}, "--patch-size"},
      {{"--stop-unshot", "1.5"}, "--stop-unshot"},
      {{"--width"}, "missing value"},
      {{"--bogus", "1"}, "unknown option"},
      {{"--camera", "0,0,0,0,0,0,0,1,0,40"}, "--camera"},
      {{"--camera", "1,2,3"}, "--camera"},
      {{"--camera", "0,0,-5,0,0,0,0,1,0,40,1"}, "--camera"},
      {{"--seed", "-1"}, "--seed"},
      {{"--correct-unshot", "maybe"}, "--correct-unshot"},
      {{"--aa", "4"}, "--aa"},
      {{"--aa"}, "missing value"},
      {{"--stop-error", "0"}, "--stop-error"},
      {{"--stop-error", "1"}, "--stop-error"},
      {{"--stop-error", "nan"}, "--stop-error"},
      {{"--stop-error"}, "missing value"},
      {{"--round-work", "-1"}, "--round-work"},
      {{"--round-work", "1.5e0"}, "--round-work"},  // 1e6 is a count (issue 40); 1.5 is not
      {{"--envs", "auto:0"}, "--envs"},
      {{"--envs", "auto:"}, "--envs"},
      {{"--envs", "auto:67"}, "no grid"},
      {{"--envs", "autox"}, "--envs"},
      {{"--envs", "auto:2", "--ranks", "3"}, "--ranks"},
  };
  std::vector<BadCase> cases;
  for (const BadCase& c : onCornell) {
    BadCase full = {{"render", "scenes/cornell.obj"}, c.message};
    full.args.insert(full.args.end(), c.args.begin(), c.args.end());
    cases.push_back(full);
  }
  cases.push_back({{"render"}, "no scene"});
  cases.push_back({{"frobnicate"}, "unknown command"});
  cases.push_back({{"render", dir.File("missing.obj")}, "missing.obj"});
  for (const BadCase& c : cases) {
    auto args = c.args;  // --out right after the command, so a flag at the end lacks its value
    args.insert(args.begin() + 1, {"--out", out});
    auto r = RunMain(args);
    std::string joined;
    for (auto& a : c.args) joined += a + " ";
    EXPECT_EQ(r.code, 2) << joined;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << joined << "\n" << r.err;
    EXPECT_FALSE(FileExists(out)) << joined << ": wrote output";
  }
}

TEST(RenderTest, MalformedSceneNamesFileAndLine) {
  TempDir dir;
  WriteFile(dir.File("s.mtl"), "newmtl a\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  WriteFile(dir.File("s.obj"), "mtllib s.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  auto r = RunMain({"render", dir.File("s.obj"), "--out", dir.File("out")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(dir.File("s.obj") + ":6:"), std::string::npos) << r.err;
  EXPECT_FALSE(FileExists(dir.File("out")));
}

// A truncated MTL, an OBJ cut mid-face and an unsolvable range: each names
// its file and line, exits 2 and writes nothing.
TEST(RenderTest, TruncatedFilesNameFileAndLine) {
  TempDir dir;
  struct Case {
    const char* mtl;
    const char* obj;
    const char* file;  // "obj" or "mtl"
    int line;
  };
  const char* head = "mtllib s.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const Case cases[] = {
      {"newmtl a\nKd 0.5 0.5 0.5\nKe 1 1", "f 1 2 3\n", "mtl", 3},
      {"newmtl a\nKd 0.5 0", "f 1 2 3\n", "mtl", 2},
      {"newmtl a\nKd 0.5 0.5 0.5\nKe 1 1 1\n", "f 1 2", "obj", 6},
      {"newmtl a\nKd 0.5 0.5 0.5\nKe 1 1 1\n", "f 1 2 3/", "obj", 6},
      {"newmtl a\nKd 0.99 0.5 0.5\nKe 1e35 1 1\n", "f 1 2 3\n", "obj", 6},
  };
  for (const Case& c : cases) {
    test::WriteFile(dir.File("s.mtl"), c.mtl);
    test::WriteFile(dir.File("s.obj"), std::string(head) + c.obj);
    auto r = RunMain({"render", dir.File("s.obj"), "--out", dir.File("out")});
    EXPECT_EQ(r.code, 2) << c.obj;
    std::string where = dir.File(std::string("s.") + c.file) + ":" + std::to_string(c.line) + ": ";
    EXPECT_EQ(r.err.rfind(where, 0), 0u) << r.err;
    EXPECT_FALSE(FileExists(dir.File("out")));
  }
}

TEST(RenderTest, HelpListsEveryOption) {
  testing::internal::CaptureStdout();
  auto r = RunMain({"--help", "all"});
  std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(r.code, 0);
  for (const char* flag :
       {"--out",       "--patch-size",  "--rays",           "--seed",       "--stop-unshot",
        "--max-shots", "--max-seconds", "--width",          "--height",     "--camera",
        "--exposure",  "--quiet",       "--correct-unshot", "--stop-error", "--aa",
        "--strict",    "--emit",        "--round-shots",    "--round-work", "--envs auto",
        "--sky",       "--sun"})
    EXPECT_NE(out.find(flag), std::string::npos) << flag;
}

// Issue 40: --help is a short usage a user can read, with the formats read
// and five examples that parse; --help all is the whole list.
TEST(RenderTest, HelpIsShortWithFiveExamples) {
  testing::internal::CaptureStdout();
  auto r = RunMain({"--help"});
  std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(r.code, 0);
  std::vector<std::string> lines;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  EXPECT_LE(lines.size(), 40u) << out;
  EXPECT_NE(out.find("--help all"), std::string::npos) << out;
  EXPECT_NE(out.find("scenes read: Wavefront OBJ"), std::string::npos) << out;
  EXPECT_EQ(out.find("--ray-alloc"), std::string::npos) << out;  // solver internals: --help all
  auto at = std::find(lines.begin(), lines.end(), "examples:");
  ASSERT_NE(at, lines.end()) << out;
  size_t examples = 0;
  for (++at; at != lines.end(); ++at) {
    if (at->rfind("  vismask ", 0) != 0) continue;
    ++examples;
    // The command (up to any '&&') parses as given.
    std::istringstream words(at->substr(2, at->find(" &&") - 2));
    std::vector<std::string> args;
    for (std::string w; words >> w;) args.push_back(w);
    std::vector<const char*> argv;
    for (const std::string& w : args) argv.push_back(w.c_str());
    Options o;
    Status s = ParseArgs(static_cast<int>(argv.size()), argv.data(), &o);
    EXPECT_TRUE(s.ok()) << *at << ": " << s.ToString();
  }
  EXPECT_EQ(examples, 5u) << out;
  testing::internal::CaptureStdout();
  r = RunMain({"render", "--help", "all"});
  std::string all = testing::internal::GetCapturedStdout();
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(all.find("--ray-alloc"), std::string::npos);
  EXPECT_GT(all.size(), 3 * out.size());
}

// Counts accept scientific notation when the value is exactly an integer,
// read in decimal (no rounding through double).
TEST(RenderTest, CountsAcceptExactIntegersInScientificNotation) {
  auto parse = [](const char* flag, const char* value, Options* o) {
    const char* argv[] = {"vismask", "render", "s.obj", flag, value};
    return ParseArgs(5, argv, o);
  };
  Options o;
  ASSERT_TRUE(parse("--emitted-rays", "1e6", &o).ok());
  EXPECT_EQ(o.emittedRays, 1000000u);
  ASSERT_TRUE(parse("--emitted-rays", "2.5E3", &o).ok());
  EXPECT_EQ(o.emittedRays, 2500u);
  ASSERT_TRUE(parse("--emitted-rays", "10e-1", &o).ok());
  EXPECT_EQ(o.emittedRays, 1u);
  ASSERT_TRUE(parse("--emitted-rays", "1e+12", &o).ok());
  EXPECT_EQ(o.emittedRays, 1000000000000u);
  ASSERT_TRUE(parse("--max-shots", "3e3", &o).ok());
  EXPECT_EQ(o.maxShots, 3000u);
  ASSERT_TRUE(parse("--seed", "1.8446744073709551615e19", &o).ok());
  EXPECT_EQ(o.seed, 18446744073709551615ull);
  ASSERT_TRUE(parse("--seed", "18446744073709551615", &o).ok());
  EXPECT_EQ(o.seed, 18446744073709551615ull);
  ASSERT_TRUE(parse("--seed", "0e999999", &o).ok());
  EXPECT_EQ(o.seed, 0u);
  for (const char* bad : {"1.5", "1e-1", "2.515e2", "1e", "1e+", "e3", "1.e3", "-1e3", "1e6x",
                          "1.8446744073709551616e19", "2e19", "1e21", " 1e3"}) {
    Status s = parse("--seed", bad, &o);
    EXPECT_FALSE(s.ok()) << bad;
  }
  Status s = parse("--emitted-rays", "1.5e0", &o);
  EXPECT_EQ(s.ToString(), "vismask: --emitted-rays: expected an integer in [1, 1e12], got '1.5e0'");
}

// `vismask render scenes/cornell.obj ARGS` parsed into *o.
Status ParseCornell(const std::vector<const char*>& args, Options* o) {
  std::vector<const char*> argv = {"vismask", "render", "scenes/cornell.obj"};
  argv.insert(argv.end(), args.begin(), args.end());
  return ParseArgs(static_cast<int>(argv.size()), argv.data(), o);
}

// Issue 20: how big a round is. With several environments and neither
// --round-shots nor --round-work, rounds by work (its size chosen at init);
// --round-shots alone keeps the rounds of before; one environment, one shot.
TEST(RenderTest, RoundSizeDefaults) {
  struct Case {
    std::vector<const char*> args;
    uint32_t shots;
    bool autoWork;
    uint64_t work;
  };
  const Case cases[] = {
      {{"--envs", "1"}, 1, false, 0},
      // 6 packets a shot in 512 KiB: Method R's (the default) 144 + 8192/8
      // bytes, 74; B's (--mask-res alone selects it) 144 + 4R^2/8 bytes
      // (padded to 8), 254 at R = 20, 16 at R = 100.
      {{"--envs", "2"}, 74, true, 0},
      {{"--envs", "2", "--mask-res", "20"}, 254, true, 0},
      {{"--envs", "auto:4"}, 74, true, 0},
      {{"--envs", "2", "--round-shots", "8"}, 8, false, 0},
      {{"--envs", "2", "--round-shots", "1"}, 1, false, 0},
      // --round-work alone: the automatic shot limit (the outbox's cap too).
      {{"--envs", "2", "--round-work", "5000"}, 74, false, 5000},
      {{"--envs", "2", "--round-work", "0"}, 74, false, 0},
      {{"--envs", "2", "--round-work", "5000", "--mask-res", "20"}, 254, false, 5000},
      {{"--envs", "2", "--round-work", "7", "--round-shots", "3"}, 3, false, 7},
      {{"--envs", "1", "--round-work", "9"}, 74, false, 9},
      {{"--envs", "2", "--mask-method", "B"}, 62, true, 0},
      {{"--envs", "2", "--mask-res", "100"}, 16, true, 0},
  };
  for (const Case& c : cases) {
    Options o;
    Status s = ParseCornell(c.args, &o);
    ASSERT_TRUE(s.ok()) << s.ToString();
    EXPECT_EQ(o.roundShots, c.shots) << c.args.size();
    EXPECT_EQ(o.roundWorkAuto, c.autoWork) << c.args.size();
    EXPECT_EQ(o.roundWork, c.work) << c.args.size();
  }
  // The automatic size: 32 full shots, each its rays times (the cube root
  // of kStepCellsPerPatch cells for each of an environment's patches, plus
  // a ray's and a hit's work), plus a shot's work (work.h). Centre rays are
  // not in it.
  Options o;
  o.maxRays = 1000;
  o.maskMethod = MaskMethod::kB;
  const WorkCosts& b = kMaskWork;
  const uint64_t shot = 1000 * (20 + b.ray + b.hit) + b.shot;
  EXPECT_EQ(AutoRoundWork(o, 2000.0, 1), 32 * shot);
  EXPECT_EQ(AutoRoundWork(o, 16000.0, 8), 32 * shot);
  o.maskMethod = MaskMethod::kR;  // R's own costs
  const WorkCosts& r = kRayBitsWork;
  EXPECT_EQ(AutoRoundWork(o, 2000.0, 1), 32 * (1000 * (20 + r.ray + r.hit) + r.shot));
  o.rayAlloc = Options::RayAlloc::kFixed;  // --rays a shot
  o.rays = 500;
  EXPECT_EQ(AutoRoundWork(o, 2000.0, 1), 32 * (500 * (20 + r.ray + r.hit) + r.shot));
}

// Method R is the default; --mask-res names a hemisphere mask's resolution,
// so given alone it selects Method B; an explicit method wins.
TEST(RenderTest, MaskMethodDefaults) {
  struct Case {
    std::vector<const char*> args;
    MaskMethod method;
  };
  const Case cases[] = {
      {{}, MaskMethod::kR},
      {{"--envs", "2"}, MaskMethod::kR},
      {{"--mask-res", "20"}, MaskMethod::kB},
      {{"--mask-res", "20", "--mask-method", "A"}, MaskMethod::kA},
      {{"--mask-method", "C", "--mask-res", "20"}, MaskMethod::kC},
      {{"--mask-method", "B"}, MaskMethod::kB},
  };
  for (const Case& c : cases) {
    Options o;
    Status s = ParseCornell(c.args, &o);
    ASSERT_TRUE(s.ok()) << s.ToString();
    EXPECT_EQ(static_cast<int>(o.maskMethod), static_cast<int>(c.method)) << c.args.size();
  }
}

// Issue 20: the default queue lets every environment make a whole round
// (admission shares the free slots among them): environments x round
// shots, at most 64 an environment and within 1 MiB of slots, at least the
// 64 of before.
TEST(RenderTest, QueueDefaults) {
  struct Case {
    std::vector<const char*> args;
    uint32_t queue;
  };
  const uint64_t packetR = PacketBytes(MaskShapeOf(MaskMethod::kR, 50, Options().maxRays));
  const uint64_t packet50 = PacketBytes(MaskShapeOf(MaskMethod::kB, 50, Options().maxRays));
  const Case cases[] = {
      {{"--envs", "1"}, 64},
      {{"--envs", "2"}, 2 * 64},  // R's 74 shots a round, at most 64 an environment
      {{"--envs", "2", "--mask-method", "B"}, 2 * 62},
      {{"--envs", "2", "--round-shots", "1"}, 64},
      {{"--envs", "4x1x4", "--mask-res", "8"}, 16 * 64},  // at most 64 an environment
      {{"--envs", "4x1x4", "--mask-res", "20"}, 16 * 64},
      {{"--envs", "5x5x5"}, static_cast<uint32_t>(kAutoQueueBytes / packetR)},
      {{"--envs", "5x5x5", "--mask-method", "B"},
       static_cast<uint32_t>(kAutoQueueBytes / packet50)},
      {{"--envs", "5x5x5", "--queue", "7"}, 7},
      {{"--envs", "2", "--queue", "64"}, 64},
  };
  for (const Case& c : cases) {
    Options o;
    Status s = ParseCornell(c.args, &o);
    ASSERT_TRUE(s.ok()) << s.ToString();
    EXPECT_EQ(o.queue, c.queue) << c.args[1];
  }
  EXPECT_LT(kAutoQueueBytes / packet50, 125u * 63u);  // the byte cap is what binds at 5x5x5
}

// Issue 20, parallel by default: more than one rank and no --envs means
// --envs auto, one balanced environment a rank (--ranks at parse; the MPI
// world's size through SetWorldSize), with the rounds of several
// environments; --envs given is kept as given.
TEST(RenderTest, RanksWithoutEnvsMeanOneBalancedEnvironmentARank) {
  auto parse = [](std::vector<const char*> args, Options* o) {
    Status s = ParseCornell(args, o);
    EXPECT_TRUE(s.ok()) << s.ToString();
  };
  Options three;
  parse({"--ranks", "3"}, &three);
  EXPECT_TRUE(three.envsAuto);
  EXPECT_EQ(three.envsAutoCount, 3);
  EXPECT_EQ(three.envs[0] * three.envs[1] * three.envs[2], 3);
  EXPECT_TRUE(three.roundWorkAuto);
  EXPECT_FALSE(SetWorldSize(3, &three));  // already auto
  Options given;
  parse({"--ranks", "2", "--envs", "2"}, &given);
  EXPECT_FALSE(given.envsAuto);
  EXPECT_FALSE(SetWorldSize(2, &given));
  Options one;
  parse({}, &one);
  EXPECT_FALSE(one.envsAuto);
  EXPECT_EQ(one.roundShots, 1u);
  EXPECT_FALSE(SetWorldSize(1, &one));
  EXPECT_TRUE(SetWorldSize(4, &one));  // mpirun -np 4, no --envs
  EXPECT_TRUE(one.envsAuto);
  EXPECT_EQ(one.envsAutoCount, 4);
  EXPECT_EQ(one.envs[0] * one.envs[1] * one.envs[2], 4);
  EXPECT_TRUE(one.roundWorkAuto);
  EXPECT_GT(one.roundShots, 1u);
}

}  // namespace
}  // namespace vismask

#include "../src/app/run.h"

namespace vismask {
namespace {

// Issue 40: init's stages. Each over a second prints a line on stderr (rank
// 0, not --quiet); run.json lists them all with their seconds.
TEST(RenderTest, InitStagesOverASecondSaySoAndRunJsonListsThem) {
  EXPECT_EQ(run::InitStageLine("textures", 1.5, "9 images decoded"),
            "vismask: init: textures took 1.5 s (9 images decoded)");
  EXPECT_EQ(run::InitStageLine("meshing", 2.25, ""), "vismask: init: meshing took 2.2 s");
  EXPECT_EQ(run::InitStageLine("meshing", 1.0, ""), "");
  EXPECT_EQ(run::InitStageLine("meshing", 0.2, "x"), "");
  run::InitClock clock;  // report off: counted, not printed
  clock.Done("meshing", 0.5);
  clock.Done("grid and arenas", 0.25);
  clock.Done("meshing", 0.75);
  ASSERT_EQ(clock.stages.size(), 2u);
  EXPECT_EQ(clock.stages[0].first, "meshing");
  EXPECT_DOUBLE_EQ(clock.stages[0].second, 1.25);

  test::TempDir dir;
  auto r = test::RunMain({"render", "scenes/textured/room.obj", "--out", dir.File("out"),
                          "--max-shots", "50", "--width", "16", "--height", "16", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string json = test::ReadFile(dir.File("out/run.json"));
  size_t at = json.find("\"init_stages\": {");
  ASSERT_NE(at, std::string::npos);
  for (const char* stage : {"reading the scene", "textures", "cutting the scene into environments",
                            "emitter check", "texture means", "meshing", "grid and arenas"})
    EXPECT_NE(json.find(std::string("\"") + stage + "\": ", at), std::string::npos) << stage;
}

}  // namespace
}  // namespace vismask
