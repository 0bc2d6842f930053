// Grid throughput, closest-hit and any-hit (disabled: run with
// --gtest_also_run_disabled_tests).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <glm/geometric.hpp>
#include <random>
#include <vector>

#include "grid_test_util.h"
#include "vismask/accel/grid.h"

namespace vismask {
namespace {

using namespace gridtest;

// Closest-hit throughput on 10k random patches (run with
// --gtest_also_run_disabled_tests; prints rays/s).
TEST(GridTest, DISABLED_Throughput) {
  std::mt19937 rng(21);
  TestScene s;
  AddRandomPatches(rng, 10000, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.1f, &s);
  const int kRays = 1000000;
  std::vector<Ray> rays(kRays);
  std::vector<uint32_t> from(kRays);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  for (int i = 0; i < kRays; ++i) {
    uint32_t p = static_cast<uint32_t>(u01(rng) * 10000) % 10000;
    glm::vec3 d = UnitVector(rng);
    if (glm::dot(d, s.patches[p].normal) < 0.0f) d = -d;
    rays[i] = Ray{PointOnPatch(rng, s.patches[p]), d, 1e-5f, kInf};
    from[i] = p;
  }
  for (float density : {1.0f, 2.0f, 4.0f, 8.0f}) {
    BuiltGrid b;
    auto t0 = std::chrono::steady_clock::now();
    BuildGrid(s, density, &b);
    auto t1 = std::chrono::steady_clock::now();
    int hits = 0;
    Hit hit;
    for (int i = 0; i < kRays; ++i) hits += b.grid.Intersect(rays[i], from[i], &hit);
    auto t2 = std::chrono::steady_clock::now();
    int occluded = 0;
    for (int i = 0; i < kRays; ++i) occluded += b.grid.Occluded(rays[i], from[i]);
    auto t3 = std::chrono::steady_clock::now();
    double build = std::chrono::duration<double>(t1 - t0).count();
    double closest = std::chrono::duration<double>(t2 - t1).count();
    double any = std::chrono::duration<double>(t3 - t2).count();
    std::printf(
        "density %.0f: res %dx%dx%d, refs %llu (%.2f/patch), %zu KB, build %.3f s; "
        "closest %.2f Mrays/s (%d hits), occluded %.2f Mrays/s\n",
        density, b.plan.res[0], b.plan.res[1], b.plan.res[2],
        static_cast<unsigned long long>(b.plan.refs), b.plan.refs / 10000.0, b.grid.bytes() / 1024,
        build, kRays / closest / 1e6, hits, kRays / any / 1e6);
    EXPECT_EQ(hits, occluded);
  }
}

// Closest-hit and any-hit throughput on a Cornell box of about 5k patches
// with rays as the solver casts them (run with --gtest_also_run_disabled_tests;
// prints rays/s per density).
TEST(GridTest, DISABLED_CornellThroughput) {
  TestScene s = CornellScene(30);
  std::vector<Ray> rays;
  std::vector<uint32_t> from;
  const int kRays = 1000000;
  SolverRays(s, 59, kRays, &rays, &from);
  for (float density : {1.0f, 2.0f, 4.0f, 8.0f}) {
    BuiltGrid b;
    BuildGrid(s, density, &b);
    int hits = 0, occluded = 0;
    Hit hit;
    auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kRays; ++i) hits += b.grid.Intersect(rays[i], from[i], &hit);
    auto t1 = std::chrono::steady_clock::now();
    for (int i = 0; i < kRays; ++i) occluded += b.grid.Occluded(rays[i], from[i]);
    auto t2 = std::chrono::steady_clock::now();
    double closest = std::chrono::duration<double>(t1 - t0).count();
    double any = std::chrono::duration<double>(t2 - t1).count();
    std::printf(
        "density %.0f: %zu patches, res %dx%dx%d, refs %llu; closest %.2f Mrays/s (%d hits), "
        "occluded %.2f Mrays/s\n",
        density, s.patches.size(), b.plan.res[0], b.plan.res[1], b.plan.res[2],
        static_cast<unsigned long long>(b.plan.refs), kRays / closest / 1e6, hits,
        kRays / any / 1e6);
    EXPECT_EQ(hits, occluded);
  }
}

}  // namespace
}  // namespace vismask
