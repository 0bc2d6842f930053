// The fast members of the stiff and extreme suites (docs/STABILITY.md; the
// whole suites are `make stability`): renders through the command line whose
// outputs must hold no NaN, Inf or negative radiosity, whose energy ledger
// must close, and which reach the analytic radiosity of a closed box within
// the error they state.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include "env_test_util.h"
#include "test_util.h"
#include "vismask/parallel/transport.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/partition.h"
#include "vismask/solve/solver.h"

namespace vismask {
namespace {

using test::FileExists;
using test::ReadCsv;
using test::ReadFile;
using test::RunMain;
using test::TempDir;

// A number from run.json: the first "key": value (or the first element of
// an array value).
double JsonNumber(const std::string& json, const std::string& key, int index = 0) {
  size_t at = json.find("\"" + key + "\": ");
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return NAN;
  at += key.size() + 4;
  if (json[at] == '[') {
    ++at;
    for (int k = 0; k < index; ++k) at = json.find(',', at) + 1;
  }
  return std::strtod(json.c_str() + at, nullptr);
}

struct Checked {
  int badB = 0;           // non-finite or negative b in patches.csv
  int badPixels = 0;      // non-finite or negative values in image.pfm
  double ledger = 0;      // max over channels of |emitted - absorbed - escaped - unshot| / emitted
  double escaped = 0;     // escaped / emitted, channel 0
  std::vector<double> b;  // channel 0 of each patch
  std::string json;
};

Checked Check(const std::string& out) {
  Checked c;
  auto rows = ReadCsv(out + "/patches.csv");
  EXPECT_GT(rows.size(), 1u);
  for (size_t i = 1; i < rows.size(); ++i) {
    for (int k = 15; k < 18; ++k) {
      double v = std::strtod(rows[i][k].c_str(), nullptr);
      if (!std::isfinite(v) || v < 0.0) ++c.badB;
    }
    c.b.push_back(std::strtod(rows[i][15].c_str(), nullptr));
  }
  std::string pfm = ReadFile(out + "/image.pfm");
  std::istringstream head(pfm);
  std::string magic;
  int w = 0, h = 0;
  double scale = 0;
  head >> magic >> w >> h >> scale;
  size_t data = pfm.size() - size_t(w) * h * 12;
  EXPECT_EQ(magic, "PF");
  for (size_t i = 0; i < size_t(w) * h * 3; ++i) {
    float v;
    std::memcpy(&v, pfm.data() + data + 4 * i, 4);
    if (!std::isfinite(v) || v < 0.0f) ++c.badPixels;
  }
  c.json = ReadFile(out + "/run.json");
  for (int ch = 0; ch < 3; ++ch) {
    double em = JsonNumber(c.json, "emitted", ch);
    double res = em - JsonNumber(c.json, "absorbed", ch) - JsonNumber(c.json, "escaped", ch) -
                 JsonNumber(c.json, "unshot", ch);
    c.ledger = std::fmax(c.ledger, std::fabs(res) / em);
  }
  c.escaped = JsonNumber(c.json, "escaped", 0) / JsonNumber(c.json, "emitted", 0);
  return c;
}

std::vector<std::string> Small() {
  return {"--width", "32", "--height", "32", "--quiet"};
}

std::vector<std::string> Args(std::vector<std::string> a, const std::vector<std::string>& more) {
  a.insert(a.end(), more.begin(), more.end());
  return a;
}

// rho = 0.999, uniform emission E = 1: b must reach E/(1-rho) within the
// error run.json states, in a few thousand shots, with a stop rule that
// knows the amplification; the closed box leaks nothing.
TEST(StabilityTest, StiffBoxReachesAnalyticWithinStatedError) {
  TempDir dir;
  const double exact = 1.0 / (1.0 - static_cast<double>(0.999f));
  auto r = RunMain(Args(
      {"render", "scenes/stiff/box-rho0.999.obj", "--out", dir.File("on"), "--patch-size", "0.34",
       "--rays", "1024", "--correct-unshot", "on", "--stop-error", "5e-4", "--max-shots", "100000"},
      Small()));
  ASSERT_EQ(r.code, 0) << r.err;
  Checked c = Check(dir.File("on"));
  EXPECT_EQ(c.badB + c.badPixels, 0);
  EXPECT_LT(c.ledger, 1e-9);
  EXPECT_EQ(c.escaped, 0.0) << "rays left a closed box";
  ASSERT_EQ(c.b.size(), 54u);
  double sum2 = 0.0;
  for (double b : c.b) sum2 += (b - exact) * (b - exact) / (exact * exact);
  double rms = std::sqrt(sum2 / c.b.size());
  double stated = JsonNumber(c.json, "stated_error");
  EXPECT_GT(stated, 0.0);
  EXPECT_LE(rms, stated) << "RMS relative error against E/(1-rho)";
  EXPECT_LT(stated, 2e-3);
  EXPECT_NE(c.json.find("\"stop_reason\": \"converged\""), std::string::npos);
  EXPECT_LT(JsonNumber(c.json, "bias_estimate"), 5e-4);
}

// --correct-unshot off writes the same solve's b minus kd * ambient: the
// option changes the output, not the solve. Without the correction,
// --stop-error holds b to its bias estimate (rho = 0.9).
TEST(StabilityTest, StopErrorBoundsTheUncorrectedBias) {
  TempDir dir;
  const double exact = 1.0 / (1.0 - static_cast<double>(0.9f));
  std::vector<std::string> base = {
      "render", "scenes/stiff/box-rho0.9.obj", "--patch-size", "0.34", "--rays", "1024"};
  for (const char* mode : {"off", "on"}) {
    auto r = RunMain(Args(
        base,
        Args({"--out", dir.File(mode), "--correct-unshot", mode, "--max-shots", "300"}, Small())));
    ASSERT_EQ(r.code, 0) << r.err;
  }
  Checked off = Check(dir.File("off")), on = Check(dir.File("on"));
  double ambient = JsonNumber(off.json, "ambient", 0);
  EXPECT_GT(ambient, 0.0);
  EXPECT_EQ(ambient, JsonNumber(on.json, "ambient", 0));
  ASSERT_EQ(off.b.size(), on.b.size());
  for (size_t i = 0; i < off.b.size(); ++i)
    EXPECT_NEAR(on.b[i], off.b[i] + static_cast<double>(0.9f) * ambient, 1e-12 * exact) << i;

  auto r = RunMain(Args(base, Args({"--out", dir.File("stop"), "--stop-error", "0.02"}, Small())));
  ASSERT_EQ(r.code, 0) << r.err;
  Checked stop = Check(dir.File("stop"));
  double mean = 0.0;
  for (double b : stop.b) mean += (b - exact) / exact / stop.b.size();
  // The uncorrected b is low by about the estimated bias, and within it.
  double bias = JsonNumber(stop.json, "bias_estimate");
  EXPECT_LT(bias, 0.02);
  EXPECT_GT(bias, 0.01);  // stopped as soon as it was below, not much later
  EXPECT_LT(mean, 0.0);
  EXPECT_LE(-mean, bias + JsonNumber(stop.json, "mc_relative_error"));
}

// The area-weighted mean of channel 0 of patches.csv's b, relative to `exact`, minus 1.
double MeanRelativeError(const std::string& out, double exact) {
  auto rows = ReadCsv(out + "/patches.csv");
  double bArea = 0.0, area = 0.0;
  for (size_t i = 1; i < rows.size(); ++i) {
    double a = std::strtod(rows[i][8].c_str(), nullptr);
    bArea += std::strtod(rows[i][15].c_str(), nullptr) * a;
    area += a;
  }
  return bArea / area / exact - 1.0;
}

// In the closed stiff box split 2x2x2, every watt not yet delivered is
// either unshot on a patch or in flight between environments. Method R
// books its flight exactly, so the ambient term (in b with
// --correct-unshot on) makes the area-weighted mean of b exactly E/(1-rho)
// at any moment, however much is in flight (here most of the power); and
// the power counted as unshot or in flight never exceeds what was emitted
// (a shooter queued in three environments counts once). Method B's masks
// lose power: the mean falls short by the loss the solver states, once
// foreign shooters have shot. Rounds of 8 shots, so that they have within
// the 300 shots: the default rounds make all 300 in one round of local
// shots, and then B's flight estimate (FlightShare, a share per receiver)
// counts more than was sent, by about the loss (mean +0.31% here, stated
// loss 0.31%: LossEstimate states its size, not its sign).
TEST(StabilityTest, AmbientCountsThePowerInFlight) {
  TempDir dir;
  const double exact = 1.0 / (1.0 - static_cast<double>(0.99f));
  for (const char* method : {"R", "B"}) {
    std::string out = dir.File(method);
    auto r = RunMain(Args({"render",
                           "scenes/stiff/box-rho0.99.obj",
                           "--out",
                           out,
                           "--patch-size",
                           "0.34",
                           "--rays",
                           "1024",
                           "--envs",
                           "2x2x2",
                           "--mask-method",
                           method,
                           "--mask-res",
                           "20",
                           "--max-shots",
                           "300",
                           "--correct-unshot",
                           "on",
                           "--round-shots",
                           "8"},
                          Small()));
    ASSERT_EQ(r.code, 0) << r.err;
    std::string json = ReadFile(out + "/run.json");
    double unshot = JsonNumber(json, "unshot_fraction");
    EXPECT_GT(unshot, 0.9) << method << ": most of the power is still to deliver";
    EXPECT_LE(unshot, 1.0) << method << ": power counted in several environments";
    EXPECT_GT(JsonNumber(json, "foreign_shots"), 0.0) << method;
    double mean = MeanRelativeError(out, exact);
    double loss = JsonNumber(json, "loss_estimate");
    if (std::string(method) == "R") {
      EXPECT_NEAR(mean, 0.0, 1e-9) << "the ambient term misses power in flight";
      EXPECT_LT(loss, 1e-9);
    } else {
      EXPECT_LT(mean, -1e-3) << "B's masks lose power";
      EXPECT_NEAR(-mean, loss, 1e-6) << "the stated loss is the shortfall";
    }
  }
}

// 2x2x2 Method R at rho = 0.99, stopped by --stop-error with the ambient
// correction: b is within the error run.json states (it was 32% low, with
// 0.8% stated, while the ambient term left out the power in flight).
TEST(StabilityTest, SplitStiffBoxMethodRWithinStatedError) {
  TempDir dir;
  const double exact = 1.0 / (1.0 - static_cast<double>(0.99f));
  auto r = RunMain(
      Args({"render", "scenes/stiff/box-rho0.99.obj", "--out", dir.File("r"), "--patch-size",
            "0.34", "--rays", "1024", "--envs", "2x2x2", "--mask-method", "R", "--correct-unshot",
            "on", "--stop-error", "0.008", "--max-shots", "100000"},
           Small()));
  ASSERT_EQ(r.code, 0) << r.err;
  Checked c = Check(dir.File("r"));
  EXPECT_EQ(c.badB + c.badPixels, 0);
  EXPECT_NE(c.json.find("\"stop_reason\": \"converged\""), std::string::npos);
  double sum2 = 0.0;
  for (double b : c.b) sum2 += (b - exact) * (b - exact) / (exact * exact);
  double rms = std::sqrt(sum2 / c.b.size());
  double stated = JsonNumber(c.json, "stated_error");
  EXPECT_LE(rms, stated) << "RMS relative error against E/(1-rho)";
  EXPECT_LT(stated, 0.01);
}

// With more environments than queue slots (--queue 64: the default would
// give each a round's worth), some rounds admit no new record
// in the environment that holds the light (issue 17): such a round shoots
// nothing, and that is not convergence while power is left.
TEST(StabilityTest, IdleRoundsAreNotConvergence) {
  TempDir dir;
  auto r = RunMain(Args({"render", "scenes/cornell.obj", "--out", dir.File("c"), "--envs", "5x5x5",
                         "--rays", "64", "--max-shots", "500", "--queue", "64"},
                        Small()));
  ASSERT_EQ(r.code, 0) << r.err;
  std::string json = ReadFile(dir.File("c") + "/run.json");
  EXPECT_NE(json.find("\"stop_reason\": \"max-shots\""), std::string::npos) << json;
  EXPECT_GT(JsonNumber(json, "shots"), 400.0);
}

// A solve whose queues have no slot admits no record, so no environment
// with a neighbour can ever shoot while all the power is unshot: a stall,
// reported after a whole rotation of rounds (two here), never convergence.
// (--queue refuses 0, so this drives Solve directly.)
TEST(StabilityTest, ASolveThatCannotShootStalls) {
  EnvGrid grid;
  grid.n[0] = 2;
  EnvOptions eo;
  eo.rays = 64;
  eo.queueCapacity = 0;
  test::TestEnvs envs;
  test::MakeTestEnvs("scenes/stiff/box-rho0.5.obj", grid, 0.34f, eo, &envs);
  if (HasFatalFailure()) return;
  Status error;
  std::unique_ptr<Transport> loop = MakeTransport(TransportRequest{"loop", 1}, &error);
  ASSERT_TRUE(loop) << error.ToString();
  RankEnvs rankEnvs = EnvsOfRank(2, 1, 0);
  Arena arena(1 << 16);
  ExchangeBuffers buffers;
  buffers.Layout(arena, rankEnvs, 1, envs.ptrs[0]->packetBytes(), 0, 6 * 256);
  SolveOptions so;
  so.queueCapacity = 0;
  so.quiet = true;
  SolveResult res = Solve(envs.span(), rankEnvs, loop.get(), &buffers, so, nullptr);
  EXPECT_EQ(StopReasonName(res.reason), std::string("stalled"));
  EXPECT_EQ(res.shots, 0u);
  EXPECT_EQ(res.rounds, 2u);
  EXPECT_NEAR(res.unshotFraction, 1.0, 1e-12);
  loop->Finish(0);
}

struct ExtremeCase {
  const char* name;
  std::vector<std::string> args;
};

TEST(StabilityTest, ExtremeCasesStayFiniteAndBalanced) {
  TempDir dir;
  const std::vector<std::string> few = {"--rays", "256", "--max-shots", "300"};
  const ExtremeCase cases[] = {
      {"scale1e-3", Args({"scenes/extreme/cornell-scale1e-3.obj"}, few)},
      {"scale1e6", Args({"scenes/extreme/cornell-scale1e6.obj"}, few)},
      {"ke1e-6", Args({"scenes/extreme/cornell-ke1e-6.obj"}, few)},
      {"ke1e30", Args({"scenes/extreme/cornell-ke1e30.obj"}, few)},
      {"sliver", Args({"scenes/extreme/sliver.obj"}, few)},
      {"grazing", Args({"scenes/extreme/grazing.obj"}, few)},
      {"one-patch", Args({"scenes/extreme/one-patch.obj", "--patch-size", "2"}, few)},
      {"one-ray", {"scenes/cornell.obj", "--rays", "1", "--max-shots", "3000"}},
      {"on-plane", Args({"scenes/extreme/cornell-on-plane.obj", "--envs", "2"}, few)},
      {"mask-r1", Args({"scenes/cornell.obj", "--envs", "2", "--mask-res", "1"}, few)},
  };
  for (const ExtremeCase& c : cases) {
    std::vector<std::string> args = Args({"render", "--out", dir.File(c.name)}, c.args);
    auto r = RunMain(Args(args, Small()));
    ASSERT_EQ(r.code, 0) << c.name << ": " << r.err;
    Checked k = Check(dir.File(c.name));
    EXPECT_EQ(k.badB, 0) << c.name;
    EXPECT_EQ(k.badPixels, 0) << c.name;
    bool single = k.json.find("\"environments\": 1,") != std::string::npos;
    if (single) {
      EXPECT_LT(k.ledger, 1e-9) << c.name;
    }
  }
}

// Scales and a move the radiosity is invariant to give the same image
// (the move to within float's steps there: 1/16 on a 559 box).
TEST(StabilityTest, ScaledCornellBoxesGiveTheSameImage) {
  TempDir dir;
  std::vector<std::string> tail = {"--rays", "256", "--max-shots", "200"};
  for (const char* s : {"cornell", "extreme/cornell-scale1e-3", "extreme/cornell-scale1e6",
                        "extreme/cornell-moved1e6"}) {
    std::string out = dir.File(std::string(s).substr(std::string(s).rfind('/') + 1));
    auto r = RunMain(
        Args(Args({"render", std::string("scenes/") + s + ".obj", "--out", out}, tail), Small()));
    ASSERT_EQ(r.code, 0) << r.err;
  }
  for (const char* s : {"cornell-scale1e-3", "cornell-scale1e6", "cornell-moved1e6"}) {
    testing::internal::CaptureStdout();
    auto r = RunMain({"compare", dir.File(s) + "/image.pfm", dir.File("cornell") + "/image.pfm"});
    std::string out = testing::internal::GetCapturedStdout();
    ASSERT_EQ(r.code, 0);
    double rmse = std::strtod(out.c_str() + out.find(' ') + 1, nullptr);
    EXPECT_LT(rmse, 0.02) << s << ": " << out;
  }
}

TEST(StabilityTest, UnsolvableRangesAreRefusedAtInit) {
  TempDir dir;
  const char* scenes[] = {"cornell-ke3e38", "cornell-ke1e-32", "cornell-scale1e13",
                          "cornell-scale1e-18", "cornell-moved3e6"};
  for (const char* s : scenes) {
    std::string path = std::string("scenes/extreme/") + s + ".obj";
    auto r = RunMain({"render", path, "--out", dir.File(s), "--quiet"});
    EXPECT_EQ(r.code, 2) << s;
    EXPECT_EQ(r.err.rfind(path + ":", 0), 0u) << r.err;
    EXPECT_FALSE(FileExists(dir.File(s))) << s;
  }
}

}  // namespace
}  // namespace vismask

namespace vismask {
namespace {

// With kd 1 on every face the kd-mean bounds nothing: the measured loss per
// unit shot stands in, and with none yet there is no estimate (no ambient
// term, bias 1) rather than an infinite one (issue 16).
TEST(StabilityTest, PerfectReflectorsUseTheMeasuredLoss) {
  EXPECT_EQ(EffectiveReflectance(0.5, 10.0, 2.0, 42.0), 0.5);  // kd below 1: as before
  EXPECT_DOUBLE_EQ(EffectiveReflectance(1.0, 10.0, 2.0, 42.0), 1.0 - 8.0 / 40.0);
  EXPECT_EQ(EffectiveReflectance(1.0, 10.0, 10.0, 10.0), 1.0);  // nothing shot yet
  AmbientReport r{};
  r.area = 2.0;
  for (int c = 0; c < 3; ++c) {
    r.unshot[c] = 2.0;
    r.kdArea[c] = c == 0 ? 2.0 : 1.0;  // channel 0: kd 1 everywhere
    r.emitted[c] = 10.0;
    r.radiosity[c] = 42.0;
  }
  double ambient[3];
  AmbientTerm(Span<const AmbientReport>(&r, 1), ambient);
  EXPECT_DOUBLE_EQ(ambient[0], 2.0 / 2.0 / (8.0 / 40.0));
  EXPECT_DOUBLE_EQ(ambient[1], 2.0 / 2.0 / 0.5);
  r.unshot[0] = 10.0;  // all still unshot: no estimate
  AmbientTerm(Span<const AmbientReport>(&r, 1), ambient);
  EXPECT_EQ(ambient[0], 0.0);
  RoundTotals t;
  t.area = 2.0;
  t.kdArea = 2.0;
  t.emitted = 10.0;
  t.unshot = 10.0;
  t.radiosity = 10.0;
  EXPECT_EQ(BiasEstimate(t, false), 1.0);
  EXPECT_EQ(LossEstimate(t), 1.0);
  t.unshot = 2.0;
  t.radiosity = 42.0;
  EXPECT_TRUE(std::isfinite(BiasEstimate(t, true)));
  EXPECT_LT(BiasEstimate(t, false), 1.0);
}

}  // namespace
}  // namespace vismask
