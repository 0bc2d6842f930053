// Helpers shared by the grid tests: random and axis-aligned scenes, a grid
// built in its own arena, and a brute-force reference to check it against.
#pragma once
#include <gtest/gtest.h>

#include <cstdint>
#include <glm/vec3.hpp>
#include <limits>
#include <random>
#include <vector>

#include "vismask/accel/grid.h"
#include "vismask/core/arena.h"

namespace vismask::gridtest {

inline constexpr float kPi = 3.14159265358979f;
inline constexpr float kInf = std::numeric_limits<float>::infinity();

// A patch from 3 or 4 corners, counter-clockwise seen from the front.
Patch MakePatch(const glm::vec3* c, uint32_t n);

// A scene: patches and their ray-test data, kept side by side.
struct TestScene {
  std::vector<Patch> patches;
  std::vector<PatchGeom> geom;
  void Add(const Patch& p) {
    patches.push_back(p);
    geom.push_back(MakePatchGeom(p));
  }
};

glm::vec3 UnitVector(std::mt19937& rng);

// Random triangles and planar convex quads (corners on an ellipse, in angle
// order) of log-uniform sizes in [sizeLo, sizeHi], centred in [lo, hi].
void AddRandomPatches(std::mt19937& rng, int count, glm::vec3 lo, glm::vec3 hi, float sizeLo,
                      float sizeHi, TestScene* scene);

// An axis-aligned quad [u0,u1] x [v0,v1] on the plane x[axis] == w, facing
// +axis (sign > 0) or -axis.
void AddAxisQuad(int axis, float w, float u0, float u1, float v0, float v1, int sign,
                 TestScene* scene);

// The same quad split m x m.
void AddSubdividedQuad(int axis, float w, float u0, float u1, float v0, float v1, int sign, int m,
                       TestScene* scene);

// Axis-aligned block [lo, hi], faces outward, each split m x m.
void AddBlock(glm::vec3 lo, glm::vec3 hi, int m, TestScene* scene);

// A Cornell-like box in [0,1]^3: five inward walls, a light, two blocks.
TestScene CornellScene(int m);

// Two big anchor quads, on z = 0 and z = 1 across [0,1]^2, that fix the
// bounds: the plan then depends only on them and on the patch count.
void AddAnchors(TestScene* s);

// The plan of the anchors and `count` random patches of sizes [sizeLo,
// sizeHi] in [0.3, 0.7]^3 (drawn from `rng`): the lattice that any scene of
// the anchors and `count` patches more gets at `density`.
Grid::Plan AnchoredPlan(std::mt19937& rng, int count, float sizeLo, float sizeHi, float density);

// Whether two plans have the same bounds and resolution.
::testing::AssertionResult SamePlan(const Grid::Plan& got, const Grid::Plan& want);

// A grid laid out in its own arena and built.
struct BuiltGrid {
  Grid::Plan plan;
  Arena arena{1};
  Grid grid;
};

// At `density` cells per patch, dense cells nested by `nest` (Grid::Nest's
// default, as an environment builds it, unless given).
void BuildGrid(const TestScene& s, float density, BuiltGrid* b, Grid::Nest nest = Grid::Nest());

// No sub-grids: the uniform grid.
inline Grid::Nest UniformNest() {
  Grid::Nest n;
  n.minRefs = 0;
  return n;
}
// Sub-grids in every cell with two references or more, up to 8 cells an
// axis: small test scenes then walk sub-grids on most rays.
inline Grid::Nest DenseNest() {
  Grid::Nest n;
  n.minRefs = 2;
  n.density = 2.0f;
  n.maxRes = 8;
  return n;
}

// Calls visit(refs, header) for every cell that holds patches itself: the
// top cells without a sub-grid and every sub-grid's cells (refs: a RefList).
template <typename Visit>
void ForEachLeafCell(const Grid& g, Visit visit) {
  for (size_t c = 0; c < g.cellCount(); ++c)
    if (!g.SubGridOf(c) && !g.CellRefs(c).empty()) visit(g.CellRefs(c), g.CellPlaneOf(c));
  for (size_t c = 0; c < g.plan().subCells; ++c)
    if (!g.SubCellRefs(c).empty()) visit(g.SubCellRefs(c), g.SubCellPlaneOf(c));
}

// The reference: every patch, the same tie rule (a front side, then the
// lower index: grid.h).
bool BruteIntersect(const TestScene& s, const Ray& ray, uint32_t skip, Hit* hit);

// Compares grid and brute force on one ray (with its skip); also the query
// skipping the brute-force hit itself. Counts the disagreements.
struct Checker {
  const TestScene& scene;
  const Grid& grid;
  int rays = 0;
  int hits = 0;
  int failures = 0;
  uint32_t hint = kNoPatch;

  void Check(const Ray& ray, uint32_t skip, const char* kind);
  void CheckWithSkips(const Ray& ray, const char* kind);
};

glm::vec3 PointOnPatch(std::mt19937& rng, const Patch& p);

// Rays as the solver casts them: a uniform point on a patch, a cosine-
// distributed direction about its normal, tMin = 1e-6 of the scene diagonal,
// skipping the patch itself.
void SolverRays(const TestScene& s, uint32_t seed, int count, std::vector<Ray>* rays,
                std::vector<uint32_t>* from);

// Sends `perKind` rays of each kind through `b` and checks them all.
void CheckRays(const TestScene& s, const BuiltGrid& b, uint32_t seed, int perKind, Checker* ck);

}  // namespace vismask::gridtest
