// The emitter check: a light facing a surface just beyond it is warned of.
#include "vismask/scene/emitter_check.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "test_util.h"
#include "twosided_test_util.h"
#include "vismask/scene/scene.h"

namespace vismask {
namespace {

using test::RunMain;
using test::TempDir;
using twosided::kMtl;
using twosided::LoadText;

// The furnished-room case: a ceiling light wound to face the ceiling it
// hangs under sends nearly all its power into it.
const char kLightUnderCeiling[] =
    "usemtl white\n"
    "v 0 0 0\nv 100 0 0\nv 100 0 100\nv 0 0 100\nf 1 4 3 2\n"  // floor, facing up
    "v 0 5 0\nv 0 5 100\nv 100 5 100\nv 100 5 0\nf 5 8 7 6\n"  // ceiling, facing down
    "usemtl light\n"
    "v 49 4.95 49\nv 51 4.95 49\nv 51 4.95 51\nv 49 4.95 51\n"
    "f 9 12 11 10\n";  // line 18 (after mtllib): facing up

TEST(EmitterCheckTest, WarnsForALightFacingTheCeilingAbove) {
  Scene scene = LoadText(kLightUnderCeiling, "room.obj");
  std::vector<std::string> w = EmitterWarnings(scene);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("room.obj:18: warning: emitter 'light' sends ", 0), 0u) << w[0];
  EXPECT_NE(w[0].find("into a surface"), std::string::npos) << w[0];
  std::vector<EmitterEstimate> e = EstimateEmitters(scene);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_GT(e[0].nearShare, 0.95);
  EXPECT_GE(e[0].nearDistance, 0.05);  // the gap, along cosine-weighted rays
  EXPECT_LE(e[0].nearDistance, 0.2);
  // Wound the right way (facing down at the floor), it is silent.
  std::string fixed = kLightUnderCeiling;
  fixed.replace(fixed.find("f 9 12 11 10"), 12, "f 9 10 11 12");
  EXPECT_TRUE(EmitterWarnings(LoadText(fixed, "room.obj")).empty());
  // Without the ceiling, facing up, it lights nothing while its back faces
  // the floor.
  std::string open = kLightUnderCeiling;
  open.replace(open.find("f 5 8 7 6\n"), 10, "");
  std::vector<std::string> w2 = EmitterWarnings(LoadText(open, "room.obj"));
  ASSERT_EQ(w2.size(), 1u);
  EXPECT_NE(w2[0].find("straight out of the scene"), std::string::npos) << w2[0];
}

// The render prints it (one line, at init) and carries on.
TEST(EmitterCheckTest, RenderWarnsOnceOnStderr) {
  TempDir dir;
  test::WriteFile(dir.File("room.obj"), std::string("mtllib room.mtl\n") + kLightUnderCeiling);
  test::WriteFile(dir.File("room.mtl"), kMtl);
  auto r = RunMain({"render", dir.File("room.obj"), "--out", dir.File("out"), "--width", "16",
                    "--height", "16", "--max-shots", "5", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.rfind(dir.File("room.obj") + ":18: warning: emitter 'light'", 0), 0u) << r.err;
  // One line for the emitter; the image it leaves unlit gets the black-image
  // warning (the camera's, issue 16 item 8) as the only other line.
  size_t eol = r.err.find('\n');
  ASSERT_NE(eol, std::string::npos);
  EXPECT_EQ(r.err.find("emitter"), r.err.rfind("emitter 'light'")) << r.err;
  EXPECT_EQ(r.err.substr(eol + 1).rfind("vismask: warning: the image is black", 0), 0u) << r.err;
  EXPECT_EQ(r.err.find('\n', eol + 1), r.err.size() - 1) << "two lines: " << r.err;
}

// The scenes that ship stay silent: the Cornell box's light hangs just below
// the ceiling facing down; the stiff boxes are closed; the extreme scenes
// are open on purpose (their lights' backs face nothing either).
TEST(EmitterCheckTest, ShippedScenesAreSilent) {
  std::vector<std::string> scenes = {"scenes/cornell.obj", "scenes/miswound.obj"};
  for (const char* rho : {"0.5", "0.9", "0.99", "0.999"})
    scenes.push_back(std::string("scenes/stiff/box-rho") + rho + ".obj");
  for (const char* name :
       {"grazing", "one-patch", "sliver", "cornell-on-plane", "cornell-ke1e-6", "cornell-ke1e30",
        "cornell-moved1e6", "cornell-scale1e-3", "cornell-scale1e6"})
    scenes.push_back(std::string("scenes/extreme/") + name + ".obj");
  for (const std::string& path : scenes) {
    Scene scene;
    Status s = LoadScene(path, &scene);
    ASSERT_TRUE(s.ok()) << s.ToString();
    std::vector<std::string> w = EmitterWarnings(scene);
    EXPECT_TRUE(w.empty()) << path << ": " << (w.empty() ? "" : w[0]);
    EXPECT_FALSE(EstimateEmitters(scene).empty()) << path;
  }
}

}  // namespace
}  // namespace vismask

// The emitter check's rays a polygon: all of them up to the budget's share,
// then fewer, never below the floor, so that a scene of very many emitting
// faces is checked in bounded time before init can refuse it.
TEST(EmitterCheckTest, RaysPerPolygonShrinkWithinTheBudget) {
  EXPECT_EQ(vismask::EmitterCheckRays(0), vismask::kEmitterCheckRays);
  EXPECT_EQ(vismask::EmitterCheckRays(1), vismask::kEmitterCheckRays);
  EXPECT_EQ(vismask::EmitterCheckRays(vismask::kEmitterCheckRayBudget / vismask::kEmitterCheckRays),
            vismask::kEmitterCheckRays);
  EXPECT_EQ(
      vismask::EmitterCheckRays(2 * vismask::kEmitterCheckRayBudget / vismask::kEmitterCheckRays),
      vismask::kEmitterCheckRays / 2);
  EXPECT_EQ(vismask::EmitterCheckRays(300000), vismask::kEmitterCheckMinRays);
  for (uint64_t n : {1ull, 100ull, 5000ull, 40000ull, 300000ull})
    EXPECT_LE(
        uint64_t(vismask::EmitterCheckRays(n)) * n,
        std::max<uint64_t>(vismask::kEmitterCheckRayBudget, vismask::kEmitterCheckMinRays * n));
}
