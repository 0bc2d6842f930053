// The solve's light where a patch is partly hidden (--origins) and the
// display's smoothing of the indirect part (--indirect-filter), end to end.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/output/image_io.h"

namespace vismask {
namespace {

using test::Join;
using test::JsonNumber;
using test::RunMain;
using test::TempDir;

// A floor whose one patch spans the wall of a closed box (facing in) that
// stands on half of it, and a lamp over the other half. Light reaches the
// floor outside the box only; rays leaving from anywhere on the patch carry
// some of it through the wall into the box (a light leak), rays leaving from
// where the light landed (--origins power, the default) do not.
TEST(OriginsTest, RaysLeaveFromWhereTheLightLandedSoNoneLeaksIntoAClosedBox) {
  TempDir dir;
  test::WriteFile(dir.File("half.mtl"),
                  "newmtl white\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n");
  test::WriteFile(dir.File("half.obj"), R"(mtllib half.mtl
v 0 0 0
v 100 0 0
v 100 0 100
v 0 0 100
usemtl white
f 1 4 3 2
v 0 0 0
v 50 0 0
v 50 0 100
v 0 0 100
v 0 50 0
v 50 50 0
v 50 50 100
v 0 50 100
f 9 10 11 12
f 6 7 11 10
f 5 6 10 9
f 7 8 12 11
f 8 5 9 12
v 60 80 30
v 90 80 30
v 90 80 70
v 60 80 70
usemtl light
f 13 14 15 16
)");
  const std::vector<std::string> base = {
      "render",  dir.File("half.obj"), "--patch-size", "200",     "--width",
      "16",      "--height",           "16",           "--quiet", "--emitted-rays",
      "2000000", "--stop-unshot",      "1e-4"};
  for (const char* o : {"power", "uniform"}) {
    auto r = RunMain(Join(base, {"--origins", o, "--out", dir.File(o)}));
    ASSERT_EQ(r.code, 0) << r.err;
  }
  // The box's walls and roof: every patch but the floor (y = 0) and the lamp.
  auto inside = [&](const char* o) {
    auto rows = test::ReadCsv(dir.File(std::string(o) + "/patches.csv"));
    double sum = 0.0;
    for (size_t i = 1; i < rows.size(); ++i) {
      double y = std::stod(rows[i][3]), ke = std::stod(rows[i][12]);
      if (y > 0.0 && ke == 0.0) sum += std::stod(rows[i][15]);
    }
    return sum;
  };
  double power = inside("power"), uniform = inside("uniform");
  EXPECT_GT(uniform, 0.01) << "uniform origins should leak light into the box";
  EXPECT_LT(power, 1e-3 * uniform) << "light leaked into the box from the floor's hidden half";
}

// The mean over pixels [x0, x1) x [y0, y1) of channels summed, and the mean
// absolute second difference along rows there (a patch-sized blotch shows
// in it; a smooth gradient hardly does).
void Region(const PfmImage& img, int x0, int x1, int y0, int y1, double* mean, double* rough) {
  auto at = [&](int x, int y) {
    const float* p = &img.pixels[3 * (size_t(y) * img.width + x)];
    return double(p[0]) + p[1] + p[2];
  };
  double sum = 0.0, r = 0.0;
  int n = 0, m = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      sum += at(x, y), ++n;
      if (x > x0 && x + 1 < x1)
        r += std::fabs(at(x - 4 < x0 ? x0 : x - 4, y) - 2.0 * at(x, y) +
                       at(x + 4 >= x1 ? x1 - 1 : x + 4, y)),
            ++m;
    }
  *mean = sum / n;
  *rough = r / m / *mean;
}

// Early in a solve (few rays a patch) the indirect part's patch-sized noise
// is smoothed on the display lattice (not given: steps from the hits a
// patch received); the back wall is smoother and as bright. Converged, the
// same rule smooths nothing.
TEST(IndirectFilterTest, EarlyImagesAreSmoothedAndConvergedOnesAreNot) {
  TempDir dir;
  const std::vector<std::string> base = {"render",   "scenes/cornell.obj",
                                         "--camera", "278,273,-800,278,273,0,0,1,0,39.3076",
                                         "--width",  "128",
                                         "--height", "128",
                                         "--quiet",  "--direct-samples",
                                         "4",        "--emitted-rays",
                                         "30000"};
  for (const char* k : {"auto", "0"}) {
    std::vector<std::string> args = Join(base, {"--out", dir.File(k)});
    if (std::string(k) != "auto") args = Join(args, {"--indirect-filter", k});
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  std::string json = test::ReadFile(dir.File("auto/run.json"));
  EXPECT_GT(JsonNumber(json, "indirect_filter_steps"), 0.0);
  PfmImage on, off;
  ASSERT_TRUE(ReadPfm(dir.File("auto/image.pfm"), &on).ok());
  ASSERT_TRUE(ReadPfm(dir.File("0/image.pfm"), &off).ok());
  // The back wall above the blocks, below the ceiling's edge.
  double meanOn, roughOn, meanOff, roughOff;
  Region(on, 40, 88, 30, 50, &meanOn, &roughOn);
  Region(off, 40, 88, 30, 50, &meanOff, &roughOff);
  EXPECT_LT(roughOn, 0.7 * roughOff) << "smoothed " << roughOn << ", not " << roughOff;
  EXPECT_NEAR(meanOn / meanOff, 1.0, 0.02);
  // Converged (large patches, many rays each): no steps, the image as
  // --indirect-filter 0 draws it.
  for (const char* k : {"conv", "conv0"}) {
    std::vector<std::string> args = {"render",         "scenes/cornell.obj",
                                     "--width",        "32",
                                     "--height",       "32",
                                     "--patch-size",   "60",
                                     "--emitted-rays", "1000000",
                                     "--quiet",        "--out",
                                     dir.File(k)};
    if (std::string(k) == "conv0") args = Join(args, {"--indirect-filter", "0"});
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  EXPECT_EQ(JsonNumber(test::ReadFile(dir.File("conv/run.json")), "indirect_filter_steps"), 0.0);
  EXPECT_EQ(test::ReadFile(dir.File("conv/image.pfm")),
            test::ReadFile(dir.File("conv0/image.pfm")));
}

}  // namespace
}  // namespace vismask
