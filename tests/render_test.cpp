// End-to-end renders through the command line: the closed-box analytic
// solution, determinism, the outputs' formats, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "test_util.h"
#include "vismask/options.h"
#include "vismask/packet.h"

namespace vismask {
namespace {

using test::FileExists;
using test::ReadCsv;
using test::ReadFile;
using test::RunMain;
using test::TempDir;
using test::WriteFile;

// A closed cube of side `s`, six faces facing inward, one material.
void WriteClosedBox(const std::string& dir, double s, double rho, double e) {
  std::ostringstream obj;
  obj << "mtllib box.mtl\nusemtl wall\n";
  const double c[8][3] = {{0, 0, 0}, {s, 0, 0}, {s, s, 0}, {0, s, 0},
                          {0, 0, s}, {s, 0, s}, {s, s, s}, {0, s, s}};
  for (auto& v : c) obj << "v " << v[0] << " " << v[1] << " " << v[2] << "\n";
  // Counter-clockwise seen from inside the cube.
  obj << "f 1 2 3 4\n"   // z = 0, normal +z
      << "f 5 8 7 6\n"   // z = s, normal -z
      << "f 1 5 6 2\n"   // y = 0, normal +y
      << "f 4 3 7 8\n"   // y = s, normal -y
      << "f 1 4 8 5\n"   // x = 0, normal +x
      << "f 2 6 7 3\n";  // x = s, normal -x
  WriteFile(dir + "/box.obj", obj.str());
  std::ostringstream mtl;
  mtl << "newmtl wall\nKd " << rho << " " << rho << " " << rho << "\nKe " << e << " " << e << " "
      << e << "\n";
  WriteFile(dir + "/box.mtl", mtl.str());
}

TEST(RenderTest, ClosedBoxConvergesToAnalyticRadiosity) {
  TempDir dir;
  const double rho = 0.5, e = 2.0, exact = e / (1.0 - rho);
  WriteClosedBox(dir.path(), 1.0, rho, e);
  auto r = RunMain({"render", dir.File("box.obj"), "--out", dir.File("out"), "--patch-size", "0.34",
                    "--rays", "50000", "--stop-unshot", "1e-4", "--quiet", "--width", "32",
                    "--height", "32"});
  ASSERT_EQ(r.code, 0) << r.err;
  auto rows = ReadCsv(dir.File("out/patches.csv"));
  ASSERT_EQ(rows.size(), 1u + 6 * 9);  // 3 x 3 patches per face
  double worst = 0.0;
  for (size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 18u);
    for (int c = 15; c < 18; ++c) {
      double b = std::stod(rows[i][c]);
      worst = std::fmax(worst, std::fabs(b - exact) / exact);
    }
  }
  EXPECT_LT(worst, 0.01) << "worst relative error of B against E/(1-rho)";
}

TEST(RenderTest, SameSeedSameBytesOtherSeedOtherBytes) {
  TempDir dir;
  std::vector<std::string> base = {
      "render", "scenes/cornell.obj", "--rays", "256",    "--max-shots", "400", "--width",
      "96",     "--height",           "96",     "--quiet"};
  auto run = [&](const std::string& out, const std::string& seed) {
    auto args = base;
    args.insert(args.end(), {"--out", dir.File(out), "--seed", seed});
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
  };
  run("a", "7");
  run("b", "7");
  run("c", "8");
  for (const char* f : {"image.pfm", "patches.csv", "image.png"}) {
    std::string a = ReadFile(dir.File(std::string("a/") + f));
    ASSERT_FALSE(a.empty()) << f;
    EXPECT_EQ(a, ReadFile(dir.File(std::string("b/") + f))) << f;
    EXPECT_NE(a, ReadFile(dir.File(std::string("c/") + f))) << f;
  }
}

TEST(RenderTest, OutputsHaveTheDocumentedFormat) {
  TempDir dir;
  auto r = RunMain({"render", "scenes/cornell.obj", "--out", dir.path(), "--rays", "128",
                    "--max-shots", "50", "--width", "40", "--height", "30", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  auto patches = ReadCsv(dir.File("patches.csv"));
  ASSERT_GT(patches.size(), 1u);
  std::string header;
  for (size_t i = 0; i < patches[0].size(); ++i) header += (i ? "," : "") + patches[0][i];
  EXPECT_EQ(header, "id,env,cx,cy,cz,nx,ny,nz,area,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b,b_r,b_g,b_b");
  auto conv = ReadCsv(dir.File("convergence.csv"));
  ASSERT_EQ(conv.size(), 51u);
  EXPECT_EQ(conv[0], (std::vector<std::string>{"shot", "seconds", "unshot_fraction"}));
  EXPECT_EQ(conv[50][0], "50");
  // Unshot power never grows from one shot to the next in a closed-ish scene
  // with kd < 1 (a shot removes its power, receivers get at most kd of it).
  for (size_t i = 2; i < conv.size(); ++i)
    EXPECT_LE(std::stod(conv[i][2]), std::stod(conv[i - 1][2]));
  std::string pfm = ReadFile(dir.File("image.pfm"));
  std::string head = "PF\n40 30\n-1.0\n";
  ASSERT_EQ(pfm.substr(0, head.size()), head);
  EXPECT_EQ(pfm.size(), head.size() + 40 * 30 * 3 * 4);
  std::string png = ReadFile(dir.File("image.png"));
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  std::string json = ReadFile(dir.File("run.json"));
  EXPECT_NE(json.find("\"stop_reason\": \"max-shots\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"shots\": 50"), std::string::npos) << json;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))  // no temporary left
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(RenderTest, EnergyBalanceCloses) {
  TempDir dir;
  auto r = RunMain({"render", "scenes/cornell.obj", "--out", dir.path(), "--rays", "256",
                    "--max-shots", "500", "--width", "16", "--height", "16", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::string json = ReadFile(dir.File("run.json"));
  auto triple = [&](const std::string& key) {
    size_t at = json.find("\"" + key + "\": [");
    EXPECT_NE(at, std::string::npos) << key;
    std::stringstream ss(json.substr(json.find('[', at) + 1));
    double v[3];
    char comma;
    ss >> v[0] >> comma >> v[1] >> comma >> v[2];
    return std::vector<double>{v[0], v[1], v[2]};
  };
  auto emitted = triple("emitted"), absorbed = triple("absorbed"), escaped = triple("escaped"),
       unshot = triple("unshot");
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(emitted[c], 0.0);
    EXPECT_GT(escaped[c], 0.0);  // the Cornell box is open at z = 0
    EXPECT_NEAR(absorbed[c] + escaped[c] + unshot[c], emitted[c], 1e-9 * emitted[c]) << c;
  }
}

struct BadCase {
  std::vector<std::string> args;
  const char* message;  // a substring of the expected stderr
};

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
      {{"--round-work", "1e6"}, "--round-work"},
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
  auto r = RunMain({"--help"});
  std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(r.code, 0);
  for (const char* flag :
       {"--out",       "--patch-size",  "--rays",           "--seed",       "--stop-unshot",
        "--max-shots", "--max-seconds", "--width",          "--height",     "--camera",
        "--exposure",  "--quiet",       "--correct-unshot", "--stop-error", "--aa",
        "--strict",    "--emit",        "--round-shots",    "--round-work", "--envs auto"})
    EXPECT_NE(out.find(flag), std::string::npos) << flag;
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
      // 6 packets a shot of 128 + 4R^2/8 bytes (padded to 8) in 512 KiB:
      // 63 at the default R = 50, the cap of 64 at R = 20, 17 at R = 100.
      {{"--envs", "2"}, 63, true, 0},
      {{"--envs", "2", "--mask-res", "20"}, 64, true, 0},
      {{"--envs", "auto:4"}, 63, true, 0},
      {{"--envs", "2", "--round-shots", "8"}, 8, false, 0},
      {{"--envs", "2", "--round-shots", "1"}, 1, false, 0},
      {{"--envs", "2", "--round-work", "5000"}, 64, false, 5000},
      {{"--envs", "2", "--round-work", "0"}, 64, false, 0},
      {{"--envs", "2", "--round-work", "7", "--round-shots", "3"}, 3, false, 7},
      {{"--envs", "1", "--round-work", "9"}, 64, false, 9},
      {{"--envs", "2", "--mask-res", "100"}, 17, true, 0},
  };
  for (const Case& c : cases) {
    std::vector<const char*> argv = {"vismask", "render", "scenes/cornell.obj"};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    Options o;
    Status s = ParseArgs(static_cast<int>(argv.size()), argv.data(), &o);
    ASSERT_TRUE(s.ok()) << s.ToString();
    EXPECT_EQ(o.roundShots, c.shots) << c.args.size();
    EXPECT_EQ(o.roundWorkAuto, c.autoWork) << c.args.size();
    EXPECT_EQ(o.roundWork, c.work) << c.args.size();
  }
  // The automatic size: 16 full shots of rays and centre rays, times the
  // cube root of an environment's grid cells.
  Options o;
  o.maxRays = 1000;
  o.maskRes = 10;  // + 400 centre rays (B)
  EXPECT_EQ(AutoRoundWork(o, 2000.0, 1, 4.0f), uint64_t(16 * 1400 * 20));
  EXPECT_EQ(AutoRoundWork(o, 16000.0, 8, 4.0f), uint64_t(16 * 1400 * 20));
  o.maskMethod = MaskMethod::kR;  // no centre rays
  EXPECT_EQ(AutoRoundWork(o, 2000.0, 1, 4.0f), uint64_t(16 * 1000 * 20));
}

// Issue 20: the default queue lets every environment make a whole round
// (admission shares the free slots among them): environments x round
// shots, within 1 MiB of slots an environment, at least the 64 of before.
TEST(RenderTest, QueueDefaults) {
  struct Case {
    std::vector<const char*> args;
    uint32_t queue;
  };
  const uint64_t packet50 = PacketBytes(MaskShapeOf(MaskMethod::kB, 50, Options().maxRays));
  const Case cases[] = {
      {{"--envs", "1"}, 64},
      {{"--envs", "2"}, 2 * 63},
      {{"--envs", "2", "--round-shots", "1"}, 64},
      {{"--envs", "4x1x4", "--mask-res", "20"}, 16 * 64},
      {{"--envs", "5x5x5"}, static_cast<uint32_t>(kAutoQueueBytes / packet50)},
      {{"--envs", "5x5x5", "--queue", "7"}, 7},
      {{"--envs", "2", "--queue", "64"}, 64},
  };
  for (const Case& c : cases) {
    std::vector<const char*> argv = {"vismask", "render", "scenes/cornell.obj"};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    Options o;
    Status s = ParseArgs(static_cast<int>(argv.size()), argv.data(), &o);
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
    std::vector<const char*> argv = {"vismask", "render", "scenes/cornell.obj"};
    argv.insert(argv.end(), args.begin(), args.end());
    Status s = ParseArgs(static_cast<int>(argv.size()), argv.data(), o);
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

// --- Real scenes as users bring them (issue 16) -------------------------------

// run.json's energy triple `key`.
std::vector<double> Triple(const std::string& json, const std::string& key) {
  size_t at = json.find("\"" + key + "\": [");
  EXPECT_NE(at, std::string::npos) << key;
  std::stringstream ss(json.substr(json.find('[', at) + 1));
  double v[3] = {0, 0, 0};
  char comma;
  ss >> v[0] >> comma >> v[1] >> comma >> v[2];
  return {v[0], v[1], v[2]};
}

// A render's outputs: finite, not black, and the energy ledger closed.
void ExpectSoundRender(const std::string& out, const std::string& what) {
  std::string pfm = ReadFile(out + "/image.pfm");
  std::istringstream head(pfm);
  std::string magic;
  int w = 0, h = 0;
  head >> magic >> w >> h;
  ASSERT_EQ(magic, "PF") << what;
  size_t n = size_t(w) * h * 3, data = pfm.size() - n * 4;
  double sum = 0.0;
  for (size_t i = 0; i < n; ++i) {
    float v;
    std::memcpy(&v, pfm.data() + data + 4 * i, 4);
    ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << what << " pixel value " << v;
    sum += v;
  }
  EXPECT_GT(sum / n, 1e-6) << what << ": black";
  std::string json = ReadFile(out + "/run.json");
  auto emitted = Triple(json, "emitted"), absorbed = Triple(json, "absorbed"),
       escaped = Triple(json, "escaped"), unshot = Triple(json, "unshot");
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(emitted[c], 0.0) << what;
    EXPECT_NEAR(absorbed[c] + escaped[c] + unshot[c], emitted[c], 1e-9 * emitted[c])
        << what << " " << c;
  }
  for (const char* key : {"ambient", "stated_error"}) {
    size_t at = json.find(std::string("\"") + key + "\": ");
    ASSERT_NE(at, std::string::npos) << key;
    EXPECT_EQ(json.substr(at, 40).find("inf"), std::string::npos)
        << what << " " << json.substr(at, 40);
    EXPECT_EQ(json.substr(at, 40).find("nan"), std::string::npos)
        << what << " " << json.substr(at, 40);
  }
}

// The public scenes in scenes/real/ (and one of ours), small and fast, with
// the one warning line each kind of oddity gets. McGuire's boxes open
// towards +z: the default camera looks in from there (issue 16 item 8).
TEST(RenderTest, RealScenesRender) {
  TempDir dir;
  const std::string mcguire = "0,1,3.9,0,1,0,0,1,0,39.3";
  struct Case {
    std::vector<std::string> args;
    std::vector<std::string> warnings;  // stderr, line by line
  };
  const Case cases[] = {
      {{"scenes/real/CornellBox-Original.obj", "--camera", mcguire},
       {"scenes/real/CornellBox-Original.obj:62: warning: 1 non-planar face triangulated (first "
        "here; up to "
        "0.005 off its plane)"}},
      {{"scenes/real/CornellBox-Original.obj"},
       {"scenes/real/CornellBox-Original.obj:62: warning: 1 non-planar"}},
      {{"scenes/real/CornellBox-Sphere.obj"},  // the default camera looks in from +z
       {"scenes/real/CornellBox-Sphere.mtl:21: warning: ignoring MTL key 'v'",
        "scenes/real/CornellBox-Sphere.mtl:15: warning: specular materials rendered as diffuse "
        "with their Kd: "
        "leftSphere (illum 5), rightSphere (illum 7)"}},
      {{"scenes/real/cornell_box.obj", "--emit", "light=ka"},
       {"scenes/real/cornell_box.obj:77: warning: 1 non-planar face triangulated (first here; up "
        "to 0.8 off "
        "its plane)"}},
      {{"scenes/lamp-room.obj", "--emit", "lamp=ka"},
       {"scenes/lamp-room.obj:19: warning: 1 non-planar face triangulated (first here; up to "
        "0.0025 off its "
        "plane)"}},
  };
  int k = 0;
  for (const Case& c : cases) {
    std::string out = dir.File("out" + std::to_string(k++));
    std::vector<std::string> args = {"render"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    args.insert(args.end(), {"--out", out, "--width", "64", "--height", "64", "--emitted-rays",
                             "20000", "--quiet"});
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << c.args[0] << "\n" << r.err;
    std::vector<std::string> lines;
    std::istringstream err(r.err);
    for (std::string line; std::getline(err, line);) lines.push_back(line);
    ASSERT_EQ(lines.size(), c.warnings.size()) << r.err;
    for (size_t i = 0; i < lines.size(); ++i)
      EXPECT_EQ(lines[i].rfind(c.warnings[i], 0), 0u) << lines[i];
    ExpectSoundRender(out, c.args[0]);
    // McGuire's boxes are closed on -z: the default view is chosen from +z.
    if (c.args.size() == 1 && c.args[0].find("CornellBox") != std::string::npos) {
      EXPECT_NE(ReadFile(out + "/run.json").find("\"view\": \"back\""), std::string::npos)
          << c.args[0];
    }
  }
}

// --strict: the refusals before issue 16, word for word.
TEST(RenderTest, StrictRefusesFacesAsBefore) {
  TempDir dir;
  auto r = RunMain(
      {"render", "scenes/real/CornellBox-Original.obj", "--strict", "--out", dir.File("out")});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(
      r.err,
      "scenes/real/CornellBox-Original.obj:62: non-planar face: vertex 1 is 0.005 off the face's "
      "plane (tolerance 0.000284)\n");
  EXPECT_FALSE(FileExists(dir.File("out")));
}

TEST(RenderTest, EmitMarksEmittersOrExitsTwo) {
  TempDir dir;
  std::string out = dir.File("out");
  auto r = RunMain({"render", "scenes/lamp-room.obj", "--out", out, "--quiet"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("no emitter"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--emit"), std::string::npos) << r.err;
  const BadCase cases[] = {
      {{"--emit", "lmap=ka"},
       "vismask: --emit: no material 'lmap' in scenes/lamp-room.obj (its materials: "
       "wall, floor, lamp)"},
      {{"--emit", "lamp"}, "--emit: expected NAME=R,G,B"},
      {{"--emit", "=1,1,1"}, "--emit: expected NAME=R,G,B"},
      {{"--emit", "lamp=1,1"}, "--emit: expected NAME=R,G,B"},
      {{"--emit", "lamp=1,-1,1"}, "--emit: expected NAME=R,G,B"},
      {{"--emit", "lamp=1,nan,1"}, "--emit: expected NAME=R,G,B"},
      {{"--emit", "lamp=kd"}, "--emit: expected NAME=R,G,B"},
  };
  for (const BadCase& c : cases) {
    std::vector<std::string> args = {"render", "scenes/lamp-room.obj", "--out", out};
    args.insert(args.end(), c.args.begin(), c.args.end());
    auto bad = RunMain(args);
    EXPECT_EQ(bad.code, 2) << c.args[1];
    EXPECT_NE(bad.err.find(c.message), std::string::npos) << bad.err;
    EXPECT_FALSE(FileExists(out));
  }
  // NAME=R,G,B; a later --emit for the same name wins.
  auto ok = RunMain({"render", "scenes/lamp-room.obj", "--out", out, "--emit", "lamp=1,1,1",
                     "--emit", "lamp=2,3,4", "--width", "16", "--height", "16", "--emitted-rays",
                     "2000", "--quiet"});
  ASSERT_EQ(ok.code, 0) << ok.err;
  auto rows = ReadCsv(out + "/patches.csv");
  bool lamp = false;
  for (size_t i = 1; i < rows.size(); ++i)
    lamp = lamp || (rows[i][12] == "2" && rows[i][13] == "3" && rows[i][14] == "4");
  EXPECT_TRUE(lamp) << "no patch with ke 2,3,4";
}

// Perfect reflectors (Kd 1 everywhere) in an open box: the solve ends, the
// estimates behind the ambient term come from the measured loss, and
// nothing is infinite. Closed, the same box is refused.
TEST(RenderTest, PerfectReflectorsInAnOpenBox) {
  TempDir dir;
  WriteClosedBox(dir.path(), 1.0, 1.0, 1.0);
  auto closed = RunMain({"render", dir.File("box.obj"), "--out", dir.File("closed"), "--quiet"});
  EXPECT_EQ(closed.code, 2);
  EXPECT_NE(closed.err.find("cannot lose power in the red channel"), std::string::npos)
      << closed.err;
  std::string obj = ReadFile(dir.File("box.obj"));
  obj.erase(obj.find("f 1 2 3 4\n"), 10);  // open at z = 0
  WriteFile(dir.File("box.obj"), obj);
  for (const char* correct : {"off", "on"}) {
    std::string out = dir.File(std::string("open-") + correct);
    auto r = RunMain({"render", dir.File("box.obj"), "--out", out, "--width", "32", "--height",
                      "32", "--emitted-rays", "20000", "--correct-unshot", correct, "--quiet"});
    ASSERT_EQ(r.code, 0) << r.err;
    ExpectSoundRender(out, correct);
  }
}

}  // namespace
}  // namespace vismask
