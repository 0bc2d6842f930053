// Helpers of the per-pixel direct light tests (direct_test.cpp,
// direct_sun_test.cpp): a render looking straight down at a floor, a
// pixel's red channel, the 10%-90% width of an edge across a row.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/output/image_io.h"

namespace vismask {

// Renders dir/s.obj looking straight down at the origin from height 0.5
// (fov 90: the image spans [-0.5, 0.5] of the floor), size x size.
inline PfmImage RenderDown(const test::TempDir& dir, int size, const std::string& flags) {
  std::vector<std::string> args = {
      "render",   dir.File("s.obj"),        "--out",   dir.File("out"),
      "--camera", "0,0.5,0,0,0,0,0,0,1,90", "--width", std::to_string(size),
      "--height", std::to_string(size),     "--quiet"};
  for (const std::string& w : test::Words(flags)) args.push_back(w);
  test::RunResult r = test::RunMain(args);
  EXPECT_EQ(r.code, 0) << r.err;
  PfmImage img;
  EXPECT_TRUE(ReadPfm(dir.File("out/image.pfm"), &img).ok());
  return img;
}

inline float Pixel(const PfmImage& img, int x, int y) {
  return img.pixels[3 * (size_t(y) * img.width + x)];
}

// The 10%-90% width of the rise across row `y` of `img`, in pixels.
inline double EdgeWidth(const PfmImage& img, int y) {
  std::vector<double> row(img.width);
  for (int x = 0; x < img.width; ++x) row[x] = Pixel(img, x, y);
  double lo = *std::min_element(row.begin(), row.end());
  double hi = *std::max_element(row.begin(), row.end());
  auto cross = [&](double level) {
    double t = lo + level * (hi - lo);
    for (int x = 1; x < img.width; ++x)
      if ((row[x - 1] - t) * (row[x] - t) <= 0.0 && row[x - 1] != row[x])
        return x - 1 + (t - row[x - 1]) / (row[x] - row[x - 1]);
    return -1.0;
  };
  return std::fabs(cross(0.9) - cross(0.1));
}

}  // namespace vismask
