// --max-seconds's pacing (pace.h): the ray worth left, the quantum that
// spends it, a re-plan on an environment, and where a run is paced.
#include "vismask/solve/pace.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "env_test_util.h"
#include "test_util.h"

namespace vismask {
namespace {

// Before the first shot the worth left is what the plan counts an emitted
// ray's worth to trace: the emission at its share F, then what it reflects
// at rho, all shot.
TEST(PaceTest, TheWorthAtTheStartIsWhatThePlanTraces) {
  const double emitted = 1000.0, f = 0.25, rho = 0.6;
  EXPECT_NEAR(Pacer::WorthLeft(emitted, emitted, f, rho, 0.0) / emitted, f + rho / (1.0 - rho),
              1e-12);
  // Reflected power left: all of it shot, and what it reflects; the part
  // below the stop is never shot.
  EXPECT_NEAR(Pacer::WorthLeft(100.0, 0.0, f, rho, 0.0), 100.0 / (1.0 - rho), 1e-9);
  EXPECT_NEAR(Pacer::WorthLeft(100.0, 0.0, f, rho, 10.0), 90.0 / (1.0 - rho), 1e-9);
  EXPECT_EQ(Pacer::WorthLeft(5.0, 0.0, f, rho, 10.0), 0.0);
  // The quantum spends the worth at the rate in the time: worth / rays.
  EXPECT_NEAR(Pacer::Quantum(2.0e6, 1.0e6, 0.5), 4.0, 1e-12);
  EXPECT_EQ(Pacer::Quantum(1.0, 0.0, 1.0), 0.0);
  EXPECT_EQ(Pacer::Quantum(1.0, 1.0, 0.0), 0.0);
}

class PacerOnAnEnvironment : public ::testing::Test {
 protected:
  void SetUp() override {
    EnvOptions eo;
    eo.rayQuantum = 1.0;
    test::MakeTestEnvs("scenes/cornell.obj", EnvGrid{}, 90.0f, eo, &envs_);
    ASSERT_EQ(envs_.ptrs.size(), 1u);
    env_ = envs_.ptrs[0];
  }
  // Totals after `seconds` and `rays`: 1000 emitted, 1000 shot, 250 of it
  // reflected and unshot (the shots' reflectance 0.25; no emission left).
  static RoundTotals Totals(double seconds, uint64_t rays) {
    RoundTotals t;
    t.elapsed = seconds;
    t.rays = rays;
    t.emitted = 1000.0;
    t.unshot = 250.0;
    t.radiosity = 1250.0;
    return t;
  }
  Span<Environment* const> envs() const {
    return Span<Environment* const>(envs_.ptrs.data(), envs_.ptrs.size());
  }
  test::TestEnvs envs_;
  Environment* env_ = nullptr;
};

TEST_F(PacerOnAnEnvironment, ASlowSolveCoarsensItsQuantumAndAFastOneRefinesIt) {
  PaceInput in;
  in.endSeconds = 1.0;
  in.stopUnshot = 0.0;
  // Within the first interval (1/64 of the end): nothing yet.
  Pacer pacer(in);
  pacer.AfterRound(Totals(0.01, 10000), envs());
  EXPECT_EQ(env_->rayQuantum(), 1.0);
  EXPECT_EQ(pacer.updates(), 0u);
  // At 0.5 s, 1e6 rays traced (2e6 a second): the worth left, 250 / 0.75,
  // in the 0.5 s left asks for a quantum of 1/3000, but a re-plan moves it
  // by at most half.
  pacer.AfterRound(Totals(0.5, 1000000), envs());
  const double worth = 250.0 / 0.75, rays = 2.0e6 * 0.5;
  EXPECT_NEAR(env_->rayQuantum(), 1.0 / 2.0, 1e-12) << "clamped to half the quantum";
  EXPECT_EQ(pacer.updates(), 1u);
  // The next interval, far slower: the quantum the time left affords.
  env_->SetRayQuantum(worth / rays);
  pacer.AfterRound(Totals(0.6, 1010000), envs());
  const double rate = 0.5 * 2.0e6 + 0.5 * 1.0e5;  // the recent intervals' rays a second
  EXPECT_NEAR(env_->rayQuantum(), std::fmin(worth / (rate * 0.4), 2.0 * worth / rays), 1e-12);
  EXPECT_GT(env_->rayQuantum(), worth / rays);
}

TEST_F(PacerOnAnEnvironment, TheTailIsPaidFirstAndNearTheEndTheQuantumStays) {
  PaceInput in;
  in.endSeconds = 1.0;
  in.stopUnshot = 0.0;
  in.tailRays = 0.3e6;  // 0.3 s at 1e6 rays a second
  Pacer pacer(in);
  env_->SetRayQuantum(0.001);
  pacer.AfterRound(Totals(0.5, 500000), envs());
  // Of the 0.5 s left the tail takes 0.3: the worth's rays in 0.2 s.
  EXPECT_NEAR(env_->rayQuantum(), std::fmin(250.0 / 0.75 / (1.0e6 * 0.2), 0.002), 1e-15);
  const double q = env_->rayQuantum();
  pacer.AfterRound(Totals(0.69, 690000), envs());
  EXPECT_EQ(env_->rayQuantum(), q) << "the tail takes all the time left";
  EXPECT_EQ(pacer.updates(), 1u);
}

// The shots a solve with shot costs still makes: the plan's local shots,
// each with as many foreign ones as the shots made so far have had, less
// those made; or the shots a tenfold fall has taken, for each fall still
// to come; whichever is more.
TEST(PaceTest, TheShotsLeftAreThePlansOrTheFallsToComeWhicheverIsMore) {
  // 1000 shots made, 750 of them foreign: a local shot leads to 4 in all.
  EXPECT_NEAR(Pacer::ShotsLeft(10000.0, 1000, 750, 0.0, 100.0, 1.0), 40000.0 - 1000.0, 1e-9);
  // None made yet: the plan's.
  EXPECT_NEAR(Pacer::ShotsLeft(10000.0, 0, 0, 0.0, 100.0, 1.0), 10000.0, 1e-9);
  // Two tenfold falls to come at 30 000 shots each.
  EXPECT_NEAR(Pacer::ShotsLeft(10000.0, 1000, 750, 30000.0, 100.0, 1.0), 60000.0, 1e-6);
  // Past the plan, and at the stop: none.
  EXPECT_EQ(Pacer::ShotsLeft(100.0, 1000, 0, 30000.0, 1.0, 1.0), 0.0);
}

// With shot costs (several environments, Methods A-C) the time the shots
// still to make take beside their rays is paid first, at the work a shot
// has cost (its least over an interval) over the work a second; the rays'
// rate is the work a second over the work a ray costs. Shots that leave
// no time coarsen the quantum as fast as it may (1.25 a re-plan); while
// the emission is still to shoot it never refines.
TEST_F(PacerOnAnEnvironment, WithShotCostsTheShotsLeftArePaidFirst) {
  PaceInput in;
  in.endSeconds = 1.0;
  in.stopUnshot = 0.001;  // 1 of the 1000 emitted
  in.shotCosts = true;
  // At 0.5 s: 1e8 work (2e8 a second), 1e6 rays, 1000 shots from 1000
  // unshot to 250 (1000 / log10(4) shots a tenfold fall), shotWork a shot.
  auto totals = [](double shotWork, double emission) {
    RoundTotals t = Totals(0.5, 1000000);
    t.paceWork = 100000000;
    t.shotWork = static_cast<uint64_t>(1000.0 * shotWork);
    t.shots = 1000;
    t.emission = emission;
    return t;
  };
  const double perDecade = 1000.0 / std::log10(4.0), shotsLeft = perDecade * std::log10(250.0);
  const double worth = (250.0 - 1.0) / 0.75;
  {
    // 1e4 work a shot: the shots left take 0.2 s of the 0.5; a ray costs
    // (1e8 - 1e7) / 1e6 = 90, so 2e8 / 90 rays a second in the 0.3 s left.
    const double shotSeconds = shotsLeft * 1.0e4 / 2.0e8;
    const double want = worth / (2.0e8 / 90.0 * (0.5 - shotSeconds));
    env_->SetRayQuantum(1.1 * want);
    Pacer pacer(in);
    pacer.AfterRound(totals(1.0e4, 0.0), envs());
    EXPECT_NEAR(env_->rayQuantum(), want, 1e-9 * want);
    // A pace by rays alone would have spent the 0.5 s on rays.
    EXPECT_GT(env_->rayQuantum(), 1.5 * worth / (2.0e8 / 90.0 * 0.5));
  }
  {
    // 5e4 work a shot: the shots left take all the time left.
    env_->SetRayQuantum(0.01);
    Pacer pacer(in);
    pacer.AfterRound(totals(5.0e4, 0.0), envs());
    EXPECT_NEAR(env_->rayQuantum(), 0.0125, 1e-15) << "behind: coarsened as fast as it may";
  }
  {
    // Cheap shots and 10% of the emission still to shoot: the pace would
    // refine a coarse quantum, but keeps it.
    env_->SetRayQuantum(1.0);
    Pacer pacer(in);
    pacer.AfterRound(totals(1.0e4, 100.0), envs());
    EXPECT_EQ(env_->rayQuantum(), 1.0);
    env_->SetRayQuantum(1.0);
    Pacer refines(in);
    refines.AfterRound(totals(1.0e4, 0.0), envs());
    EXPECT_NEAR(env_->rayQuantum(), 0.8, 1e-12) << "without emission left it refines";
  }
}

// The round reports' emission not yet shot (EnvSums::emission) is kept
// as the shots book it, not summed over the patches each round (a
// one-environment solve's rounds are one shot each: the sum over 7 500
// patches a round took the default Cornell solve from 1.7 to 2.5 s); it
// stays the sum's, within rounding, and is the sum exactly at a reset.
TEST(PaceTest, TheReportedEmissionIsTheSumOverThePatches) {
  EnvOptions eo;
  eo.rayQuantum = 50.0;  // a lamp patch's shot whole in ~140 rays
  eo.directSamples = 4;
  eo.emissionRays = 0.25;
  test::TestEnvs envs;
  test::MakeTestEnvs("scenes/cornell.obj", EnvGrid{}, 90.0f, eo, &envs);
  ASSERT_EQ(envs.ptrs.size(), 1u);
  Environment* env = envs.ptrs[0];
  double sum[3], left[3];
  env->EmissionUnshot(sum);
  env->EmissionLeft(left);
  ASSERT_GT(sum[0], 0.0);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(left[c], sum[c]) << c;
  const double emitted = sum[0];
  for (int round = 0; round < 40; ++round) {
    env->RunRound(1, 0);
    env->EmissionUnshot(sum);
    env->EmissionLeft(left);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(left[c], sum[c], 1e-12 * emitted) << round << " " << c;
  }
  EXPECT_LT(sum[0], 0.5 * emitted) << "the lamp has shot";
}

// A planned --max-seconds run, in one environment or several, under any
// method, is paced and says so in run.json; given --emitted-rays, or
// with --checkpoint, it is not.
TEST(PaceTest, APlannedRunIsPacedUnlessGivenItsRaysOrCheckpointed) {
  test::TempDir dir;
  auto json = [&](const std::string& extra) {
    std::vector<std::string> args = {
        "render",  "scenes/cornell.obj", "--out", dir.path(), "--width", "16", "--height", "16",
        "--quiet", "--max-seconds",      "0.3"};
    for (const std::string& w : test::Words(extra)) args.push_back(w);
    test::RunResult r = test::RunMain(args);
    EXPECT_EQ(r.code, 0) << r.err;
    return test::ReadFile(dir.File("run.json"));
  };
  EXPECT_GT(test::JsonNumber(json(""), "emitted_rays_paced", "options"), 10000);
  EXPECT_EQ(json("--emitted-rays 300000").find("emitted_rays_paced"), std::string::npos);
  EXPECT_GT(test::JsonNumber(json("--envs 2"), "emitted_rays_paced", "options"), 10000);
  // (At 0.3 s Method B's shots take all of it: its quantum coarsens to the end.)
  EXPECT_GT(test::JsonNumber(json("--envs 2 --mask-method B"), "emitted_rays_paced", "options"), 0);
  test::TempDir ckpt;
  EXPECT_EQ(json("--envs 2 --checkpoint " + ckpt.path()).find("emitted_rays_paced"),
            std::string::npos);
}

}  // namespace
}  // namespace vismask
