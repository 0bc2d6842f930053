// A leaf's corners shown from its quarters' indirect power
// (ElementTree::CornerShift), and a patch's shots continuing one Sobol'
// sequence (RayPoints' first point).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "../src/solve/shot_ray.h"
#include "env_test_util.h"

namespace vismask {
namespace {

// Quarter k of the unit quad takes hits[k] hits of indirect power (p, p, p).
void Fill(ElementTree* tree, const int hits[4], double p) {
  const double power[3] = {p, p, p};
  for (uint32_t k = 0; k < 4; ++k)
    for (int h = 0; h < hits[k]; ++h) tree->AddIndirectHit(0, k, power);
}

// What CornerShift must give, worked out here: alpha = 1 - 4 / chi2 (0
// below), times quarter q's density minus the leaf's, channel 0.
double Expected(const int hits[4], double p, uint32_t q, double* alpha) {
  double total = 0.0, squares = 0.0, chi2 = 0.0;
  for (int k = 0; k < 4; ++k) {
    total += 3.0 * p * hits[k];
    squares += hits[k] * (3.0 * p) * (3.0 * p);
  }
  for (int k = 0; k < 4; ++k) {
    const double d = 3.0 * p * hits[k] - 0.25 * total;
    chi2 += d * d / (0.25 * squares);
  }
  *alpha = chi2 > ElementTree::kCornerDof ? 1.0 - ElementTree::kCornerDof / chi2 : 0.0;
  return *alpha * (p * hits[q] / 0.25 - total / 3.0);
}

TEST(CornerShiftTest, CornersFollowTheirQuartersAsFarAsTheHitsTell) {
  test::UnitQuadTree quad(true);
  ElementTree& tree = quad.tree;
  const Span<const Patch> patches = quad.patches;
  const uint8_t* path = nullptr;
  double alpha = -1.0;
  // Even: nothing to shift.
  tree.Reset(patches);
  const int even[4] = {100, 100, 100, 100};
  Fill(&tree, even, 0.01);
  for (uint32_t q = 0; q < 4; ++q) {
    EXPECT_EQ(tree.CornerShift(patches[0], 0, path, 0, q, &alpha).x, 0.0) << q;
    EXPECT_EQ(alpha, 0.0);
  }
  // A gradient well beyond the noise: each corner moves most of the way to
  // its quarter's density, the bright quarter's up and the others' down.
  tree.Reset(patches);
  const int steep[4] = {100, 300, 100, 100};
  Fill(&tree, steep, 0.01);
  for (uint32_t q = 0; q < 4; ++q) {
    double want = Expected(steep, 0.01, q, &alpha);
    double got = 0.0;
    const glm::dvec3 shift = tree.CornerShift(patches[0], 0, path, 0, q, &got);
    // The quarters are summed in float: 1e-5 of the value.
    EXPECT_NEAR(got, alpha, 1e-6) << q;
    EXPECT_GT(alpha, 0.9);
    EXPECT_NEAR(shift.x, want, 1e-5 * std::fabs(want)) << q;
    EXPECT_NEAR(shift.z, want, 1e-5 * std::fabs(want)) << q;
    EXPECT_TRUE(q == 1 ? shift.x > 0.0 : shift.x < 0.0) << q;
  }
  // A spread within the noise of a few hits: no shift.
  tree.Reset(patches);
  const int few[4] = {3, 5, 4, 4};
  Fill(&tree, few, 0.01);
  Expected(few, 0.01, 1, &alpha);
  ASSERT_EQ(alpha, 0.0) << "the case must be within the noise";
  EXPECT_EQ(tree.CornerShift(patches[0], 0, path, 0, 1, &alpha).x, 0.0);
  // Between: shrunk, not all of the way.
  tree.Reset(patches);
  const int some[4] = {20, 34, 20, 20};
  Fill(&tree, some, 0.01);
  const double want = Expected(some, 0.01, 1, &alpha);
  ASSERT_GT(alpha, 0.1);
  ASSERT_LT(alpha, 0.9);
  double got = 0.0;
  EXPECT_NEAR(tree.CornerShift(patches[0], 0, path, 0, 1, &got).x, want, 1e-5 * want);
  EXPECT_NEAR(got, alpha, 1e-6);
}

TEST(CornerShiftTest, ALaterShotContinuesThePatchsSequence) {
  // Shot 2 of a patch (first = the rays of shot 1) takes the points after
  // shot 1's, walked sequentially as Distribute walks them.
  const uint64_t stream = 0x1234abcdull;
  const uint32_t first = 37, rays = 50;
  RayPoints whole(true, stream), later(true, stream, first);
  std::vector<float> all(5 * (first + rays));
  for (uint32_t r = 0; r < first + rays; ++r) whole.Next(r, &all[5 * r], true);
  for (uint32_t r = 0; r < rays; ++r) {
    float u[5];
    later.Next(r, u, true);
    for (int k = 0; k < 5; ++k) ASSERT_EQ(u[k], all[5 * (first + r) + k]) << r << " " << k;
  }
  // A fresh stream (another shot's key) gives other points.
  RayPoints other(true, stream + 1);
  float u[5];
  other.Next(0, u, true);
  EXPECT_NE(u[3], all[3]);
}

}  // namespace
}  // namespace vismask
