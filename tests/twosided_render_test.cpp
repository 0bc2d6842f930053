// Two-sided renders: miswound walls lit, the ledger closed, emitted power
// doubled by --two-sided-emitters, and the footprint of the twins.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/output/image_io.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::RunMain;
using test::TempDir;

// Mean radiance (channels summed) of image rows [y0, y1) x columns [x0, x1).
double Region(const PfmImage& im, int y0, int y1, int x0, int x1) {
  double sum = 0.0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      for (int c = 0; c < 3; ++c) sum += im.pixels[(size_t(y) * im.width + x) * 3 + c];
  return sum / ((y1 - y0) * (x1 - x0));
}

// scenes/miswound.obj: the Cornell box with the floor, the back wall and the
// green wall wound the wrong way. One-sided they are black; two-sided they
// look as in the correctly wound box.
TEST(TwoSidedTest, MiswoundWallsAreBlackOneSidedAndLitTwoSided) {
  TempDir dir;
  auto render = [&](const std::string& scene, const std::string& name, bool twoSided) {
    std::vector<std::string> args = {"render",         scene,    "--out",         dir.File(name),
                                     "--width",        "64",     "--height",      "64",
                                     "--emitted-rays", "300000", "--stop-unshot", "1e-2",
                                     "--quiet",        "--view", "front"};
    // (--view front: by default the camera would look at the mis-wound box
    // from the side its wrong-way faces front, below.)
    if (twoSided) args.push_back("--two-sided");
    auto r = RunMain(args);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "") << "no warning for these scenes";
    PfmImage im;
    EXPECT_TRUE(ReadPfm(dir.File(name + "/image.pfm"), &im).ok());
    return im;
  };
  PfmImage good = render("scenes/cornell.obj", "cornell", false);
  PfmImage one = render("scenes/miswound.obj", "one", false);
  PfmImage two = render("scenes/miswound.obj", "two", true);
  struct Wall {
    const char* name;
    int y0, y1, x0, x1;
  };
  for (const Wall& w : {Wall{"floor", 58, 62, 26, 34}, Wall{"back wall", 14, 22, 28, 36},
                        Wall{"green wall", 20, 40, 58, 62}}) {
    double ref = Region(good, w.y0, w.y1, w.x0, w.x1);
    ASSERT_GT(ref, 0.01) << w.name;
    EXPECT_LT(Region(one, w.y0, w.y1, w.x0, w.x1), 1e-3 * ref) << w.name << " is lit one-sided";
    EXPECT_NEAR(Region(two, w.y0, w.y1, w.x0, w.x1), ref, 0.1 * ref) << w.name;
  }
  std::string json = ReadFile(dir.File("two/run.json"));
  EXPECT_NE(json.find("\"two_sided\": true"), std::string::npos);
  EXPECT_NE(json.find("\"twin_patches\": "), std::string::npos);
  // A one-sided run.json is as before: no two-sided keys.
  EXPECT_EQ(ReadFile(dir.File("one/run.json")).find("two_sided"), std::string::npos);
}

// run.json's energy triple `key`.
std::vector<double> Triple(const std::string& json, const std::string& key) {
  size_t at = json.find("\"" + key + "\": [");
  std::vector<double> v;
  if (at == std::string::npos) return v;
  const char* p = json.c_str() + json.find('[', at) + 1;
  for (int c = 0; c < 3; ++c) {
    char* end = nullptr;
    v.push_back(std::strtod(p, &end));
    p = end + 1;
  }
  return v;
}

// The ledger closes with both sides receiving and both sides of the light
// emitting, in one environment and across two with Method R (whose ledger
// books its power in flight exactly).
TEST(TwoSidedTest, LedgerClosesTwoSided) {
  TempDir dir;
  for (std::vector<std::string> extra :
       // --round-shots 1: draining to exactly 0 with rounds by work runs for
       // minutes (over a million shots; open issue, see the issue 20 report).
       // Draining to exactly 0 at all is erratic: this scene in two
       // environments drains in 484 000 shots at --emission-rays 0.25 and
       // had not in 2.2 million at 0.125 (the Cornell box in one: the other
       // way round), so the drain keeps the light's share it was measured at.
       {std::vector<std::string>{},
        std::vector<std::string>{"--envs", "2", "--mask-method", "R", "--stop-unshot", "0",
                                 "--max-shots", "100000000", "--round-shots", "1",
                                 "--emission-rays", "0.25"}}) {
    std::vector<std::string> args = {"render",
                                     "scenes/miswound.obj",
                                     "--out",
                                     dir.File("out"),
                                     "--width",
                                     "32",
                                     "--height",
                                     "32",
                                     "--emitted-rays",
                                     "200000",
                                     "--stop-unshot",
                                     "1e-2",
                                     "--quiet",
                                     "--two-sided",
                                     "--two-sided-emitters",
                                     "--max-rays",
                                     "1024"};
    args.insert(args.end(), extra.begin(), extra.end());
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    std::string json = ReadFile(dir.File("out/run.json"));
    std::vector<double> emitted = Triple(json, "emitted"), residual = Triple(json, "residual");
    ASSERT_EQ(residual.size(), 3u);
    for (int c = 0; c < 3; ++c)
      EXPECT_LT(std::fabs(residual[c]), 1e-9 * emitted[c])
          << "channel " << c << ", " << extra.size() << " extra options";
  }
}

// --two-sided-emitters: each side emits Ke, twice the one-sided power; with
// --two-sided alone an emitter's back reflects but does not emit.
TEST(TwoSidedTest, TwoSidedEmittersDoubleTheEmittedPower) {
  TempDir dir;
  auto emitted = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args = {
        "render", "scenes/cornell.obj", "--out", dir.File(name), "--width", "16", "--height",
        "16",     "--max-shots",        "10",    "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    auto r = RunMain(args);
    EXPECT_EQ(r.code, 0) << r.err;
    return Triple(ReadFile(dir.File(name + "/run.json")), "emitted");
  };
  std::vector<double> one = emitted("one", {});
  std::vector<double> both = emitted("both", {"--two-sided-emitters"});
  std::vector<double> all = emitted("all", {"--two-sided", "--two-sided-emitters"});
  std::vector<double> backs = emitted("backs", {"--two-sided"});
  ASSERT_EQ(one.size(), 3u);
  ASSERT_EQ(both.size(), 3u);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(one[c], 0.0);
    EXPECT_DOUBLE_EQ(both[c], 2.0 * one[c]);
    EXPECT_DOUBLE_EQ(all[c], 2.0 * one[c]);
    EXPECT_DOUBLE_EQ(backs[c], one[c]);
  }
}

// footprint shows what the twins cost: patches doubled, and the bytes.
TEST(TwoSidedTest, FootprintShowsTheCost) {
  auto fp = [](std::vector<std::string> extra) {
    std::vector<std::string> args = {"footprint", "scenes/cornell.obj", "--json", "--envs", "2"};
    args.insert(args.end(), extra.begin(), extra.end());
    testing::internal::CaptureStdout();
    auto r = RunMain(args);
    std::string out = testing::internal::GetCapturedStdout();
    EXPECT_EQ(r.code, 0) << r.err;
    return out;
  };
  auto number = [](const std::string& json, const std::string& key) {
    size_t at = json.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key;
    return std::strtoll(json.c_str() + at + key.size() + 4, nullptr, 10);
  };
  std::string one = fp({}), two = fp({"--two-sided"});
  EXPECT_EQ(number(one, "twin_patches"), 0);
  EXPECT_EQ(number(one, "extra_bytes"), 0);
  EXPECT_EQ(number(two, "patches"), 2 * number(two, "one_sided_patches"));
  EXPECT_EQ(number(two, "twin_patches"), number(two, "one_sided_patches"));
  EXPECT_EQ(number(two, "one_sided_total_bytes"), number(one, "total_bytes"));
  EXPECT_GT(number(two, "extra_bytes"), 0);
  EXPECT_EQ(number(two, "total_bytes") - number(two, "one_sided_total_bytes"),
            number(two, "extra_bytes"));
}

}  // namespace
}  // namespace vismask
