// Method B's centre mask by patch (RasterCentres) against the grid's walk
// (WalkCentres), bit for bit; and KeepExits keeping every pixel that a
// direction able to leave through an exit falls in.
#include "vismask/solve/centre_raster.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <random>
#include <vector>

#include "grid_test_util.h"
#include "mask_test_util.h"
#include "vismask/solve/sampling.h"

namespace vismask {
namespace {

using namespace gridtest;

// The centre rays of patch `i` of `s`, as Environment::CastCentres forms them.
CentreRays RaysOf(const Patch& p, const MaskDirections& dirs, float epsilon) {
  PatchSampler sampler = MakePatchSampler(p);
  glm::vec3 centre(0.0f);
  for (uint32_t k = 0; k < p.numCorners; ++k) centre += p.corner[k];
  centre /= static_cast<float>(p.numCorners);
  return CentreRays{centre + epsilon * sampler.frame.n, sampler.frame, &dirs};
}

// Both ways for every shooter of `s` (every `stride`-th), from an all-open
// mask and from one with a random half closed; counts the pixels that differ.
struct Compared {
  uint64_t pixels = 0, closed = 0, differ = 0, byPatchTests = 0;
};

Compared CompareAll(const TestScene& s, uint32_t res, uint32_t stride, float epsilon) {
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  test::MaskTables d(res);
  MaskShape shape{res, 0};
  std::vector<uint64_t> w1(shape.words()), w2(shape.words());
  MaskBits walk(Span<uint64_t>(w1.data(), w1.size()), shape);
  MaskBits raster(Span<uint64_t>(w2.data(), w2.size()), shape);
  std::mt19937 rng(res);
  Compared c;
  Span<const Patch> patches(s.patches.data(), s.patches.size());
  Span<const PatchGeom> geom(s.geom.data(), s.geom.size());
  for (uint32_t i = 0; i < s.patches.size(); i += stride) {
    CentreRays rays = RaysOf(s.patches[i], d.dirs, epsilon);
    for (int half = 0; half < 2; ++half) {
      walk.SetAllOpen();
      if (half)
        for (uint32_t p = 0; p < shape.pixels(); ++p)
          if (rng() & 1) walk.Close(p);
      raster.CopyFrom(walk);
      WalkCentres(b.grid, Skip(i), rays, &walk);
      c.byPatchTests += RasterCentres(patches, geom, Skip(i), rays, &raster);
      for (uint32_t p = 0; p < shape.pixels(); ++p) {
        c.differ += walk.IsOpen(p) != raster.IsOpen(p);
        c.closed += !walk.IsOpen(p);
      }
      c.pixels += shape.pixels();
    }
  }
  return c;
}

TEST(CentreRasterTest, CornellBoxGivesTheWalksBits) {
  TestScene s = CornellScene(8);
  for (uint32_t res : {7u, 20u, 64u}) {
    Compared c = CompareAll(s, res, 3, 1e-6f);
    EXPECT_EQ(c.differ, 0u) << "R = " << res << " over " << c.pixels << " pixels";
    // Not vacuous: most of a closed box's pixels close, and by patch tests.
    EXPECT_GT(c.closed, c.pixels / 2) << "R = " << res;
    EXPECT_GT(c.byPatchTests, 0u) << "R = " << res;
  }
}

TEST(CentreRasterTest, RandomScenesGiveTheWalksBits) {
  // Random quads and triangles of every size and slant, some close to the
  // shooters, in a box and spread thin.
  struct Case {
    int count;
    glm::vec3 lo, hi;
    float sizeLo, sizeHi;
    uint32_t res;
  };
  const Case cases[] = {
      {400, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.4f, 30},
      {200, glm::vec3(-3.0f, 0.0f, 5.0f), glm::vec3(4.0f, 0.3f, 6.0f), 0.05f, 3.0f, 40},
      {300, glm::vec3(100.0f), glm::vec3(101.0f), 0.002f, 0.2f, 25}};
  uint32_t seed = 11;
  for (const Case& k : cases) {
    std::mt19937 rng(seed++);
    TestScene s;
    AddRandomPatches(rng, k.count, k.lo, k.hi, k.sizeLo, k.sizeHi, &s);
    float epsilon = 1e-6f * glm::length(k.hi - k.lo) + 1e-5f * std::fabs(k.hi.x);
    Compared c = CompareAll(s, k.res, 2, epsilon);
    EXPECT_EQ(c.differ, 0u) << "scene " << seed << " over " << c.pixels << " pixels";
    EXPECT_GT(c.closed, c.pixels / 20) << "scene " << seed;
  }
}

// A frame about a random normal.
Frame RandomFrame(std::mt19937& rng) {
  Frame f;
  f.n = UnitVector(rng);
  f.t = glm::normalize(
      glm::cross(f.n, std::fabs(f.n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)));
  f.b = glm::cross(f.n, f.t);
  return f;
}

// The slab exit of a ray from inside `box`: the axis and side (0: lo) of the
// face it leaves by.
void ExitFace(const Bounds& box, const glm::vec3& o, const glm::vec3& d, int* axis, int* side) {
  double best = HUGE_VAL;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0f) continue;
    double t = ((d[a] > 0.0f ? box.hi[a] : box.lo[a]) - double(o[a])) / d[a];
    if (t < best) {
      best = t;
      *axis = a;
      *side = d[a] > 0.0f;
    }
  }
}

TEST(CentreRasterTest, KeepExitsKeepsEveryPixelThatCanLeave) {
  const Bounds box{glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(2.0f, 1.0f, 1.5f)};
  // Exits: +x and -y faces, as an environment with neighbours there has.
  const int exitAxis[2] = {0, 1}, exitSide[2] = {1, 0};
  const Patch exits[2] = {BoxFace(box, exitAxis[0], exitSide[0]),
                          BoxFace(box, exitAxis[1], exitSide[1])};
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  uint64_t kept = 0, closed = 0, checked = 0;
  for (uint32_t res : {5u, 16u, 50u}) {
    test::MaskTables d(res);
    MaskShape shape{res, 0};
    std::vector<uint64_t> words(shape.words());
    MaskBits mask(Span<uint64_t>(words.data(), words.size()), shape);
    for (int shooter = 0; shooter < 60; ++shooter) {
      // A point inside the box and a random frame.
      glm::vec3 o(0.05f + 1.9f * unit(rng), 0.05f + 0.9f * unit(rng), 0.05f + 1.4f * unit(rng));
      Frame f = RandomFrame(rng);
      CentreRays rays{o, f, &d.dirs};
      mask.SetAllOpen();
      closed += KeepExits(Span<const Patch>(exits, 2), rays, &mask);
      kept += mask.CountOpen();
      // Directions anywhere in the hemisphere, not just pixel centres.
      for (int k = 0; k < 4000; ++k) {
        glm::vec3 local = UnitVector(rng);
        local.z = std::fabs(local.z);
        int axis = -1, side = 0;
        ExitFace(box, o, f.ToWorld(local), &axis, &side);
        bool leaves = (axis == 0 && side == 1) || (axis == 1 && side == 0);
        if (!leaves) continue;
        ++checked;
        uint32_t p = MaskPixel(local, res);
        ASSERT_TRUE(mask.IsOpen(p)) << "R " << res << " shooter " << shooter << " pixel " << p;
      }
    }
  }
  EXPECT_GT(checked, 100000u);
  EXPECT_GT(closed, kept / 4) << "KeepExits should close the pixels that face walls";
}

// FlightShare's count by face view: every column it counts as surely
// crossing does cross (by FlightShare's own arithmetic: its recurrence for
// the column angles, the half-open face), and none outside `may` does.
TEST(CentreRasterTest, FaceViewBoundsTheCrossingDirections) {
  const Bounds box{glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(3.0f, 1.0f, 1.5f)};
  Patch face;  // box's x = 1 face
  const glm::vec3 c[4] = {{1, 0, 0}, {1, 1, 0}, {1, 1, 1.5f}, {1, 0, 1.5f}};
  for (int k = 0; k < 4; ++k) face.corner[k] = c[k];
  face.normal = glm::vec3(1, 0, 0);
  face.numCorners = 4;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  uint64_t sure = 0, crossing = 0;
  for (uint32_t res : {8u, 30u}) {
    test::MaskTables d(res);
    const uint32_t cols = 4 * res;
    // FlightShare's column table: a rotation per column from half a column.
    std::vector<double> cs(2 * cols);
    const double step = 6.283185307179586 / cols, rc = std::cos(step), rs = std::sin(step);
    double cc = std::cos(0.5 * step), ss = std::sin(0.5 * step);
    for (uint32_t col = 0; col < cols; ++col) {
      cs[2 * col] = cc;
      cs[2 * col + 1] = ss;
      double t = cc * rc - ss * rs;
      ss = ss * rc + cc * rs;
      cc = t;
    }
    for (int shooter = 0; shooter < 80; ++shooter) {
      glm::vec3 o(unit(rng), -0.5f + 2.0f * unit(rng), -0.5f + 2.5f * unit(rng));  // x < 1
      Frame f = RandomFrame(rng);
      CentreRays rays{o, f, &d.dirs};
      PolygonView view;
      if (!FaceView(face, rays, 1e-7, 1e-7, &view)) continue;
      for (uint32_t row = 0; row < res; ++row) {
        double theta = (row + 0.5) * 1.5707963267948966 / res, st = std::sin(theta),
               ct = std::cos(theta);
        PixelArc may, in;
        bool any = ViewRow(view, rays, row, &may, &in);
        auto within = [cols](const PixelArc& a, uint32_t col) {
          if (a.lo > a.hi) return false;
          if (a.hi - a.lo + 1 >= int(cols)) return true;
          int k = ((int(col) - a.lo) % int(cols) + int(cols)) % int(cols);
          return k <= a.hi - a.lo;
        };
        for (uint32_t col = 0; col < cols; ++col) {
          double lx = st * cs[2 * col], ly = st * cs[2 * col + 1];
          double dx = lx * f.t.x + ly * f.b.x + ct * f.n.x;
          double dy = lx * f.t.y + ly * f.b.y + ct * f.n.y;
          double dz = lx * f.t.z + ly * f.b.z + ct * f.n.z;
          bool crosses = false;
          if (dx != 0.0) {
            double t = (1.0 - o.x) / dx;
            double q1 = o.y + t * dy, q2 = o.z + t * dz;
            crosses = t > 0.0 && q1 >= box.lo.y && q1 < box.hi.y && q2 >= box.lo.z && q2 < box.hi.z;
          }
          crossing += crosses;
          if (!any || !within(may, col)) {
            ASSERT_FALSE(crosses) << "R " << res << " row " << row << " col " << col;
          }
          if (any && within(in, col)) {
            ++sure;
            ASSERT_TRUE(crosses) << "R " << res << " row " << row << " col " << col;
          }
        }
      }
    }
  }
  EXPECT_GT(crossing, 10000u);
  EXPECT_GT(sure, crossing / 2) << "most crossing columns are counted without the test";
}

}  // namespace
}  // namespace vismask
