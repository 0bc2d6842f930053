// Balanced planes: a WorkSplitter puts the planes so that each slab of
// environments holds about the same estimated work.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <map>
#include <string>
#include <vector>

#include "partition_test_util.h"
#include "vismask/solve/partition.h"

namespace vismask {
namespace {

using namespace parttest;

// A WorkSplitter fed `scene`'s polygons in order, weighted by their
// estimated patches at `patchSize`.
WorkSplitter SplitterOf(const Scene& scene, float patchSize) {
  WorkSplitter s;
  for (const Polygon& p : scene.polygons) {
    const int n = static_cast<int>(p.corners.size());
    s.Add(p.corners.data(), n, p.area, EstimatedPatches(p.corners.data(), n, patchSize));
  }
  return s;
}

// The estimated patches of each environment of a partition: each piece's
// own (what the mesher makes of it, cuts included), or its share by area
// of its source polygon's (the weight the splitter balances).
std::vector<double> WorkPerEnv(const Partition& part, float patchSize,
                               const Scene* bySourceArea = nullptr) {
  std::vector<double> work(part.grid.count(), 0.0);
  for (size_t i = 0; i < part.scene.polygons.size(); ++i) {
    const Polygon& p =
        bySourceArea ? bySourceArea->polygons[part.source[i]] : part.scene.polygons[i];
    double w = EstimatedPatches(p.corners.data(), static_cast<int>(p.corners.size()), patchSize);
    if (bySourceArea) w *= part.scene.polygons[i].area / p.area;
    work[part.env[i]] += w;
  }
  return work;
}

double Imbalance(const std::vector<double>& work) {
  double most = 0.0, sum = 0.0;
  for (double w : work) {
    most = std::max(most, w);
    sum += w;
  }
  return most * work.size() / sum;
}

// The weight of each slab of `axis` (the environments sharing a cell
// index on it), and its most over the mean.
double SlabImbalance(const Partition& part, const std::vector<double>& work, int axis) {
  std::vector<double> slab(part.grid.n[axis], 0.0);
  for (int e = 0; e < part.grid.count(); ++e) {
    int c[3];
    part.grid.Cell(e, c);
    slab[c[axis]] += work[e];
  }
  return Imbalance(slab);
}

// The Cornell box's uniform split at x = 278 is lopsided (the tall block
// and the light's side); balanced planes even out every axis's slabs, and
// the grid they make is still a partition with every invariant of a
// uniform one. (The cells of a grid split on several axes are not evened
// out: each axis's planes are shared by every cell, and the weight is not
// separable.)
TEST(PartitionTest, BalancedPlanesEvenOutTheCornellBox) {
  const Scene scene = LoadCornell();
  const float patchSize = 20.0f;
  for (const char* text : {"2", "4x1x2", "2x2x2", "3x3x3"}) {
    SCOPED_TRACE(text);
    EnvGrid uniform = MakeGrid(text, scene.bounds);
    EnvGrid balanced = uniform;
    SplitterOf(scene, patchSize).Planes(&balanced);
    EXPECT_TRUE(balanced.balanced);
    for (int a = 0; a < 3; ++a)
      for (int k = 1; k <= balanced.n[a]; ++k) {
        EXPECT_LT(balanced.Plane(a, k - 1), balanced.Plane(a, k)) << "axis " << a << " plane " << k;
      }
    Partition u, b;
    ASSERT_TRUE(PartitionScene(scene, uniform, &u).ok());
    ASSERT_TRUE(PartitionScene(scene, balanced, &b).ok());
    CheckPartition(scene, balanced, b);
    const std::vector<double> wu = WorkPerEnv(u, patchSize), wb = WorkPerEnv(b, patchSize);
    std::printf("%s: most patches in an environment / mean %.3f uniform, %.3f balanced;", text,
                Imbalance(wu), Imbalance(wb));
    // The slabs by the splitter's own weight: even but for the walls across
    // an axis, which cannot be cut (each side wall of the box is about a
    // quarter of its patches, so 4 slabs on x cannot do better than that).
    const std::vector<double> su = WorkPerEnv(u, patchSize, &scene),
                              sb = WorkPerEnv(b, patchSize, &scene);
    for (int a = 0; a < 3; ++a) {
      if (balanced.n[a] == 1) continue;
      const double before = SlabImbalance(u, su, a), after = SlabImbalance(b, sb, a);
      std::printf(" axis %d slabs %.3f -> %.3f", a, before, after);
      EXPECT_LE(after, before + 0.01) << "axis " << a;
      EXPECT_LT(after, 1.2) << "axis " << a;
    }
    std::printf("\n");
    if (std::string(text) == "2") {
      EXPECT_GT(Imbalance(wu), 1.2);  // the lopsided split the balance removes
      EXPECT_LT(Imbalance(wb), 1.05);
    }
  }
}

// The planes depend only on the polygons and their order: fed twice, the
// same bits; and a splitter is a fixed block (feeding does not grow it).
TEST(PartitionTest, BalancedPlanesAreDeterministic) {
  const Scene scene = LoadCornell();
  EnvGrid a = MakeGrid("4x2x3", scene.bounds), b = a;
  SplitterOf(scene, 10.0f).Planes(&a);
  SplitterOf(scene, 10.0f).Planes(&b);
  for (int axis = 0; axis < 3; ++axis)
    for (int k = 0; k <= a.n[axis]; ++k)
      EXPECT_EQ(a.Plane(axis, k), b.Plane(axis, k)) << axis << " " << k;
  // Another patch size weighs the polygons differently: other planes.
  EnvGrid c = MakeGrid("4x2x3", scene.bounds);
  SplitterOf(scene, 200.0f).Planes(&c);
  bool differ = false;
  for (int axis = 0; axis < 3; ++axis)
    for (int k = 1; k < a.n[axis]; ++k) differ = differ || a.Plane(axis, k) != c.Plane(axis, k);
  EXPECT_TRUE(differ);
}

// Unit squares side by side along x from 0 to 100, fed in an order that
// makes the bins grow both down and up from the first: the quantile planes
// of an even spread are where they should be, to the bins' resolution.
TEST(PartitionTest, BalancedPlanesOfAnEvenSpread) {
  std::vector<Polygon> polys;
  for (int k = 0; k < 100; ++k) {
    int i = (k * 37 + 50) % 100;  // starts in the middle, wanders both ways
    float x = static_cast<float>(i);
    polys.push_back(MakePolygon({{x, 0, 0}, {x + 1, 0, 0}, {x + 1, 1, 0}, {x, 1, 0}}, k + 1));
  }
  const Scene scene = MakeScene(polys);
  EnvGrid grid = MakeGrid("4", scene.bounds);
  WorkSplitter s;
  for (const Polygon& p : scene.polygons) s.Add(p.corners.data(), 4, p.area, 1.0);
  EXPECT_EQ(s.polygons(), 100u);
  EXPECT_DOUBLE_EQ(s.totalWeight(), 100.0);
  s.Planes(&grid);
  for (int k = 1; k < 4; ++k) EXPECT_NEAR(grid.Plane(0, k), 25.0f * k, 0.25f) << k;
  // Axes the scene has no extent on (z) or one polygon spans whole (y)
  // keep what uniform planes they have: one environment each here.
  EXPECT_EQ(grid.Plane(1, 0), 0.0f);
  EXPECT_EQ(grid.Plane(1, 1), 1.0f);
}

// Walls across x (point masses on the axis) cannot be cut: the plane goes
// to the middle of the gap that divides their weight best.
TEST(PartitionTest, BalancedPlaneFallsBetweenWalls) {
  std::vector<Polygon> polys;
  for (float x : {0.0f, 1.0f, 2.0f, 3.0f})
    polys.push_back(MakePolygon({{x, 0, 0}, {x, 1, 0}, {x, 1, 1}, {x, 0, 1}}, 1));
  const Scene scene = MakeScene(polys);
  EnvGrid grid = MakeGrid("2", scene.bounds);
  WorkSplitter s;
  for (const Polygon& p : scene.polygons) s.Add(p.corners.data(), 4, p.area, 1.0);
  s.Planes(&grid);
  EXPECT_NEAR(grid.Plane(0, 1), 1.5f, 0.01f);
  Partition part;
  ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
  CheckPartition(scene, grid, part);
  EXPECT_EQ(std::count(part.env.begin(), part.env.end(), 0u), 2);
}

TEST(PartitionTest, ChooseEnvShapeCutsTheSmallestFaces) {
  int n[3];
  // A long building: cut across its length first.
  ASSERT_TRUE(ChooseEnvShape(4, glm::vec3(40, 3, 10), n));
  EXPECT_EQ(n[0] * n[1] * n[2], 4);
  EXPECT_EQ(n[0], 4);
  // 16 in a wide, low building of two floors: never across the floors.
  ASSERT_TRUE(ChooseEnvShape(16, glm::vec3(16, 6, 16), n));
  EXPECT_EQ(n[1], 1);
  EXPECT_EQ(n[0] * n[2], 16);
  // Flat in y: never split there; a prime above 64 has no grid.
  ASSERT_TRUE(ChooseEnvShape(8, glm::vec3(1, 0, 1), n));
  EXPECT_EQ(n[1], 1);
  EXPECT_FALSE(ChooseEnvShape(67, glm::vec3(1, 1, 1), n));
}

}  // namespace
}  // namespace vismask
