// The grid's sub-grids (Grid::Nest): a dense top cell's own grid gives
// brute force's hit on every ray, bit for bit the uniform grid's, is laid
// out exactly as planned, and saves the walk patch tests where patches
// cluster; a scene without dense cells gets none.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>
#include <random>
#include <sstream>
#include <vector>

#include "grid_test_util.h"
#include "test_util.h"
#include "vismask/accel/grid.h"
#include "vismask/app/options.h"
#include "vismask/solve/env_options.h"

namespace vismask {
namespace {

using namespace gridtest;

// A room with a finely split floor and small, dense clusters of patches
// (props on a bare floor): the top cells around the clusters hold hundreds
// of references, the rest a few.
TestScene ClusterScene(uint32_t seed) {
  TestScene s;
  AddSubdividedQuad(1, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, +1, 10, &s);  // floor
  AddSubdividedQuad(1, 0.6f, 0.0f, 1.0f, 0.0f, 1.0f, -1, 4, &s);   // ceiling
  AddAxisQuad(0, 0.0f, 0.0f, 0.6f, 0.0f, 1.0f, +1, &s);
  AddAxisQuad(0, 1.0f, 0.0f, 0.6f, 0.0f, 1.0f, -1, &s);
  std::mt19937 rng(seed);
  const glm::vec3 centres[] = {{0.2f, 0.05f, 0.3f}, {0.7f, 0.08f, 0.6f}, {0.45f, 0.3f, 0.8f}};
  for (const glm::vec3& c : centres)
    AddRandomPatches(rng, 400, c - 0.04f, c + 0.04f, 0.002f, 0.03f, &s);
  AddBlock(glm::vec3(0.1f, 0.0f, 0.7f), glm::vec3(0.16f, 0.2f, 0.76f), 3, &s);  // a post
  return s;
}

// Rays from points on the sub-grids' cell planes (where the two levels'
// planes meet), any direction, and rays along them.
void CheckSubPlaneRays(const BuiltGrid& b, uint32_t seed, int count, Checker* ck) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  Span<const SubGrid> subs = b.grid.subGrids();
  ASSERT_GT(subs.size(), 0u);
  for (int i = 0; i < count; ++i) {
    const SubGrid& g = subs[rng() % subs.size()];
    glm::vec3 o;
    for (int a = 0; a < 3; ++a) {
      float k = static_cast<float>(rng() % (g.res[a] + 1));
      o[a] = i % 2 ? g.lo[a] + k * g.cellSize[a] : g.lo[a] + u01(rng) * g.res[a] * g.cellSize[a];
    }
    glm::vec3 d = UnitVector(rng);
    if (i % 3 == 0) d[rng() % 3] = 0.0f;
    if (d == glm::vec3(0.0f)) d.x = 1.0f;
    ck->CheckWithSkips(Ray{o, d, 0.0f, kInf}, "sub-plane");
    ck->CheckWithSkips(Ray{o, d, 0.0f, u01(rng) * 0.2f}, "sub-plane-segment");
  }
}

// Solver rays through the nested and the uniform grid: the same closest hit
// (patch, t's bits, side) and the same any-hit answer on every ray.
void CheckAgainstUniform(const TestScene& s, const Grid& nested, const Grid& uniform, uint32_t seed,
                         int count) {
  std::vector<Ray> rays;
  std::vector<uint32_t> from;
  SolverRays(s, seed, count, &rays, &from);
  int differ = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    Hit a, b;
    bool ha = nested.Intersect(rays[i], from[i], &a), hb = uniform.Intersect(rays[i], from[i], &b);
    bool same = ha == hb && nested.Occluded(rays[i], from[i]) == hb &&
                (!ha || (a.patch == b.patch && std::memcmp(&a.t, &b.t, sizeof a.t) == 0 &&
                         a.front == b.front));
    if (!same && ++differ <= 5)
      ADD_FAILURE() << "ray " << i << ": nested " << (ha ? a.patch : kNoPatch) << " uniform "
                    << (hb ? b.patch : kNoPatch);
  }
  EXPECT_EQ(differ, 0);
}

TEST(GridNestTest, NestedGridsMatchBruteForceAndTheUniformGrid) {
  struct Case {
    const char* name;
    TestScene scene;
    float density;
  };
  std::mt19937 rng(5);
  TestScene random;
  AddRandomPatches(rng, 1500, glm::vec3(0.0f), glm::vec3(1.0f), 0.005f, 0.3f, &random);
  Case cases[] = {{"clusters", ClusterScene(3), 1.0f},
                  {"clusters at 4 cells a patch", ClusterScene(4), 4.0f},
                  {"cornell", CornellScene(8), 1.0f},
                  {"random", random, 1.0f}};
  int total = 0, nestedCases = 0;
  for (const Case& c : cases) {
    BuiltGrid uniform;
    BuildGrid(c.scene, c.density, &uniform, UniformNest());
    for (const Grid::Nest& nest : {Grid::Nest(), DenseNest()}) {
      SCOPED_TRACE(std::string(c.name) + (nest.minRefs == 2 ? ", dense nest" : ", default nest"));
      BuiltGrid b;
      BuildGrid(c.scene, c.density, &b, nest);
      if (b.plan.subGrids == 0) continue;
      ++nestedCases;
      Checker ck{c.scene, b.grid};
      CheckRays(c.scene, b, 11, 300, &ck);
      CheckSubPlaneRays(b, 12, 1500, &ck);
      EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
      EXPECT_GT(ck.hits, ck.rays / 4);
      total += ck.rays;
      CheckAgainstUniform(c.scene, b.grid, uniform.grid, 13, 3000);
    }
  }
  EXPECT_GE(nestedCases, 6);  // the dense nest everywhere, the default on the clusters
  EXPECT_GE(total, 50000);
}

TEST(GridNestTest, LayoutMeasuresWhatItUses) {
  TestScene s = ClusterScene(7);
  BuiltGrid b;
  BuildGrid(s, 1.0f, &b);
  const Grid::Plan& plan = b.plan;
  ASSERT_GT(plan.subGrids, 0u);
  ASSERT_EQ(b.grid.subGrids().size(), plan.subGrids);
  // The arena holds exactly what the measuring pass counted.
  Arena measure = Arena::Measure();
  Grid probe;
  probe.Layout(measure, plan);
  EXPECT_EQ(b.arena.used(), measure.used());
  EXPECT_EQ(b.grid.bytes(), (plan.occupied + 1) * sizeof(CellRecord) +
                                plan.units * sizeof(uint16_t) +
                                ((b.grid.cellCount() + 63) / 64 + (plan.subCells + 63) / 64) * 12 +
                                plan.planes * sizeof(CellPlane) + plan.subGrids * sizeof(SubGrid));
  // Sub-grids tile their top cells, one after another, and every top cell
  // with one holds its header only.
  uint64_t cells = 0, refs = 0, headers = 0;
  for (size_t c = 0; c < b.grid.cellCount(); ++c) {
    const bool bit = b.grid.CellOccupied(c);
    const SubGrid* g = b.grid.SubGridOf(c);
    ASSERT_EQ(bit, g || !b.grid.CellRefs(c).empty()) << "cell " << c;
    if (!g) continue;
    EXPECT_TRUE(b.grid.CellRefs(c).empty());
    EXPECT_EQ(g->first, cells);
    cells += static_cast<uint64_t>(g->res[0]) * g->res[1] * g->res[2];
    EXPECT_GT(g->res[0] * g->res[1] * g->res[2], 1);
    ++headers;
  }
  EXPECT_EQ(cells, plan.subCells);
  for (size_t c = 0; c < plan.subCells; ++c) {
    const bool bit = b.grid.SubCellOccupied(c);
    ASSERT_EQ(bit, !b.grid.SubCellRefs(c).empty()) << "sub cell " << c;
  }
  ForEachLeafCell(b.grid, [&](const RefList& r, uint32_t) {
    ++headers;
    refs += r.size();
    for (size_t k = 1; k < r.size(); ++k) EXPECT_LT(r[k - 1], r[k]);  // sorted, no repeat
  });
  EXPECT_EQ(refs, plan.refs);
  EXPECT_EQ(headers, plan.occupied);
}

TEST(GridNestTest, DenseClustersWalkFewerSteps) {
  TestScene s = ClusterScene(9);
  BuiltGrid nested, uniform;
  BuildGrid(s, 1.0f, &nested);
  BuildGrid(s, 1.0f, &uniform, UniformNest());
  ASSERT_GT(nested.plan.subGrids, 0u);
  std::vector<Ray> rays;
  std::vector<uint32_t> from;
  SolverRays(s, 21, 4000, &rays, &from);
  for (size_t i = 0; i < rays.size(); ++i) {
    Hit h;
    nested.grid.Intersect(rays[i], from[i], &h);
    uniform.grid.Intersect(rays[i], from[i], &h);
  }
  // Most rays leave a cluster's patch: the uniform grid tests the cluster's
  // hundreds of patches in its few cells, the sub-grid a few.
  EXPECT_LT(nested.grid.steps() * 3, uniform.grid.steps())
      << nested.grid.steps() << " against " << uniform.grid.steps();
}

TEST(GridNestTest, EvenScenesStayUniform) {
  // The Cornell-like box split evenly, at an environment's density: no cell
  // holds enough references for a sub-grid, so the plan, the bytes and the
  // steps are the uniform grid's.
  TestScene s = CornellScene(16);
  BuiltGrid nested, uniform;
  BuildGrid(s, 1.0f, &nested);
  BuildGrid(s, 1.0f, &uniform, UniformNest());
  EXPECT_EQ(nested.plan.subGrids, 0u);
  EXPECT_EQ(nested.plan.refs, uniform.plan.refs);
  EXPECT_EQ(nested.plan.occupied, uniform.plan.occupied);
  EXPECT_EQ(nested.grid.bytes(), uniform.grid.bytes());
  EXPECT_EQ(nested.arena.used(), uniform.arena.used());
}

// A room lit from its ceiling, with a small ball of 512 faces on its floor:
// the ball's top cells hold hundreds of references each.
void WriteBallRoom(const std::string& dir) {
  std::ostringstream obj;
  obj << "mtllib room.mtl\nusemtl wall\n"
      << "v 0 0 0\nv 4 0 0\nv 4 0 4\nv 0 0 4\nv 0 3 0\nv 4 3 0\nv 4 3 4\nv 0 3 4\n"
      << "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n"
      << "usemtl light\nv 1.5 2.99 1.5\nv 2.5 2.99 1.5\nv 2.5 2.99 2.5\nv 1.5 2.99 2.5\n"
      << "f 9 10 11 12\nusemtl ball\n";
  const int kU = 32, kV = 16;
  const double r = 0.15, pi = std::acos(-1.0);
  for (int j = 0; j <= kV; ++j)
    for (int i = 0; i < kU; ++i) {
      const double th = pi * j / kV, ph = 2.0 * pi * i / kU;
      obj << "v " << 2.0 + r * std::sin(th) * std::cos(ph) << " " << r + r * std::cos(th) << " "
          << 2.0 + r * std::sin(th) * std::sin(ph) << "\n";
    }
  auto at = [&](int i, int j) { return 13 + j * kU + (i % kU); };
  for (int j = 0; j < kV; ++j)
    for (int i = 0; i < kU; ++i)
      obj << "f " << at(i, j) << " " << at(i + 1, j) << " " << at(i + 1, j + 1) << " "
          << at(i, j + 1) << "\n";
  test::WriteFile(dir + "/room.obj", obj.str());
  test::WriteFile(dir + "/room.mtl",
                  "newmtl wall\nKd 0.6 0.6 0.6\nnewmtl ball\nKd 0.7 0.3 0.3\n"
                  "newmtl light\nKd 0.5 0.5 0.5\nKe 10 10 10\n");
}

// --sub-grids: the default nests the ball's cells and 0 gives one uniform
// grid; in one environment every output byte is the same, since the
// sub-grids give the uniform grid's hit on every ray.
TEST(GridNestTest, SubGridsOptionChangesNoImageOrPatchByte) {
  EXPECT_EQ(Options().subGrids, Grid::Nest().minRefs);
  EXPECT_EQ(EnvOptions().subGridRefs, Grid::Nest().minRefs);
  test::TempDir dir;
  WriteBallRoom(dir.path());
  std::string json[2];
  for (int k = 0; k < 2; ++k) {
    std::vector<std::string> args = test::Words("render " + dir.File("room.obj") +
                                                " --width 32 --height 32 --max-shots 300 --out " +
                                                dir.File(k ? "uniform" : "nested"));
    if (k) args = test::Join(args, {"--sub-grids", "0"});
    auto r = test::RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    json[k] = test::ReadFile(dir.File(k ? "uniform/run.json" : "nested/run.json"));
  }
  EXPECT_GT(test::JsonNumber(json[0], "grid_sub_grids", "counts"), 0.0);
  EXPECT_EQ(test::JsonNumber(json[1], "grid_sub_grids", "counts"), 0.0);
  EXPECT_EQ(test::JsonNumber(json[1], "sub_grids", "options"), 0.0);
  EXPECT_EQ(test::JsonNumber(json[0], "shots"), test::JsonNumber(json[1], "shots"));
  for (const char* f : {"image.pfm", "patches.csv"})
    EXPECT_TRUE(test::ReadFile(dir.File(std::string("nested/") + f)) ==
                test::ReadFile(dir.File(std::string("uniform/") + f)))
        << f;
}

}  // namespace
}  // namespace vismask
