// The sun (--sun) in the per-pixel direct light (direct.h): its unoccluded
// irradiance and shadow samples give E cos(theta); a plane under it matches
// that per pixel; a shadow edge is as sharp as the sun's disc allows, which
// the solve alone is not; the image's mean stays the solve-only image's
// (the sun's first bounce counted once) and patches.csv stays its bytes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "direct_test_util.h"
#include "grid_test_util.h"
#include "test_util.h"
#include "vismask/display/direct.h"
#include "vismask/output/image_io.h"

namespace vismask {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A sun at `elevation` degrees above the horizon (towards +z), irradiance
// (2, 1, 0.5), the default disc.
OutsideLight SunAt(double elevation) {
  OutsideLight light;
  const double t = elevation * kPi / 180.0;
  std::ostringstream text;
  text << "0," << std::sin(t) << "," << std::cos(t) << ",2,1,0.5";
  EXPECT_TRUE(ParseSun(text.str(), &light));
  return light;
}

TEST(DirectSunTest, UnoccludedAndSamplesGiveItsIrradianceTimesTheCosine) {
  // A small roof [0, 1] x [0, 1] at y = 1 facing down; the points under it
  // see the sun through it or not at all.
  gridtest::TestScene s;
  gridtest::AddSubdividedQuad(1, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f, -1, 1, &s);
  LitTestScene lit(s);
  const gridtest::BuiltGrid& b = lit.b;
  DirectLight& light = lit.light;
  EXPECT_TRUE(light.empty()) << "no emitter and no sun";
  light.SetSun(SunAt(30.0));
  ASSERT_FALSE(light.empty());
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  const glm::vec3 e = light.Unoccluded(glm::vec3(5.0f, 0.0f, 5.0f), up);
  EXPECT_NEAR(e.x, 2.0 * 0.5, 1e-6);
  EXPECT_NEAR(e.z, 0.5 * 0.5, 1e-6);
  EXPECT_EQ(light.Unoccluded(glm::vec3(5.0f, 0.0f, 5.0f), -up).x, 0.0f) << "below the horizon";
  // Out in the open: every ray leaves, the weights average E cos(theta)
  // (the disc's 0.53 degrees change the cosine by less than 1e-4). Under
  // the roof's middle, the sun 30 degrees up, none does.
  const uint32_t n = 1024;
  glm::dvec3 sum(0.0);
  uint32_t open = 0, under = 0;
  for (uint32_t k = 0; k < n; ++k) {
    glm::vec3 w, w2;
    open += light.Sample(b.grid, kNoPatch, kNoPatch, glm::vec3(5.0f, 0.0f, 5.0f), up,
                         DirectLightSample(3, k), {}, 1e-4f, nullptr, &w, 1.0f);
    sum += glm::dvec3(w);
    under += light.Sample(b.grid, kNoPatch, kNoPatch, glm::vec3(0.5f, 0.9f, 0.3f), up,
                          DirectLightSample(3, k), {}, 1e-4f, nullptr, &w2, 1.0f);
  }
  EXPECT_EQ(open, n);
  EXPECT_EQ(under, 0u);
  EXPECT_NEAR(sum.x / n, 2.0 * 0.5, 1e-3);
  EXPECT_NEAR(sum.y / n, 1.0 * 0.5, 1e-3);
}

// A floor [-h, h]^2 at y = 0 (Kd 0.5, facing up; h = 10 unless given) and,
// with `occluder` > 0, a black roof over x < 0 at that height facing up
// (the floor sees its back, which absorbs). Nothing emits.
void WriteSunScene(const std::string& dir, double occluder, double h = 10.0) {
  std::ostringstream obj;
  obj << "mtllib s.mtl\nv " << -h << " 0 " << -h << "\nv " << h << " 0 " << -h << "\nv " << h
      << " 0 " << h << "\nv " << -h << " 0 " << h << "\n"
      << "v " << -h << " " << occluder << " " << -h << "\nv 0 " << occluder << " " << -h << "\nv 0 "
      << occluder << " " << h << "\nv " << -h << " " << occluder << " " << h
      << "\nusemtl floor\nf 1 4 3 2\n";
  if (occluder > 0) obj << "usemtl black\nf 5 8 7 6\n";
  test::WriteFile(dir + "/s.obj", obj.str());
  test::WriteFile(dir + "/s.mtl", "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl black\nKd 0 0 0\n");
}

TEST(DirectSunTest, PlaneUnderTheSunMatchesItsIrradianceTimesTheCosine) {
  test::TempDir dir;
  WriteSunScene(dir.path(), 0.0);
  const int n = 32;
  for (double elevation : {30.0, 70.0}) {
    const double t = elevation * kPi / 180.0;
    std::ostringstream sun;
    sun << "--sun 0," << std::sin(t) << "," << std::cos(t) << ",2,1,0.5";
    PfmImage img = RenderDown(dir, n, "--direct-samples 8 " + sun.str());
    ASSERT_EQ(img.width, n);
    // Every pixel: kd E sin(elevation) / pi (red: E = 2), the light
    // reflected leaves the scene.
    const double want = 0.5 * 2.0 * std::sin(t) / kPi;
    double worst = 0.0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) worst = std::max(worst, std::fabs(Pixel(img, i, j) / want - 1.0));
    EXPECT_LT(worst, 0.01) << elevation << " degrees";
  }
}

// The 10%-90% width of the shadow of a straight edge under a uniform disc
// of diameter 1: the share of the disc beyond a chord at distance d from
// its centre (radius 1/2) goes from 0.1 to 0.9 over 2 d10, where
// (acos(x) - x sqrt(1 - x^2)) / pi = 0.1 at x = 2 d10.
double DiscEdgeWidth() {
  double lo = 0.0, hi = 1.0;
  for (int k = 0; k < 60; ++k) {
    const double x = 0.5 * (lo + hi);
    ((std::acos(x) - x * std::sqrt(1.0 - x * x)) / kPi > 0.1 ? lo : hi) = x;
  }
  return lo;  // 2 d10 for a disc of diameter 1
}

TEST(DirectSunTest, ShadowEdgeIsAsSharpAsTheSunsDisc) {
  test::TempDir dir;
  // The sun overhead, 4 degrees across; the roof's edge (x = 0) at 1.5:
  // the penumbra on the floor is the disc seen from the edge, 1.5 * 2 tan 2
  // degrees wide, its 10%-90% part DiscEdgeWidth() of that; 128 pixels
  // over the 1.0 of floor seen.
  WriteSunScene(dir.path(), 1.5);
  const int n = 128;
  const double penumbra = 1.5 * 2.0 * std::tan(2.0 * kPi / 180.0);
  const double geometric = DiscEdgeWidth() * penumbra * n;
  ASSERT_GT(geometric, 5.0);
  PfmImage direct = RenderDown(dir, n, "--sun 0,1,0,3,3,3,4 --direct-samples 32");
  PfmImage solved = RenderDown(dir, n, "--sun 0,1,0,3,3,3,4 --direct-samples 0");
  double wDirect = 0.0, wSolved = 0.0;
  for (int y : {20, 64, 100}) {
    wDirect = std::max(wDirect, std::fabs(EdgeWidth(direct, y) - geometric));
    wSolved = std::max(wSolved, std::fabs(EdgeWidth(solved, y) - geometric));
  }
  EXPECT_LT(wDirect, 1.5) << "the 10-90% width, off its geometric " << geometric << " px";
  // The solve alone draws it at its elements' scale, smeared where they
  // straddle the edge (the test tells them apart).
  EXPECT_GT(wSolved, geometric);
}

// Where row y crosses halfway between its least and greatest value (in
// pixels from the left), or -1.
double EdgeAt(const PfmImage& img, int y) {
  double lo = 1e30, hi = -1e30;
  for (int x = 0; x < img.width; ++x) {
    const double v = Pixel(img, x, y);
    lo = std::min(lo, v), hi = std::max(hi, v);
  }
  const double t = 0.5 * (lo + hi);
  for (int x = 1; x < img.width; ++x) {
    const double a = Pixel(img, x - 1, y), b = Pixel(img, x, y);
    if ((a - t) * (b - t) <= 0.0 && a != b) return x - 1 + (t - a) / (b - a);
  }
  return -1.0;
}

TEST(DirectSunTest, ShadowCastAcrossAnEnvironmentPlaneIsWhereAndAsSharpAsInOne) {
  // The roof over x < 0 at 1.5 on a floor 2 across, the sun 4 degrees
  // across and tilted towards -x: the roof's edge falls on the floor near
  // x = 0.3. Cut at x = 0 (--envs 2x1x1), the roof lies in the first
  // environment and the edge in the second, whose shadow rays leave its box
  // below the roof: the first's sun map must shade them (without it the
  // edge would be at x = 0, 38 pixels off). Seen from above x = 0.3, 128
  // pixels a unit. The map's texel is what the edge may move by: here the
  // scene's diagonal (3.2) over 256, 1.6 pixels, no finer than the maps'
  // (16 x 32 texels across each environment's box).
  test::TempDir dir;
  WriteSunScene(dir.path(), 1.5, 1.0);
  const int n = 128;
  const double texel = std::sqrt(2.0 * 2.0 + 1.5 * 1.5 + 2.0 * 2.0) / 256.0 * n;
  const std::string sun = "--sun -0.2,1,0,3,3,3,4 --direct-samples 32";
  PfmImage one = RenderDown(dir, n, sun, 0.3, "one");
  PfmImage two = RenderDown(dir, n, sun + " --envs 2x1x1", 0.3, "two");
  for (int y : {20, 64, 100}) {
    const double at = EdgeAt(one, y);
    ASSERT_GT(at, 0.25 * n) << "the edge in view";
    ASSERT_LT(at, 0.75 * n);
    EXPECT_NEAR(EdgeAt(two, y), at, texel) << "row " << y;
    EXPECT_NEAR(EdgeWidth(two, y), EdgeWidth(one, y), 1.5) << "row " << y;
  }
}

double Mean(const PfmImage& img) {
  double s = 0.0;
  for (float v : img.pixels) s += v;
  return s / static_cast<double>(img.pixels.size());
}

TEST(DirectSunTest, ImageMeanIsTheSolveAlonesAndPatchesKeepTheirBytes) {
  // The sun through the skylight: with per-pixel direct light its first
  // bounce is gathered per pixel and kept out of the solve's indirect part,
  // the later bounces stay the solve's. Counted twice or lost, the mean
  // would move by the first bounce's share, most of the image's light.
  // With --emission-rays 1 the solves trace the same rays: the same bytes.
  test::TempDir dir;
  PfmImage img[3];
  std::string csv[3];
  double rays[3];
  for (int k = 0; k < 3; ++k) {
    const std::string out = dir.File("out" + std::to_string(k));
    std::vector<std::string> args = {"render",
                                     "scenes/skylight.obj",
                                     "--out",
                                     out,
                                     "--camera",
                                     "0.4,2.2,0.4,3,0.3,3,0,1,0,70",
                                     "--width",
                                     "48",
                                     "--height",
                                     "48",
                                     "--sun",
                                     "1,4,0.5,3,3,3",
                                     "--quiet",
                                     "--emission-rays",
                                     k == 2 ? "0.25" : "1",
                                     "--direct-samples",
                                     k == 0 ? "0" : "32"};
    test::RunResult r = test::RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    ASSERT_TRUE(ReadPfm(out + "/image.pfm", &img[k]).ok());
    csv[k] = test::ReadFile(out + "/patches.csv");
    rays[k] = test::JsonNumber(test::ReadFile(out + "/run.json"), "rays");
  }
  EXPECT_NEAR(Mean(img[1]) / Mean(img[0]), 1.0, 0.03);
  // --emission-rays 0.25: the sun's shots, gathered per pixel, trace a
  // quarter of their worth; the image's light stays.
  EXPECT_LT(rays[2], 0.8 * rays[1]);
  EXPECT_NEAR(Mean(img[2]) / Mean(img[0]), 1.0, 0.03);
  EXPECT_FALSE(csv[0].empty());
  EXPECT_EQ(csv[0], csv[1]) << "the solve is the same whatever the display";
}

}  // namespace
}  // namespace vismask
