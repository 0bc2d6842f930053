// End-to-end renders through the command line: the closed-box analytic
// solution, determinism, the outputs' formats and the energy ledger.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "render_test_util.h"
#include "test_util.h"
#include "vismask/solve/packet.h"

namespace vismask {
namespace {

using namespace test;

TEST(RenderTest, ClosedBoxConvergesToAnalyticRadiosity) {
  TempDir dir;
  const double rho = 0.5, e = 2.0, exact = e / (1.0 - rho);
  WriteClosedBox(dir.path(), 1.0, rho, e);
  auto r = RunMain({"render", dir.File("box.obj"), "--out", dir.File("out"), "--patch-size", "0.34",
                    "--rays", "50000", "--stop-unshot", "1e-4", "--quiet", "--width", "32",
                    "--height", "32"});
  ASSERT_EQ(r.code, 0) << r.err;
  auto rows = ReadCsv(dir.File("out/patches.csv"));
  ASSERT_EQ(rows.size(), 1u + 6 * 9);  // 3 x 3 patches per face
  double worst = 0.0;
  for (size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 18u);
    for (int c = 15; c < 18; ++c) {
      double b = std::stod(rows[i][c]);
      worst = std::fmax(worst, std::fabs(b - exact) / exact);
    }
  }
  EXPECT_LT(worst, 0.01) << "worst relative error of B against E/(1-rho)";
}

TEST(RenderTest, SameSeedSameBytesOtherSeedOtherBytes) {
  TempDir dir;
  std::vector<std::string> base = {
      "render", "scenes/cornell.obj", "--rays", "256",    "--max-shots", "400", "--width",
      "96",     "--height",           "96",     "--quiet"};
  auto run = [&](const std::string& out, const std::string& seed) {
    auto args = base;
    args.insert(args.end(), {"--out", dir.File(out), "--seed", seed});
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
  };
  run("a", "7");
  run("b", "7");
  run("c", "8");
  for (const char* f : {"image.pfm", "patches.csv", "image.png"}) {
    std::string a = ReadFile(dir.File(std::string("a/") + f));
    ASSERT_FALSE(a.empty()) << f;
    EXPECT_EQ(a, ReadFile(dir.File(std::string("b/") + f))) << f;
    EXPECT_NE(a, ReadFile(dir.File(std::string("c/") + f))) << f;
  }
}

TEST(RenderTest, OutputsHaveTheDocumentedFormat) {
  TempDir dir;
  auto r = RunMain({"render", "scenes/cornell.obj", "--out", dir.path(), "--rays", "128",
                    "--max-shots", "50", "--width", "40", "--height", "30", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  auto patches = ReadCsv(dir.File("patches.csv"));
  ASSERT_GT(patches.size(), 1u);
  std::string header;
  for (size_t i = 0; i < patches[0].size(); ++i) header += (i ? "," : "") + patches[0][i];
  EXPECT_EQ(header, "id,env,cx,cy,cz,nx,ny,nz,area,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b,b_r,b_g,b_b");
  auto conv = ReadCsv(dir.File("convergence.csv"));
  ASSERT_EQ(conv.size(), 51u);
  EXPECT_EQ(conv[0], (std::vector<std::string>{"shot", "seconds", "unshot_fraction"}));
  EXPECT_EQ(conv[50][0], "50");
  // Unshot power never grows from one shot to the next in a closed-ish scene
  // with kd < 1 (a shot removes its power, receivers get at most kd of it).
  for (size_t i = 2; i < conv.size(); ++i)
    EXPECT_LE(std::stod(conv[i][2]), std::stod(conv[i - 1][2]));
  std::string pfm = ReadFile(dir.File("image.pfm"));
  std::string head = "PF\n40 30\n-1.0\n";
  ASSERT_EQ(pfm.substr(0, head.size()), head);
  EXPECT_EQ(pfm.size(), head.size() + 40 * 30 * 3 * 4);
  std::string png = ReadFile(dir.File("image.png"));
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  std::string json = ReadFile(dir.File("run.json"));
  EXPECT_NE(json.find("\"stop_reason\": \"max-shots\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"shots\": 50"), std::string::npos) << json;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))  // no temporary left
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(RenderTest, EnergyBalanceCloses) {
  TempDir dir;
  auto r = RunMain({"render", "scenes/cornell.obj", "--out", dir.path(), "--rays", "256",
                    "--max-shots", "500", "--width", "16", "--height", "16", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::string json = ReadFile(dir.File("run.json"));
  auto triple = [&](const std::string& key) {
    size_t at = json.find("\"" + key + "\": [");
    EXPECT_NE(at, std::string::npos) << key;
    std::stringstream ss(json.substr(json.find('[', at) + 1));
    double v[3];
    char comma;
    ss >> v[0] >> comma >> v[1] >> comma >> v[2];
    return std::vector<double>{v[0], v[1], v[2]};
  };
  auto emitted = triple("emitted"), absorbed = triple("absorbed"), escaped = triple("escaped"),
       unshot = triple("unshot");
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(emitted[c], 0.0);
    EXPECT_GT(escaped[c], 0.0);  // the Cornell box is open at z = 0
    EXPECT_NEAR(absorbed[c] + escaped[c] + unshot[c], emitted[c], 1e-9 * emitted[c]) << c;
  }
}

}  // namespace
}  // namespace vismask
