// How the grid stores its references: records for occupied cells only,
// 16-bit references from a block's least patch or 32-bit ones, and only the
// plane records some cell names. Every layout must find brute force's hits
// and take exactly the bytes its plan counted.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "grid_test_util.h"
#include "vismask/accel/grid.h"

namespace vismask {
namespace {

using namespace gridtest;

// More than 65536 patches: a floor, a cluster of props whose indices lie
// at both ends (a sub-grid whose references must be 32-bit), a cluster of
// consecutive indices (16-bit), and a far field of small triangles between
// them in index order, which makes the top cells' references 32-bit.
constexpr int kFiller = 66000;
TestScene WideScene() {
  TestScene s;
  AddSubdividedQuad(1, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, +1, 10, &s);  // floor
  std::mt19937 rng(5);
  const glm::vec3 mixed(0.3f, 0.1f, 0.3f), plain(0.7f, 0.1f, 0.7f);
  AddRandomPatches(rng, 200, mixed - 0.04f, mixed + 0.04f, 0.002f, 0.03f, &s);
  AddRandomPatches(rng, kFiller, glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(1.0f, 1.0f, 1.0f), 0.0005f,
                   0.002f, &s);
  AddRandomPatches(rng, 200, mixed - 0.04f, mixed + 0.04f, 0.002f, 0.03f, &s);
  AddRandomPatches(rng, 300, plain - 0.04f, plain + 0.04f, 0.002f, 0.03f, &s);
  return s;
}

// The patch indices a cell's references decode to: ascending, in range.
::testing::AssertionResult Decodes(const RefList& refs, size_t patches) {
  for (size_t k = 0; k < refs.size(); ++k) {
    if (refs[k] >= patches) return ::testing::AssertionFailure() << "patch " << refs[k];
    if (k > 0 && !(refs[k - 1] < refs[k]))
      return ::testing::AssertionFailure() << refs[k - 1] << " before " << refs[k];
  }
  return ::testing::AssertionSuccess();
}

TEST(GridRefsTest, WideAndNarrowReferencesFindBruteForceHits) {
  const TestScene s = WideScene();
  const size_t n = s.patches.size();
  // Sub-grids wherever cells are shared (the clusters' cells hold a dozen
  // references each at this density).
  BuiltGrid b;
  BuildGrid(s, 1.0f, &b, DenseNest());
  const Grid::Plan& plan = b.plan;
  ASSERT_TRUE(plan.topWide);
  ASSERT_GT(plan.subGrids, 0u);
  size_t wide = 0, narrow = 0;
  for (const SubGrid& g : b.grid.subGrids()) (g.wide ? wide : narrow) += 1;
  EXPECT_GT(wide, 0u);
  EXPECT_GT(narrow, 0u);

  // Every cell decodes to what its width says, and the units add up to the
  // plan's: 2 a 32-bit reference, 1 a 16-bit one.
  uint64_t units = 0, refs = 0;
  for (size_t c = 0; c < b.grid.cellCount(); ++c) {
    RefList r = b.grid.CellRefs(c);
    ASSERT_TRUE(Decodes(r, n)) << "cell " << c;
    units += 2 * r.size();
    refs += r.size();
  }
  for (const SubGrid& g : b.grid.subGrids()) {
    const size_t cells = static_cast<size_t>(g.res[0]) * g.res[1] * g.res[2];
    for (size_t l = 0; l < cells; ++l) {
      RefList r = b.grid.SubCellRefs(g.first + l);
      ASSERT_TRUE(Decodes(r, n)) << "sub cell " << g.first + l;
      for (uint32_t p : r) {
        if (!g.wide) {
          ASSERT_LE(p - g.base, 0xffffu);
        }
      }
      units += (g.wide ? 2 : 1) * r.size();
      refs += r.size();
    }
  }
  EXPECT_EQ(refs, plan.refs);
  EXPECT_EQ(units, plan.units);
  // The arena holds exactly what the measuring pass counted, and the grid
  // reports it.
  Arena measure = Arena::Measure();
  Grid probe;
  probe.Layout(measure, plan);
  EXPECT_EQ(b.arena.used(), measure.used());
  EXPECT_EQ(b.grid.bytes(), probe.bytes());
  EXPECT_EQ(b.grid.bytes(), (plan.occupied + 1) * sizeof(CellRecord) +
                                plan.units * sizeof(uint16_t) +
                                ((b.grid.cellCount() + 63) / 64 + (plan.subCells + 63) / 64) * 12 +
                                plan.planes * sizeof(CellPlane) + plan.subGrids * sizeof(SubGrid));

  // Rays through the clusters (inside them, and from their patches), each
  // against brute force and against the uniform grid's hit.
  BuiltGrid uniform;
  BuildGrid(s, 1.0f, &uniform, UniformNest());
  Checker ck{s, b.grid};
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  const uint32_t clusters[][2] = {{100, 300},
                                  {100 + 200 + kFiller, 100 + 400 + kFiller},
                                  {100 + 400 + kFiller, 100 + 700 + kFiller}};
  int differ = 0;
  for (int i = 0; i < 240; ++i) {
    const uint32_t* range = clusters[i % 3];
    const uint32_t from = range[0] + rng() % (range[1] - range[0]);
    glm::vec3 o = i % 2 ? PointOnPatch(rng, s.patches[from])
                        : s.patches[from].corner[0] + 0.05f * (UnitVector(rng) * u01(rng));
    Ray ray{o, UnitVector(rng), 1e-6f, kInf};
    ck.CheckWithSkips(ray, "cluster");
    Hit got, want;
    const bool g = b.grid.Intersect(ray, Skip(), &got);
    const bool w = uniform.grid.Intersect(ray, Skip(), &want);
    differ += g != w || (g && (got.patch != want.patch || got.t != want.t));
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
  EXPECT_EQ(differ, 0);
  EXPECT_GT(ck.hits, ck.rays / 4);
}

TEST(GridRefsTest, KeepsOnlyThePlaneRecordsCellsName) {
  for (int m : {3, 8}) {
    SCOPED_TRACE("cornell " + std::to_string(m));
    TestScene s = CornellScene(m);
    for (const Grid::Nest& nest : {UniformNest(), DenseNest(), Grid::Nest()}) {
      BuiltGrid b;
      BuildGrid(s, 1.0f, &b, nest);
      Span<const CellPlane> planes = b.grid.planes();
      ASSERT_EQ(planes.size(), b.plan.planes);
      std::vector<int> named(planes.size(), 0);
      ForEachLeafCell(b.grid, [&](const RefList& refs, uint32_t h) {
        if (h == Grid::kNoPlane) return;
        ASSERT_LT(h, planes.size());
        ++named[h];
        // Every patch of the cell lies in the record's plane and range.
        for (uint32_t p : refs) {
          const PatchGeom& g = s.geom[p];
          const float sign = g.n == planes[h].n ? 1.0f : -1.0f;
          ASSERT_EQ(sign * g.n, planes[h].n) << "patch " << p;
          ASSERT_GE(sign * g.d, planes[h].dLo) << "patch " << p;
          ASSERT_LE(sign * g.d, planes[h].dHi) << "patch " << p;
        }
      });
      EXPECT_GT(planes.size(), 0u);
      for (size_t r = 0; r < named.size(); ++r) EXPECT_GT(named[r], 0) << "record " << r;
      // In run order.
      for (size_t r = 1; r < planes.size(); ++r) EXPECT_LT(planes[r - 1].first, planes[r].first);
    }
  }
}

}  // namespace
}  // namespace vismask
