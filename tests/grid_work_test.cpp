// What MakePlan hands Build (Grid::Work), and the registration shortcut for
// patches whose normal lies along a box axis: both must leave the built
// grid exactly as it was.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "../src/accel/grid_cells.h"
#include "grid_test_util.h"
#include "vismask/accel/grid.h"

namespace vismask {
namespace {

using namespace gridtest;

// A scene with sub-grids: a dense cluster of small patches in a box of
// walls.
TestScene ClusterScene(uint32_t seed) {
  std::mt19937 rng(seed);
  TestScene s = CornellScene(6);
  AddRandomPatches(rng, 3000, glm::vec3(0.4f), glm::vec3(0.5f), 0.002f, 0.01f, &s);
  AddRandomPatches(rng, 300, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.1f, &s);
  return s;
}

struct Built {
  Arena arena{1};
  Grid grid;
};

// Lays out `plan` and builds it from `s`, with `work` (or none).
void BuildFrom(const TestScene& s, const Grid::Plan& plan, Grid::Work* work, Built* b) {
  Arena measure = Arena::Measure();
  Grid probe;
  probe.Layout(measure, plan);
  b->arena = Arena(measure.used());
  b->grid.Layout(b->arena, plan);
  b->grid.Build(Span<const Patch>(s.patches.data(), s.patches.size()),
                Span<const PatchGeom>(s.geom.data(), s.geom.size()), work);
}

std::vector<uint32_t> Refs(const RefList& list) {
  std::vector<uint32_t> v;
  for (uint32_t r : list) v.push_back(r);
  return v;
}

// Every array the walk reads, compared.
void ExpectSameGrid(const Grid& a, const Grid& b) {
  ASSERT_EQ(a.cellCount(), b.cellCount());
  ASSERT_EQ(a.bytes(), b.bytes());
  for (size_t c = 0; c < a.cellCount(); ++c) {
    ASSERT_EQ(a.CellOccupied(c), b.CellOccupied(c)) << c;
    ASSERT_EQ(a.CellPlaneOf(c), b.CellPlaneOf(c)) << c;
    ASSERT_EQ(Refs(a.CellRefs(c)), Refs(b.CellRefs(c))) << c;
  }
  ASSERT_EQ(a.subGrids().size(), b.subGrids().size());
  size_t subCells = 0;
  for (const SubGrid& g : a.subGrids())
    subCells += static_cast<size_t>(g.res[0]) * g.res[1] * g.res[2];
  for (size_t s = 0; s < subCells; ++s) {
    ASSERT_EQ(a.SubCellOccupied(s), b.SubCellOccupied(s)) << s;
    ASSERT_EQ(a.SubCellPlaneOf(s), b.SubCellPlaneOf(s)) << s;
    ASSERT_EQ(Refs(a.SubCellRefs(s)), Refs(b.SubCellRefs(s))) << s;
  }
  ASSERT_EQ(a.records().size(), b.records().size());
  for (size_t r = 0; r < a.records().size(); ++r) {
    EXPECT_EQ(a.records()[r].start, b.records()[r].start) << r;
    EXPECT_EQ(a.records()[r].header, b.records()[r].header) << r;
  }
}

TEST(GridWorkTest, BuildTakesItsPlansWorkAndBuildsTheSameGrid) {
  TestScene s = ClusterScene(5);
  Span<const Patch> patches(s.patches.data(), s.patches.size());
  Span<const PatchGeom> geom(s.geom.data(), s.geom.size());
  Grid::Work work;
  Grid::Plan plan = Grid::MakePlan(patches, geom, 1.0f, Grid::Nest(), &work);
  ASSERT_FALSE(work.empty());
  ASSERT_GT(plan.subGrids, 0u);  // the nested path is exercised
  Built with, without;
  BuildFrom(s, plan, &work, &with);
  EXPECT_TRUE(work.empty());  // taken
  BuildFrom(s, plan, nullptr, &without);
  ExpectSameGrid(with.grid, without.grid);
}

// Work from other patches is not taken: the grid is built from its own.
// (Taken, its counts would not be the plan's, or its cells not the
// patches'.)
TEST(GridWorkTest, BuildIgnoresWorkFromOtherPatches) {
  TestScene s = ClusterScene(6), other = ClusterScene(7);
  // The same number of patches and the same bounds (the walls'), one
  // small patch moved across the box: other cells.
  TestScene moved = s;
  Patch p = moved.patches.back();
  const float dx = p.corner[0].x < 0.5f ? 0.3f : -0.3f;
  for (glm::vec3& c : p.corner) c.x += dx;
  moved.patches.back() = p;
  moved.geom.back() = MakePatchGeom(p);
  Span<const Patch> patches(s.patches.data(), s.patches.size());
  Span<const PatchGeom> geom(s.geom.data(), s.geom.size());
  Grid::Plan plan = Grid::MakePlan(patches, geom, 1.0f);
  Built want;
  BuildFrom(s, plan, nullptr, &want);
  for (const TestScene* from : {&other, &moved}) {
    Grid::Work work;
    Grid::MakePlan(Span<const Patch>(from->patches.data(), from->patches.size()),
                   Span<const PatchGeom>(from->geom.data(), from->geom.size()), 1.0f, Grid::Nest(),
                   &work);
    ASSERT_FALSE(work.empty());
    Built got;
    BuildFrom(s, plan, &work, &got);
    EXPECT_TRUE(work.empty());  // spent either way
    ExpectSameGrid(got.grid, want.grid);
  }
}

// A patch whose normal lies along a box axis leaves out the axes an edge
// crossed with a box axis would add (MakeShape): they are 0 or exactly
// +-(an axis already there). The cells it is registered in must be those
// the whole set of axes gives, on every lattice tried.
TEST(GridWorkTest, AlignedPatchesRegisterTheCellsAllAxesGive) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  TestScene s;
  for (int k = 0; k < 400; ++k) {
    const int axis = k % 3;
    const float w = u(rng), u0 = u(rng), v0 = u(rng);
    const float du = 0.001f + 0.3f * u(rng) * u(rng), dv = 0.001f + 0.3f * u(rng) * u(rng);
    AddAxisQuad(axis, w, u0, u0 + du, v0, v0 + dv, k % 2 ? 1 : -1, &s);
    // A right triangle on the same plane: its long edge is slanted.
    glm::vec3 c[3];
    const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    for (int j = 0; j < 3; ++j) c[j][axis] = w;
    c[0][ua] = u0, c[0][va] = v0;
    c[1][ua] = u0 + du, c[1][va] = v0;
    c[2][ua] = u0, c[2][va] = v0 + dv;
    s.Add(MakePatch(c, 3));
  }
  const gridcells::Scale scale = gridcells::ScaleOf(Span<const Patch>(s.patches.data(), 800));
  int checked = 0;
  for (float density : {1.0f, 8.0f, 64.0f}) {
    const Grid::Plan plan =
        Grid::MakePlan(Span<const Patch>(s.patches.data(), 800), density, UniformNest());
    const gridcells::CellGeometry cells = gridcells::CellGeometryOf(plan);
    for (size_t i = 0; i < s.patches.size(); ++i) {
      gridcells::Shape shape;
      gridcells::MakeShape(s.patches[i], s.geom[i], scale, &shape);
      ASSERT_GT(shape.numAxes, 0);
      gridcells::Shape all;
      gridcells::MakeShape(s.patches[i], s.geom[i], scale, &all, false, /*allAxes=*/true);
      ASSERT_GT(all.numAxes, shape.numAxes) << i;  // the shortcut was taken
      std::vector<size_t> got, want;
      gridcells::ForEachCell(cells, shape, [&](size_t c) { got.push_back(c); });
      gridcells::ForEachCell(cells, all, [&](size_t c) { want.push_back(c); });
      ASSERT_EQ(got, want) << "patch " << i << " density " << density;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2400);
}

}  // namespace
}  // namespace vismask
