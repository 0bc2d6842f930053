// Helpers of the per-pixel direct light tests (direct_test.cpp,
// direct_sun_test.cpp): a test scene's grid and emitter lists, a render
// looking straight down at a floor, a pixel's red channel, the 10%-90%
// width of an edge across a row.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "grid_test_util.h"
#include "test_util.h"
#include "vismask/core/arena.h"
#include "vismask/display/direct.h"
#include "vismask/output/image_io.h"

namespace vismask {

// A test scene's grid (density 1) and its DirectLight, laid out in an arena
// of their own and built; `s` must outlive it.
struct LitTestScene {
  explicit LitTestScene(const gridtest::TestScene& s) {
    gridtest::BuildGrid(s, 1.0f, &b);
    Span<const Patch> patches(s.patches.data(), s.patches.size());
    light.Layout(arena, DirectLight::Count(patches));
    light.Build(patches);
  }
  gridtest::BuiltGrid b;
  Arena arena{64 * 1024};
  DirectLight light;
};

// Renders dir/s.obj looking straight down from height 0.5 above (x, 0, 0)
// (fov 90: the image spans 1.0 of the floor), size x size, into dir/NAME.
inline PfmImage RenderDown(const test::TempDir& dir, int size, const std::string& flags,
                           double x = 0.0, const std::string& name = "out") {
  const std::string cx = std::to_string(x);
  std::vector<std::string> args = {"render",   dir.File("s.obj"),
                                   "--out",    dir.File(name),
                                   "--camera", cx + ",0.5,0," + cx + ",0,0,0,0,1,90",
                                   "--width",  std::to_string(size),
                                   "--height", std::to_string(size),
                                   "--quiet"};
  for (const std::string& w : test::Words(flags)) args.push_back(w);
  test::RunResult r = test::RunMain(args);
  EXPECT_EQ(r.code, 0) << r.err;
  PfmImage img;
  EXPECT_TRUE(ReadPfm(dir.File(name + "/image.pfm"), &img).ok());
  return img;
}

// A lamp of WriteLampsScene: a square of side `side` centred at (x, y, z),
// facing down, of exitance `ke` (every channel).
struct Lamp {
  double x, y, z, side, ke;
};

// The floor [-10, 10]^2 at y = 0 (Kd 0.5, facing up), a black wall in the
// plane x = 1 (y 0 to 3, z -10 to 10) and `lamps` (Kd 0), written to
// dir/s.obj and dir/s.mtl: the floor at x < 1 sees the lamps on its side
// and none of those beyond the wall, and nothing reflects onto it.
inline void WriteLampsScene(const std::string& dir, const std::vector<Lamp>& lamps) {
  std::string obj =
      "mtllib s.mtl\n"
      "v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\n"
      "v 1 0 -10\nv 1 0 10\nv 1 3 10\nv 1 3 -10\n"
      "usemtl floor\nf 1 4 3 2\nusemtl black\nf 5 6 7 8\n";
  std::string mtl = "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl black\nKd 0 0 0\n";
  int v = 9;
  for (size_t i = 0; i < lamps.size(); ++i) {
    const Lamp& l = lamps[i];
    const double h = l.side / 2;
    for (const auto& c : {std::pair<double, double>{-h, -h}, {h, -h}, {h, h}, {-h, h}})
      obj += "v " + std::to_string(l.x + c.first) + " " + std::to_string(l.y) + " " +
             std::to_string(l.z + c.second) + "\n";
    const std::string name = "lamp" + std::to_string(i);
    obj += "usemtl " + name + "\nf " + std::to_string(v) + " " + std::to_string(v + 1) + " " +
           std::to_string(v + 2) + " " + std::to_string(v + 3) + "\n";
    const std::string ke = std::to_string(l.ke);
    mtl += "newmtl " + name + "\nKd 0 0 0\nKe " + ke + " " + ke + " " + ke + "\n";
    v += 4;
  }
  test::WriteFile(dir + "/s.obj", obj);
  test::WriteFile(dir + "/s.mtl", mtl);
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
