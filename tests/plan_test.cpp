// --max-seconds's plan (plan.h): the patches and emitted rays a budget
// affords, from the timed rate.
#include "vismask/app/plan.h"

#include <gtest/gtest.h>

#include <cmath>

namespace vismask {
namespace {

// About the Cornell box's automatic mesh on a 2-core x86-64.
PlanInput Cornell(double seconds) {
  PlanInput in;
  in.rate = 3.5e6;
  in.rho = 0.5;
  in.patches = 7504;
  in.seconds = seconds;
  in.minRays = 16;
  in.emittedRays = 4000000;
  return in;
}

// Where the tail of small shots would keep the automatic mesh, the balance
// of the indirect part's noise against its discretisation asks for fewer
// patches, as the square root of the rays the budget traces.
TEST(PlanTest, FewerRaysFewerPatchesAsTheSquareRoot) {
  const double p1 = PlannedPatches(Cornell(1.0)), p4 = PlannedPatches(Cornell(0.25));
  ASSERT_GT(p1, 0.0);  // re-meshed, although the tail takes only ~2% of the budget
  EXPECT_LT(p1, 7504 / 1.5);
  EXPECT_NEAR(p4 / p1, 0.5, 1e-9);
}

// Several environments: the tail's rule alone (their cuts' slivers), and
// never more emitted rays than the default (a ray there costs more than
// the timed walk).
TEST(PlanTest, SeveralEnvironmentsKeepTheTailsRuleAlone) {
  PlanInput in = Cornell(1.0);
  in.oneEnvironment = false;
  EXPECT_EQ(PlannedPatches(in), 0.0);
  in.seconds = 0.001;
  EXPECT_NEAR(PlannedPatches(in), PlannedPatches(Cornell(0.001)), 1e-9);
  EXPECT_EQ(PlannedEmittedRays(in), PlannedEmittedRays(Cornell(0.001)));
  in.seconds = 10.0;
  EXPECT_EQ(PlannedEmittedRays(in), 4000000u);
  in.seconds = 1.0;
  const double tail = 2.0 * in.patches * in.minRays / (1.0 - in.rho);
  EXPECT_EQ(PlannedEmittedRays(in),
            static_cast<uint64_t>((0.7 * in.rate * in.seconds - tail) * (1.0 - in.rho)));
}

// Several environments paced (Method R): the tail's rule for the mesh, and
// the emitted rays one environment's plan would fill the budget with.
TEST(PlanTest, SeveralEnvironmentsPacedFillTheBudget) {
  PlanInput in = Cornell(10.0);
  in.oneEnvironment = false;
  in.paced = true;
  EXPECT_EQ(PlannedEmittedRays(in), PlannedEmittedRays(Cornell(10.0)));
  EXPECT_GT(PlannedEmittedRays(in), 4000000u);
  in.seconds = 1.0;
  EXPECT_EQ(PlannedEmittedRays(in), PlannedEmittedRays(Cornell(1.0)));
  EXPECT_EQ(PlannedPatches(in), 0.0);
}

// A long budget keeps the automatic mesh (never more patches than it), and
// its emitted rays grow with T past the default 4e6: the budget is spent.
TEST(PlanTest, ALongBudgetKeepsTheMeshAndSpendsItsTime) {
  EXPECT_EQ(PlannedPatches(Cornell(10.0)), 0.0);
  EXPECT_EQ(PlannedPatches(Cornell(1000.0)), 0.0);
  const uint64_t e10 = PlannedEmittedRays(Cornell(10.0)), e20 = PlannedEmittedRays(Cornell(20.0));
  EXPECT_GT(e10, 4000000u);
  const double tail = 2.0 * 7504 * 16 / 0.5;
  EXPECT_NEAR(static_cast<double>(e20) / 0.5 + tail, 2.0 * (static_cast<double>(e10) / 0.5 + tail),
              4.0);
}

// A budget too short for the mesh's tail: the tail's rule, which is the
// smaller there, makes the plan.
TEST(PlanTest, ATinyBudgetIsPlannedByItsTail) {
  const PlanInput in = Cornell(0.001);
  const double tail = 0.2 * in.rate * in.seconds * (1.0 - in.rho) / (2.0 * in.minRays);
  EXPECT_NEAR(PlannedPatches(in), tail, 1e-9);
}

TEST(PlanTest, EmittedRaysLeaveTheTailItsRays) {
  const PlanInput in = Cornell(1.0);
  const double tail = 2.0 * in.patches * in.minRays / (1.0 - in.rho);
  EXPECT_EQ(PlannedEmittedRays(in),
            static_cast<uint64_t>((0.9 * in.rate * in.seconds - tail) * (1.0 - in.rho)));
  EXPECT_EQ(PlannedEmittedRays(Cornell(1e-6)), 10000u);
}

// --emission-rays F: an emitted ray's worth traces F of it in the emitters'
// own shots and rho / (1 - rho) in the reflected power's, so the plan buys
// more emitted rays for the same rays traced: e(F) (F + rho / (1 - rho))
// is the same for every F.
TEST(PlanTest, EmissionRaysBuyMoreEmittedRaysForTheSameRaysTraced) {
  PlanInput in = Cornell(1.0);
  const double tail = 2.0 * in.patches * in.minRays / (1.0 - in.rho);
  const double traced = 0.9 * in.rate * in.seconds - tail;
  for (double f : {1.0, 0.5, 0.25, 0.1}) {
    in.emissionRays = f;
    const double e = static_cast<double>(PlannedEmittedRays(in));
    EXPECT_NEAR(e * (f + in.rho / (1.0 - in.rho)), traced, 2.0) << f;
  }
  in.emissionRays = 0.25;
  EXPECT_GT(PlannedEmittedRays(in), PlannedEmittedRays(Cornell(1.0)) * 3 / 2);
}

}  // namespace
}  // namespace vismask
