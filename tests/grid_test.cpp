// The grid against brute force: every kind of ray through random, flat,
// cell-aligned, sliver, edge-hugging and long scenes gets the same hit.
#include "vismask/accel/grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <random>
#include <vector>

#include "grid_test_util.h"

namespace vismask {
namespace {

using namespace gridtest;

TEST(GridTest, RandomScenesMatchBruteForce) {
  struct Case {
    int count;
    glm::vec3 lo, hi;
    float sizeLo, sizeHi, density;
    int rays;
  };
  const Case cases[] = {
      {2000, glm::vec3(0.0f), glm::vec3(1.0f), 0.005f, 0.3f, 4.0f, 1800},
      {300, glm::vec3(-2.0f, 0.0f, 5.0f), glm::vec3(3.0f, 0.5f, 7.0f), 0.01f, 2.0f, 1.0f, 900},
      {1000, glm::vec3(100.0f, -50.0f, 20.0f), glm::vec3(101.0f, -49.0f, 21.0f), 0.002f, 0.1f, 8.0f,
       900},
      {50, glm::vec3(0.0f), glm::vec3(1.0f), 0.5f, 3.0f, 2.0f, 600},
  };
  uint32_t seed = 1;
  int total = 0;
  for (const Case& c : cases) {
    std::mt19937 rng(seed);
    TestScene s;
    AddRandomPatches(rng, c.count, c.lo, c.hi, c.sizeLo, c.sizeHi, &s);
    BuiltGrid b;
    BuildGrid(s, c.density, &b);
    Checker ck{s, b.grid};
    CheckRays(s, b, seed + 100, c.rays, &ck);
    EXPECT_EQ(ck.failures, 0) << "scene " << seed << " of " << c.count << " patches, " << ck.rays
                              << " rays";
    EXPECT_GT(ck.hits, ck.rays / 20);
    total += ck.rays;
    ++seed;
  }
  EXPECT_GE(total, 60000);
}

TEST(GridTest, CornellBoxMatchesBruteForce) {
  int total = 0;
  const float densities[] = {0.5f, 4.0f, 30.0f};
  for (float density : densities) {
    TestScene s = CornellScene(8);
    BuiltGrid b;
    BuildGrid(s, density, &b);
    Checker ck{s, b.grid};
    CheckRays(s, b, 7, 900, &ck);
    EXPECT_EQ(ck.failures, 0) << "density " << density;
    total += ck.rays;
  }
  EXPECT_GE(total, 45000);
}

// Cells whose patches share a plane (CellPlane): a ray that meets the plane
// behind its origin skips them without reading a patch. The scene has
// walls of one surface each, a tilted wall whose patches' plane offsets
// differ by rounding, and that wall's twins (TwinGeom: the normal's other
// sign) in the same cells. The skip must give brute force's hit, bit for
// bit, from points on, in front of and behind the planes, with tMin 0 and
// with tMin < 0 (where a hit behind the origin counts and no cell may be
// skipped).
TEST(GridTest, SharedPlanesSkipCellsExactly) {
  TestScene s = CornellScene(8);
  for (size_t i = 0; i < s.patches.size(); ++i)
    s.patches[i].surface = static_cast<uint32_t>(i < 320 ? i / 64 : 5 + i);
  const size_t tiltFirst = s.patches.size();
  const int m = 6;
  const glm::vec3 origin(0.1f, 0.15f, 0.6f), u(0.7f, 0.05f, -0.3f), v(0.02f, 0.6f, 0.13f);
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < m; ++j) {
      glm::vec3 c[4] = {origin + u * (i / float(m)) + v * (j / float(m)),
                        origin + u * ((i + 1) / float(m)) + v * (j / float(m)),
                        origin + u * ((i + 1) / float(m)) + v * ((j + 1) / float(m)),
                        origin + u * (i / float(m)) + v * ((j + 1) / float(m))};
      Patch p = MakePatch(c, 4);
      p.normal = glm::normalize(glm::cross(u, v));  // one normal for the whole surface
      p.surface = 1000;
      s.Add(p);
    }
  }
  const size_t tiltEnd = s.patches.size();
  for (size_t i = tiltFirst; i < tiltEnd; ++i) {  // the twins: a run of their own
    Patch t = s.patches[i];
    std::swap(t.corner[1], t.corner[3]);
    t.normal = -t.normal;
    s.patches.push_back(t);
    s.geom.push_back(TwinGeom(s.geom[i]));
  }
  // The uniform grid, and the same scene with sub-grids in most cells
  // (their cells carry plane records the same way).
  for (const Grid::Nest& nest : {UniformNest(), DenseNest()}) {
    SCOPED_TRACE(nest.minRefs ? "nested" : "uniform");
    BuiltGrid b;
    BuildGrid(s, 4.0f, &b, nest);
    if (nest.minRefs) {
      EXPECT_GT(b.plan.subGrids, 0u);
    }
    Span<const CellPlane> planes = b.grid.planes();
    ASSERT_EQ(planes.size(), b.plan.planes);
    ASSERT_EQ(planes.size(), 6u);  // five walls, and the tilted wall with its twins

    // Every record covers its run: the same normal up to sign, every offset in range.
    bool spread = false;
    for (const CellPlane& r : planes) {
      spread |= r.dLo < r.dHi;
      for (uint32_t p = r.first; p < r.first + r.count; ++p) {
        const PatchGeom& g = s.geom[p];
        float sign = g.n == r.n ? 1.0f : -1.0f;
        ASSERT_EQ(sign * g.n, r.n) << "patch " << p;
        ASSERT_GE(sign * g.d, r.dLo) << "patch " << p;
        ASSERT_LE(sign * g.d, r.dHi) << "patch " << p;
      }
    }
    EXPECT_TRUE(spread);  // the tilted wall's offsets round apart
    // Cells with a plane: every patch in a run with that record; one holds a patch and its twin.
    size_t withPlane = 0, occupied = 0, twinned = 0;
    ForEachLeafCell(b.grid, [&](const RefList& refs, uint32_t h) {
      ++occupied;
      if (h == Grid::kNoPlane) return;
      ++withPlane;
      ASSERT_LT(h, planes.size());
      bool orig = false, twin = false;
      for (uint32_t p : refs) {
        const PatchGeom& g = s.geom[p];
        float sign = g.n == planes[h].n ? 1.0f : -1.0f;
        ASSERT_EQ(sign * g.n, planes[h].n) << "patch " << p;
        ASSERT_GE(sign * g.d, planes[h].dLo);
        ASSERT_LE(sign * g.d, planes[h].dHi);
        orig |= p >= tiltFirst && p < tiltEnd;
        twin |= p >= tiltEnd;
      }
      twinned += orig && twin;
    });
    // Most cells of the uniform grid; of the nested one's, a third at least
    // (a cell of one plane keeps its patches, the cells split are mixed ones).
    EXPECT_GT(withPlane * (nest.minRefs ? 3 : 2), occupied) << withPlane << " of " << occupied;
    EXPECT_GT(twinned, 0u);

    Checker ck{s, b.grid};
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u01(0.0f, 1.0f);
    for (int i = 0; i < 6000; ++i) {
      uint32_t p = static_cast<uint32_t>(rng() % s.patches.size());
      glm::vec3 n = glm::normalize(s.geom[p].n);
      float offsets[3] = {0.0f, 1e-6f, -1e-6f};
      glm::vec3 o = PointOnPatch(rng, s.patches[p]) + offsets[i % 3] * n;
      glm::vec3 d = UnitVector(rng);
      if (i % 5 == 0) d = glm::normalize(d - glm::dot(d, n) * n + 1e-4f * n);  // grazing
      float tMin = i % 4 == 0 ? -0.5f : 0.0f;
      ck.Check(Ray{o, d, tMin, kInf}, i % 2 ? p : kNoPatch, "plane");
      ck.Check(Ray{o, -d, tMin, 0.3f + u01(rng)}, kNoPatch, "plane-reverse");
    }
    CheckRays(s, b, 29, 300, &ck);
    EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
    EXPECT_GT(ck.hits, ck.rays / 3);
  }
}

TEST(GridTest, FlatScenes) {
  // One axis-aligned quad: the grid must still have thickness.
  TestScene quad;
  AddAxisQuad(2, 0.25f, 0.0f, 1.0f, 0.0f, 1.0f, +1, &quad);
  BuiltGrid b;
  BuildGrid(quad, 4.0f, &b);
  EXPECT_EQ(b.plan.res[2], 1);
  EXPECT_LT(b.plan.bounds.lo.z, 0.25f);
  EXPECT_GT(b.plan.bounds.hi.z, 0.25f);
  EXPECT_EQ(b.plan.refs, b.grid.cellCount());  // the quad spans every cell
  Hit hit;
  ASSERT_TRUE(b.grid.Intersect(Ray{glm::vec3(0.3f, 0.6f, 1.0f), glm::vec3(0, 0, -1), 0.0f, kInf},
                               kNoPatch, &hit));
  EXPECT_EQ(hit.patch, 0u);
  EXPECT_EQ(hit.t, 0.75f);
  EXPECT_TRUE(hit.front);
  EXPECT_FALSE(b.grid.Intersect(Ray{glm::vec3(1.3f, 0.6f, 1.0f), glm::vec3(0, 0, -1), 0.0f, kInf},
                                kNoPatch, &hit));
  Checker ck{quad, b.grid};
  CheckRays(quad, b, 11, 300, &ck);
  EXPECT_EQ(ck.failures, 0);

  // Many triangles in one slanted plane.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  TestScene plane;
  glm::vec3 e1 = glm::normalize(glm::vec3(1.0f, 0.3f, 0.1f));
  glm::vec3 e2 = glm::normalize(glm::cross(glm::vec3(0.2f, 0.1f, 1.0f), e1));
  while (plane.patches.size() < 500) {
    glm::vec3 c[3];
    for (glm::vec3& x : c) x = (4.0f * u01(rng)) * e1 + (4.0f * u01(rng)) * e2;
    Patch p = MakePatch(c, 3);
    if (std::isfinite(p.normal.x) && p.area > 1e-4f) plane.Add(p);
  }
  BuiltGrid bp;
  BuildGrid(plane, 4.0f, &bp);
  Checker ckp{plane, bp.grid};
  CheckRays(plane, bp, 12, 400, &ckp);
  EXPECT_EQ(ckp.failures, 0);
}

// Patches whose planes, edges and corners lie on the cell lattice, and rays
// along lattice lines: every hit is on a cell boundary.
TEST(GridTest, CellAlignedSceneMatchesBruteForce) {
  // Two big anchor quads fix the bounds; the plan depends only on them and on
  // the patch count, so a first scene of the same size tells us the lattice.
  const int kCount = 600;
  std::mt19937 rng(17);
  Grid::Plan plan = AnchoredPlan(rng, kCount, 0.01f, 0.1f, 4.0f);
  const Bounds& bb = plan.bounds;
  glm::vec3 cell = (bb.hi - bb.lo) / glm::vec3(plan.res[0], plan.res[1], plan.res[2]);
  auto lattice = [&](int a, int k) { return bb.lo[a] + static_cast<float>(k) * cell[a]; };
  // Lattice indices well inside [0, 1] on every axis.
  int kLo[3], kHi[3];
  for (int a = 0; a < 3; ++a) {
    kLo[a] = static_cast<int>(std::ceil((0.1f - bb.lo[a]) / cell[a]));
    kHi[a] = static_cast<int>(std::floor((0.9f - bb.lo[a]) / cell[a]));
    ASSERT_LT(kLo[a] + 3, kHi[a]);
  }
  auto pick = [&](int a) { return kLo[a] + static_cast<int>(rng() % (kHi[a] - kLo[a] + 1)); };

  TestScene s;
  AddAnchors(&s);
  while (static_cast<int>(s.patches.size()) < kCount + 2) {
    if (s.patches.size() % 2 == 0) {
      // Axis-aligned quad on a cell plane, edges on cell planes.
      int axis = static_cast<int>(rng() % 3), ua = (axis + 1) % 3, va = (axis + 2) % 3;
      int u0 = pick(ua), v0 = pick(va);
      int u1 = std::min(kHi[ua], u0 + 1 + static_cast<int>(rng() % 3));
      int v1 = std::min(kHi[va], v0 + 1 + static_cast<int>(rng() % 3));
      if (u1 == u0 || v1 == v0) continue;
      AddAxisQuad(axis, lattice(axis, pick(axis)), lattice(ua, u0), lattice(ua, u1),
                  lattice(va, v0), lattice(va, v1), rng() % 2 ? 1 : -1, &s);
    } else {
      // Triangle with corners on lattice points.
      glm::vec3 c[3];
      int k0[3];
      for (int a = 0; a < 3; ++a) k0[a] = pick(a);
      for (glm::vec3& x : c) {
        for (int a = 0; a < 3; ++a) {
          int k = std::clamp(k0[a] + static_cast<int>(rng() % 5) - 2, kLo[a], kHi[a]);
          x[a] = lattice(a, k);
        }
      }
      Patch p = MakePatch(c, 3);
      float minCell = std::min({cell.x, cell.y, cell.z});
      if (!(p.area > 0.1f * minCell * minCell)) continue;  // collinear corners
      s.Add(p);
    }
  }
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  ASSERT_TRUE(SamePlan(b.plan, plan));

  Checker ck{s, b.grid};
  CheckRays(s, b, 23, 400, &ck);
  // From lattice points along lattice axes, face and space diagonals.
  const glm::vec3 dirs[] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1},  {1, 1, 0},  {1, 0, 1},
                            {0, 1, 1}, {1, 1, 1}, {1, -1, 0}, {1, 1, -1}, {-1, 1, 1}};
  for (int i = 0; i < 3000; ++i) {
    glm::vec3 o;
    for (int a = 0; a < 3; ++a) o[a] = lattice(a, static_cast<int>(rng() % (plan.res[a] + 1)));
    glm::vec3 d = dirs[rng() % 10] * (rng() % 2 ? 1.0f : -1.0f);
    for (int a = 0; a < 3; ++a) d[a] *= cell[a];  // through lattice points exactly
    ck.CheckWithSkips(Ray{o, d, 0.0f, kInf}, "lattice");
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
}

// Slivers: the widened edge planes of a very sharp corner reach well past the
// tip, and IntersectPatch accepts hits there; the grid must too.
TEST(GridTest, SliverTipsMatchBruteForce) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  TestScene s;
  AddRandomPatches(rng, 300, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.2f, &s);
  struct Tip {
    glm::vec3 point, out, normal;
  };
  std::vector<Tip> tips;
  glm::vec3 shift(u01(rng) * 50.0f, 0.0f, 0.0f);
  for (int i = 0; i < 300; ++i) {
    glm::vec3 c0 = glm::vec3(u01(rng), u01(rng), u01(rng)) + (i % 2 ? shift : glm::vec3(0.0f));
    glm::vec3 axis = UnitVector(rng);
    glm::vec3 side = glm::normalize(glm::cross(axis, UnitVector(rng)));
    float length = 0.05f + 0.3f * u01(rng);
    float width = length * std::exp(std::log(1e-6f) + std::log(1e4f) * u01(rng));
    glm::vec3 c[3] = {c0, c0 + length * axis, c0 + 0.5f * length * axis + width * side};
    Patch p = MakePatch(c, 3);
    if (!std::isfinite(p.normal.x + p.normal.y + p.normal.z) || p.area <= 0.0f) continue;
    s.Add(p);
    tips.push_back({c[0], -axis, p.normal});
    tips.push_back({c[1], axis, p.normal});
  }
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  Checker ck{s, b.grid};
  for (int i = 0; i < 20000; ++i) {
    const Tip& tip = tips[rng() % tips.size()];
    // A target on the patch plane, at or beyond the tip by 0 .. 0.1.
    float beyond = i % 4 == 0 ? 0.0f : std::exp(std::log(1e-9f) + std::log(1e8f) * u01(rng));
    glm::vec3 target = tip.point + beyond * tip.out;
    glm::vec3 from = target + (0.05f + u01(rng)) * UnitVector(rng);
    ck.CheckWithSkips(Ray{from, target - from, 0.0f, kInf}, "sliver-tip");
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
}

// Rays as the solver casts them, from points on the walls of a Cornell box
// (walls in outer layers, rays leaving them through a sliver of a cell), at
// several densities; and again with the box far from the world origin, where
// the padding is a few hundred ulps of coordinates much larger than a cell.
TEST(GridTest, SolverRaysMatchBruteForce) {
  int total = 0;
  for (float offset : {0.0f, 3000.0f}) {
    TestScene s = CornellScene(12);
    if (offset != 0.0f) {
      for (size_t i = 0; i < s.patches.size(); ++i) {
        for (glm::vec3& c : s.patches[i].corner) c += glm::vec3(offset, -0.5f * offset, 0.0f);
        s.geom[i] = MakePatchGeom(s.patches[i]);
      }
    }
    for (float density : {1.0f, 4.0f, 8.0f}) {
      BuiltGrid b;
      BuildGrid(s, density, &b);
      Checker ck{s, b.grid};
      std::vector<Ray> rays;
      std::vector<uint32_t> from;
      SolverRays(s, 53, 4000, &rays, &from);
      for (size_t i = 0; i < rays.size(); ++i) ck.Check(rays[i], from[i], "solver");
      EXPECT_EQ(ck.failures, 0) << "offset " << offset << ", density " << density;
      EXPECT_GT(ck.hits, ck.rays / 2);
      total += ck.rays;
    }
  }
  EXPECT_GE(total, 24000);
}

// Tiny patches next to a cell edge (where two cell planes meet), a few pads
// from both planes, so that each is registered in one cell only: a ray that
// reaches one crosses the two planes within a few pads of each other, and
// must be walked across them in the right order (or it skips the patch's
// cell), after crossing many planes on its way there.
TEST(GridTest, EdgeHuggingPatchesMatchBruteForce) {
  // Two anchor quads fix the bounds, so a first scene of the same size gives
  // the lattice (as in CellAlignedSceneMatchesBruteForce).
  const int kCount = 1200;
  std::mt19937 rng(47);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  Grid::Plan plan = AnchoredPlan(rng, kCount, 0.01f, 0.02f, 8.0f);
  const Bounds& bb = plan.bounds;
  glm::vec3 cell = (bb.hi - bb.lo) / glm::vec3(plan.res[0], plan.res[1], plan.res[2]);
  const float pad = 4e-5f;  // kPadRel times the scene magnitude, 1 here
  TestScene s;
  AddAnchors(&s);
  std::vector<glm::vec3> targets;
  while (static_cast<int>(s.patches.size()) < kCount + 2) {
    // The edge along axis c where planes of axes a and b meet; the patch
    // faces along c, 4 pads off both planes, one pad across.
    int c = static_cast<int>(rng() % 3), a = (c + 1) % 3, b = (c + 2) % 3;
    glm::vec3 p;
    for (int q : {a, b}) {
      int k = 2 + static_cast<int>(rng() % (plan.res[q] - 3));
      p[q] = bb.lo[q] + static_cast<float>(k) * cell[q] + (rng() % 2 ? 4.0f : -4.0f) * pad;
    }
    int k = 1 + static_cast<int>(rng() % (plan.res[c] - 2));
    p[c] = bb.lo[c] + (static_cast<float>(k) + 0.2f + 0.6f * u01(rng)) * cell[c];
    targets.push_back(p);
    AddAxisQuad(c, p[c], p[a] - 0.5f * pad, p[a] + 0.5f * pad, p[b] - 0.5f * pad, p[b] + 0.5f * pad,
                rng() % 2 ? 1 : -1, &s);
  }
  BuiltGrid b;
  BuildGrid(s, 8.0f, &b);
  ASSERT_TRUE(SamePlan(b.plan, plan));
  // Each target is registered in one cell.
  std::vector<int> cells(s.patches.size(), 0);
  for (size_t c = 0; c < b.grid.cellCount(); ++c)
    for (uint32_t r : b.grid.CellRefs(c)) ++cells[r];
  for (size_t i = 2; i < s.patches.size(); ++i) ASSERT_EQ(cells[i], 1) << "patch " << i;

  Checker ck{s, b.grid};
  for (int i = 0; i < 20000; ++i) {
    glm::vec3 target = targets[rng() % targets.size()];
    // From a random point on the grid's box, so many planes lie on the way.
    glm::vec3 o = bb.lo + glm::vec3(u01(rng), u01(rng), u01(rng)) * (bb.hi - bb.lo);
    int face = static_cast<int>(rng() % 3);
    o[face] = rng() % 2 ? bb.lo[face] : bb.hi[face];
    ck.Check(Ray{o, target - o, 0.0f, kInf}, kNoPatch, "edge-hugging");
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
  EXPECT_GT(ck.hits, ck.rays / 2);
}

// Long walks: a grid 1024 cells long, rays along it from end to end, so the
// per-axis plane formula is taken out to its last plane.
TEST(GridTest, LongWalksMatchBruteForce) {
  std::mt19937 rng(43);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  TestScene s;
  for (int i = 0; i < 3000; ++i) {
    int axis = i % 3;
    float x = 1000.0f * u01(rng), w = axis == 0 ? x : u01(rng);
    AddAxisQuad(axis, w, 0.0f, 0.2f, 0.0f, 0.2f, i % 2 ? 1 : -1, &s);
    // Spread over the cross-section, off the quad's own plane.
    glm::vec3 shift(axis == 0 ? 0.0f : x, axis == 1 ? 0.0f : 0.8f * u01(rng),
                    axis == 2 ? 0.0f : 0.8f * u01(rng));
    Patch& p = s.patches.back();
    for (glm::vec3& c : p.corner) c += shift;
    s.geom.back() = MakePatchGeom(p);
  }
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  ASSERT_EQ(b.plan.res[0], 1024);
  Checker ck{s, b.grid};
  const Bounds& bb = b.plan.bounds;
  for (int i = 0; i < 3000; ++i) {
    // From beyond one end to beyond the other, slightly off the axis.
    float side = i % 2 ? 1.0f : -1.0f;
    glm::vec3 o(side > 0 ? bb.lo.x - 1.0f : bb.hi.x + 1.0f, u01(rng), u01(rng));
    glm::vec3 target(side > 0 ? bb.hi.x : bb.lo.x, u01(rng), u01(rng));
    ck.CheckWithSkips(Ray{o, target - o, 0.0f, kInf}, "along");
    // Exactly along the axis, from a cell plane.
    int k = static_cast<int>(rng() % (b.plan.res[0] + 1));
    float cell = (bb.hi.x - bb.lo.x) / b.plan.res[0];
    glm::vec3 o2(bb.lo.x + static_cast<float>(k) * cell, u01(rng), u01(rng));
    ck.CheckWithSkips(Ray{o2, glm::vec3(side, 0.0f, 0.0f), 0.0f, kInf}, "axis");
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
  EXPECT_GT(ck.hits, ck.rays / 4);
}

// The walk's clip, axis by axis: each component of the direction moving,
// zero (the origin then inside or outside that slab) or so small that its
// inverse overflows (every patch tested), each origin coordinate inside
// the box or beyond either face: brute force's hit in every combination.
TEST(GridTest, ClipAxesMatchBruteForce) {
  TestScene s = CornellScene(4);
  BuiltGrid b;
  BuildGrid(s, 1.0f, &b);
  Checker ck{s, b.grid};
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  const float tiny = 1e-39f;  // subnormal: 1 / tiny overflows
  int overflowHits = 0;
  for (int dirs = 0; dirs < 27; ++dirs) {
    for (int places = 0; places < 27; ++places) {
      for (int rep = 0; rep < 4; ++rep) {
        glm::vec3 o, d;
        bool overflows = false;
        for (int a = 0, dc = dirs, pc = places; a < 3; ++a, dc /= 3, pc /= 3) {
          const float sign = rng() % 2 ? 1.0f : -1.0f;
          d[a] = dc % 3 == 0 ? sign * (0.2f + u01(rng)) : (dc % 3 == 1 ? 0.0f : sign * tiny);
          overflows |= dc % 3 == 2;
          o[a] = pc % 3 == 0 ? 0.05f + 0.9f * u01(rng) : (pc % 3 == 1 ? -0.5f : 1.5f);
        }
        if (d == glm::vec3(0.0f)) continue;
        const int before = ck.hits;
        ck.CheckWithSkips(Ray{o, d, 0.0f, kInf}, "clip");
        ck.CheckWithSkips(Ray{o, d, 0.0f, 0.5f + u01(rng)}, "clip-segment");
        if (overflows) overflowHits += ck.hits - before;
      }
    }
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
  EXPECT_GT(ck.hits, ck.rays / 20);  // most origins lie outside the box
  EXPECT_GT(overflowHits, 0);        // rays that only testing every patch can answer
}

TEST(GridTest, EdgeCases) {
  TestScene s = CornellScene(4);
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  Hit hit;
  // Zero direction, empty interval, reversed interval: no hit.
  EXPECT_FALSE(b.grid.Intersect(Ray{glm::vec3(0.5f), glm::vec3(0.0f), 0.0f, kInf}, kNoPatch, &hit));
  EXPECT_FALSE(b.grid.Occluded(Ray{glm::vec3(0.5f), glm::vec3(0, 1, 0), 0.3f, 0.3f}, kNoPatch));
  EXPECT_FALSE(b.grid.Occluded(Ray{glm::vec3(0.5f), glm::vec3(0, 1, 0), 0.4f, 0.1f}, kNoPatch));
  // Straight up from the floor's centre line through the light.
  ASSERT_TRUE(b.grid.Intersect(Ray{glm::vec3(0.5f, 0.0f, 0.5f), glm::vec3(0, 1, 0), 0.0f, kInf},
                               kNoPatch, &hit));
  EXPECT_FLOAT_EQ(hit.t, 0.999f);
  EXPECT_TRUE(hit.front);
  // Along the floor plane: the floor is never hit edge-on, the right wall is.
  ASSERT_TRUE(b.grid.Intersect(Ray{glm::vec3(0.1f, 0.0f, 0.1f), glm::vec3(1, 0, 0), 0.0f, kInf},
                               kNoPatch, &hit));
  EXPECT_FLOAT_EQ(hit.t, 0.9f);
  EXPECT_TRUE(hit.front);  // the right wall faces -x, into the box
  // Shared edges between wall quads leave no crack.
  for (int i = 0; i <= 16; ++i) {
    float x = i / 16.0f;
    EXPECT_TRUE(
        b.grid.Occluded(Ray{glm::vec3(x, 0.5f, 0.9f), glm::vec3(0, 0, -1), 0.0f, kInf}, kNoPatch))
        << x;
  }
  // An empty grid answers every ray with a miss.
  TestScene none;
  BuiltGrid e;
  BuildGrid(none, 4.0f, &e);
  EXPECT_EQ(e.plan.refs, 0u);
  EXPECT_FALSE(
      e.grid.Intersect(Ray{glm::vec3(0.5f), glm::vec3(0, 1, 0), 0.0f, kInf}, kNoPatch, &hit));
  EXPECT_FALSE(e.grid.Occluded(Ray{glm::vec3(-3.0f), glm::vec3(1, 1, 1), 0.0f, kInf}, kNoPatch));
  // Out of the open front: nothing.
  EXPECT_FALSE(
      b.grid.Occluded(Ray{glm::vec3(0.1f, 0.9f, 0.9f), glm::vec3(0, 0, 1), 0.0f, kInf}, kNoPatch));
}

}  // namespace
}  // namespace vismask
