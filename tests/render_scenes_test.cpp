// Real scenes as users bring them (issue 16): faces mended, --strict,
// --emit, and perfect reflectors, each rendering soundly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "render_test_util.h"
#include "test_util.h"
#include "vismask/app/options.h"

namespace vismask {
namespace {

using namespace test;

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
      // As published, its light's material is in no MTL: grey, and --emit
      // names it (issue 40).
      {{"scenes/real/CornellBox-Glossy.obj", "--emit", "light=17,12,4"},
       {"scenes/real/CornellBox-Glossy.mtl:4: warning: specular materials rendered as diffuse "
        "with their Kd: sphere (Ks), shortBox (Ks)",
        "scenes/real/CornellBox-Glossy.obj:3009: warning: 1 material that no MTL defines, given "
        "the default grey (Kd 0.5; --emit NAME=R,G,B makes one an emitter; first here): "
        "'light'"}},
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
