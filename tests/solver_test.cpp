// The solver's scheduling rules: the exchange's admission of records
// (AdmittedForwards) and the shot budget of a round (ShotBudget).
#include "vismask/solve/solver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

namespace vismask {
namespace {

TEST(SolverTest, AdmissionNeverOverfillsAQueue) {
  // Simulate: envs create what they are admitted; each env drains at most
  // one record a round. No env may ever have more than `capacity` records
  // still to receive.
  const uint32_t n = 5;
  const uint64_t capacity = 7;
  std::vector<uint64_t> created(n, 0), processed(n, 0);
  std::mt19937 rng(3);
  for (uint64_t round = 0; round < 500; ++round) {
    uint64_t total = 0;
    for (uint64_t c : created) total += c;
    uint64_t maxOut = 0;
    for (uint32_t e = 0; e < n; ++e) maxOut = std::max(maxOut, total - created[e] - processed[e]);
    ASSERT_LE(maxOut, capacity);
    uint64_t admitted = 0;
    for (uint32_t e = 0; e < n; ++e) {
      uint32_t a = AdmittedForwards(round, e, n, capacity, maxOut);
      admitted += a;
      created[e] += rng() % (a + 1);
    }
    EXPECT_EQ(admitted, capacity - maxOut);
    total = 0;
    for (uint64_t c : created) total += c;
    for (uint32_t e = 0; e < n; ++e)
      if (total - created[e] > processed[e] && rng() % 3) ++processed[e];
  }
}

TEST(SolverTest, ShotBudgetHonoursMaxShots) {
  EXPECT_EQ(ShotBudget(3, 4, 5, 0, 0), 5u);
  // 7 shots left over 4 environments: spread, never more than the round's 5.
  uint64_t sum = 0;
  for (uint32_t e = 0; e < 4; ++e) sum += ShotBudget(e, 4, 5, 93, 100);
  EXPECT_EQ(sum, 7u);
  EXPECT_EQ(ShotBudget(0, 4, 5, 93, 100), 2u);
  EXPECT_EQ(ShotBudget(2, 4, 5, 93, 100), 2u);
  EXPECT_EQ(ShotBudget(3, 4, 5, 93, 100), 1u);
  // Fewer left than environments: the first ones, one each (as one shot a
  // round always gave); a whole round's worth: every environment its round.
  EXPECT_EQ(ShotBudget(1, 4, 5, 98, 100), 1u);
  EXPECT_EQ(ShotBudget(2, 4, 5, 98, 100), 0u);
  EXPECT_EQ(ShotBudget(3, 4, 5, 0, 100), 5u);
  // Issue 20: 125 environments, 63-shot rounds, 500 shots: all get 4.
  EXPECT_EQ(ShotBudget(124, 125, 63, 0, 500), 4u);
}

}  // namespace
}  // namespace vismask

namespace vismask {
namespace {

// Issue 40: the progress line's time left. Unshot power falling by e every
// 2 s, from 1 towards --stop-unshot e^-10: 20 s in all.
TEST(SolverTest, TimeLeftFollowsTheUnshotDecayAndTheBounds) {
  SolveOptions o;
  o.stopUnshot = std::exp(-10.0);
  TimeLeft t;
  EXPECT_LT(t.Estimate(o), 0.0);  // nothing yet
  t.Add(0.0, 0, 1.0);
  EXPECT_LT(t.Estimate(o), 0.0);
  for (int s = 2; s <= 8; s += 2) t.Add(s, 100 * s, std::exp(-s / 2.0));
  EXPECT_NEAR(t.Estimate(o), 12.0, 1e-9);  // at 8 s: 12 s to go
  // A bound that comes sooner wins: --max-seconds 10, or --max-shots at
  // 100 shots/s.
  o.maxSeconds = 10.0;
  EXPECT_NEAR(t.Estimate(o), 2.0, 1e-9);
  o.maxSeconds = 0.0;
  o.maxShots = 1300;
  EXPECT_NEAR(t.Estimate(o), 5.0, 1e-9);
  // Unshot power that stops falling: no estimate without a bound.
  o.maxShots = 0;
  TimeLeft flat;
  for (int s = 0; s <= 8; s += 2) flat.Add(s, 100 * s, 0.5);
  EXPECT_LT(flat.Estimate(o), 0.0);
}

}  // namespace
}  // namespace vismask
