// Direct light per pixel with several environments: each environment
// gathers every environment's emitters, its shadow rays traced in its own
// grid and, beyond its box, read from the other environments' transit
// masks (foreign_light.h); with --foreign-mask-res 0 each gathers only its
// own (a shadow ray between two points of its box never leaves it), and
// another environment's emitters' light comes with the solve's foreign
// shots. A hard shadow edge whose lamp and occluder lie
// in the environment of the floor it falls on is as sharp as with one
// environment; the image is the same bytes on every transport and rank
// count; the solve (patches.csv) is the same whatever --direct-samples.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "direct_test_util.h"
#include "test_util.h"
#include "vismask/app/options.h"

namespace vismask {
namespace {

// The floor [-10, 10]^2 at y = 0 (Kd 0.5, facing up); a 0.1 square emitter
// (Ke 10, Kd 0) at height 3 above (-5, 0, 0) facing down; a black occluder
// over x < -5 at height 1.5 facing up. Cut at x = 0 into two environments,
// the lamp, the occluder and the penumbra below them (0.1 wide on the
// floor) all lie in the first.
void WriteOffsetShadowScene(const std::string& dir) {
  std::ostringstream obj;
  obj << "mtllib s.mtl\n"
      << "v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\n"
      << "v -5.05 3 -0.05\nv -4.95 3 -0.05\nv -4.95 3 0.05\nv -5.05 3 0.05\n"
      << "v -10 1.5 -10\nv -5 1.5 -10\nv -5 1.5 10\nv -10 1.5 10\n"
      << "usemtl floor\nf 1 4 3 2\nusemtl light\nf 5 6 7 8\nusemtl black\nf 9 12 11 10\n";
  test::WriteFile(dir + "/s.obj", obj.str());
  test::WriteFile(dir + "/s.mtl",
                  "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n"
                  "newmtl black\nKd 0 0 0\n");
}

// Renders the scene from 0.5 above (-5, 0, 0), looking down (1.0 of the
// floor across the image), into dir/NAME; returns the image.
PfmImage RenderOffset(const test::TempDir& dir, const std::string& name, int size,
                      const std::string& flags) {
  return RenderDown(dir, size, flags, -5.0, name);
}

TEST(DirectEnvsTest, ShadowEdgeInTheLampsEnvironmentIsAsSharpAsWithOne) {
  test::TempDir dir;
  WriteOffsetShadowScene(dir.path());
  const int n = 128;
  const double geometric = 0.08 * n;  // the penumbra's 10%-90% part, as in DirectTest
  // At --emission-rays 1 (the default with the gather is an eighth).
  PfmImage direct =
      RenderOffset(dir, "direct", n, "--envs 2x1x1 --direct-samples 32 --emission-rays 1");
  PfmImage solved = RenderOffset(dir, "solved", n, "--envs 2x1x1 --direct-samples 0");
  EXPECT_NE(test::ReadFile(dir.File("direct/run.json")).find("\"direct_samples\": 32"),
            std::string::npos);
  double wDirect = 0.0, wSolved = 0.0;
  for (int y : {20, 64, 100}) {
    wDirect = std::max(wDirect, std::fabs(EdgeWidth(direct, y) - geometric));
    wSolved = std::max(wSolved, std::fabs(EdgeWidth(solved, y) - geometric));
  }
  EXPECT_LT(wDirect, 1.5) << "the 10-90% width, off its geometric " << geometric << " px";
  EXPECT_GT(wSolved, 2.0) << "the solve alone draws it as wide as its patches";
  // The gather changes the image only: the solve is the same bytes.
  EXPECT_EQ(test::ReadFile(dir.File("direct/patches.csv")),
            test::ReadFile(dir.File("solved/patches.csv")));
  // Not given, it is the default with several environments too.
  RenderOffset(dir, "default", 16, "--envs 2x1x1 --max-shots 50");
  EXPECT_NE(test::ReadFile(dir.File("default/run.json"))
                .find("\"direct_samples\": " + std::to_string(kDefaultDirectSamples)),
            std::string::npos);
}

// The floor [-10, 10]^2 at y = 0 (Kd 0.5, facing up) and a 0.2 square
// lamp (Ke 10, Kd 0) at height 1 above (-0.5, 0, 0) facing down: cut at
// x = 0 into two environments, the first (the lamp's) gathers its light per
// pixel, the second shows it solved. Nothing reflects onto the floor.
void WriteLampBesideCutScene(const std::string& dir) {
  test::WriteFile(dir + "/s.obj",
                  "mtllib s.mtl\n"
                  "v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\n"
                  "v -0.6 1 -0.1\nv -0.4 1 -0.1\nv -0.4 1 0.1\nv -0.6 1 0.1\n"
                  "usemtl floor\nf 1 4 3 2\nusemtl light\nf 5 6 7 8\n");
  test::WriteFile(dir + "/s.mtl",
                  "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n");
}

// Column x's mean of the red channel.
double ColumnMean(const PfmImage& img, int x) {
  double sum = 0.0;
  for (int y = 0; y < img.height; ++y) sum += Pixel(img, x, y);
  return sum / img.height;
}

// The lamp beside the cut and a black rectangle at height 0.3 over x in
// [-0.4, -0.02], z in [-0.3, 0.3], facing up: in the lamp's environment, it
// hides the whole lamp from the floor at x in [0, 0.14] (z near 0), which
// lies in the other; the floor beyond x = 0.23 sees all of it.
void WriteForeignShadowScene(const std::string& dir) {
  test::WriteFile(dir + "/s.obj",
                  "mtllib s.mtl\n"
                  "v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\n"
                  "v -0.6 1 -0.1\nv -0.4 1 -0.1\nv -0.4 1 0.1\nv -0.6 1 0.1\n"
                  "v -0.4 0.3 -0.3\nv -0.02 0.3 -0.3\nv -0.02 0.3 0.3\nv -0.4 0.3 0.3\n"
                  "usemtl floor\nf 1 4 3 2\nusemtl light\nf 5 6 7 8\n"
                  "usemtl black\nf 9 12 11 10\n");
  test::WriteFile(dir + "/s.mtl",
                  "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n"
                  "newmtl black\nKd 0 0 0\n");
}

TEST(DirectEnvsTest, EveryEnvironmentGathersEveryLamp) {
  // The lamp beside the cut: the side without it gathers the lamp's light
  // per pixel through the transit masks, as one environment does, and the
  // foreign shots' emission is direct there (not counted twice).
  test::TempDir dir;
  WriteLampBesideCutScene(dir.path());
  const int n = 64;
  PfmImage one = RenderDown(dir, n, "--direct-samples 32", 0.0, "one");
  PfmImage split = RenderDown(dir, n, "--envs 2x1x1 --direct-samples 32", 0.0, "split");
  PfmImage own =
      RenderDown(dir, n, "--envs 2x1x1 --direct-samples 32 --foreign-mask-res 0", 0.0, "own");
  double worst = 0.0, worstOwn = 0.0;
  for (int x = 0; x < n; ++x) {
    worst = std::max(worst, std::fabs(ColumnMean(split, x) / ColumnMean(one, x) - 1.0));
    worstOwn = std::max(worstOwn, std::fabs(ColumnMean(own, x) / ColumnMean(one, x) - 1.0));
  }
  EXPECT_LT(worst, 0.01) << "every column as with one environment";
  EXPECT_GT(worstOwn, 0.01) << "only its own lamp: the other side shows the solve's";
  EXPECT_NE(test::ReadFile(dir.File("split/run.json")).find("\"foreign_mask_res\": 32"),
            std::string::npos);
}

TEST(DirectEnvsTest, AnOccluderInTheLampsEnvironmentShadowsTheOther) {
  // Seen from above (0.2, 0, 0): columns increase towards -x (column c at
  // x = 0.7 - (c + 0.5) / 64), the cut (x = 0) at column 44.8. The floor at
  // x in [0, 0.14] is in the occluder's umbra: black with one environment,
  // and with two, where the occluder lies in the lamp's environment and
  // the floor in the other.
  test::TempDir dir;
  WriteForeignShadowScene(dir.path());
  const int n = 64;
  PfmImage one = RenderDown(dir, n, "--direct-samples 32", 0.2, "one");
  PfmImage split = RenderDown(dir, n, "--envs 2x1x1 --direct-samples 32", 0.2, "split");
  // Lit floor at x in [0.45, 0.7] (columns 0 to 15), umbra at x in
  // [0.02, 0.12] (columns 37 to 42), rows 28 to 35 (z near 0).
  double lit = 0.0, umbraOne = 0.0, umbraSplit = 0.0;
  for (int y = 28; y < 36; ++y) {
    for (int x = 0; x < 16; ++x) lit += Pixel(split, x, y) / 128.0;
    for (int x = 37; x < 43; ++x) {
      umbraOne += Pixel(one, x, y) / 48.0;
      umbraSplit += Pixel(split, x, y) / 48.0;
    }
  }
  ASSERT_GT(lit, 0.0);
  EXPECT_LT(umbraOne, 0.01 * lit) << "the umbra with one environment";
  EXPECT_LT(umbraSplit, 0.01 * lit) << "the umbra across the cut";
}

TEST(DirectEnvsTest, CutVerticesShareTheSolvedWholeBesideAGatheringEnvironment) {
  // Each environment gathering only its own lamp (--foreign-mask-res 0):
  // the display's vertices on the cut take both sides' values: the lamp's
  // environment shows only the indirect part there (its pixels add the
  // direct), the other side the whole. Shared as they are, the lamp's side
  // would get half the other's direct light on top of its own gather and
  // the other side half of it only: a bright and a dark band along the cut.
  test::TempDir dir;
  WriteLampBesideCutScene(dir.path());
  const int n = 64;
  // Looking down at (0, 0, 0): the cut between columns n/2 - 1 (x > 0, the
  // solve's side) and n/2 (x < 0, the lamp's).
  PfmImage one = RenderDown(dir, n, "--direct-samples 32", 0.0, "one");
  PfmImage split =
      RenderDown(dir, n, "--envs 2x1x1 --direct-samples 32 --foreign-mask-res 0", 0.0, "split");
  const double oneSolved = ColumnMean(one, n / 2 - 1), oneLamp = ColumnMean(one, n / 2);
  ASSERT_GT(oneLamp, oneSolved) << "the lamp's side is nearer the lamp";
  // The gathering side beside the cut: its gather, and no indirect light
  // (there is none), as with one environment.
  EXPECT_NEAR(ColumnMean(split, n / 2) / oneLamp, 1.0, 0.02);
  // The solve's side: the lamp's light at patch scale, not half of it.
  EXPECT_NEAR(ColumnMean(split, n / 2 - 1) / oneSolved, 1.0, 0.15);
  // Shared the same way on two ranks over pipes.
  RenderDown(dir, n, "--envs 2x1x1 --direct-samples 32 --foreign-mask-res 0 --ranks 2", 0.0,
             "ranks");
  EXPECT_EQ(test::ReadFile(dir.File("split/image.pfm")),
            test::ReadFile(dir.File("ranks/image.pfm")));
}

TEST(DirectEnvsTest, SameBytesOnEveryTransportAndRankCount) {
  // The Cornell box in two environments, its lamp cut between them (each
  // gathers both halves, the other's through its transit masks), on the
  // loop transport and on two ranks over pipes.
  test::TempDir dir;
  std::vector<std::string> images;
  for (const char* ranks : {"", "--ranks 2"}) {
    std::string out = dir.File(*ranks ? "pipes" : "loop");
    std::vector<std::string> args = {"render",
                                     "scenes/cornell.obj",
                                     "--out",
                                     out,
                                     "--envs",
                                     "2",
                                     "--direct-samples",
                                     "32",
                                     "--width",
                                     "64",
                                     "--height",
                                     "64",
                                     "--emitted-rays",
                                     "200000",
                                     "--quiet"};
    for (const std::string& w : test::Words(ranks)) args.push_back(w);
    test::RunResult r = test::RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(test::ReadFile(out + "/run.json").find("\"direct_samples\": 32"), std::string::npos);
    images.push_back(test::ReadFile(out + "/image.pfm"));
  }
  ASSERT_FALSE(images[0].empty());
  EXPECT_EQ(images[0], images[1]);
}

}  // namespace
}  // namespace vismask
