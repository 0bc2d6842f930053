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

// A planned --max-seconds run in one environment, or in several under
// Method R, is paced and says so in run.json; given --emitted-rays, or
// under Method B, whose time goes to its masks, it is not.
TEST(PaceTest, APlannedRunInOneEnvironmentOrUnderMethodRIsPaced) {
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
  EXPECT_EQ(json("--envs 2 --mask-method B").find("emitted_rays_paced"), std::string::npos);
}

}  // namespace
}  // namespace vismask
