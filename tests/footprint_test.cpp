// Memory: footprint's predictions are what a render reserves and uses, one
// environment pays for no exchange, and --mem-budget refuses at init.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "test_util.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::RunMain;
using test::TempDir;

// The value of `"key": N` after position `from` in a JSON text.
unsigned long long JsonNumber(const std::string& json, const std::string& key, size_t from = 0) {
  size_t at = json.find("\"" + key + "\": ", from);
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return 0;
  return std::stoull(json.substr(at + key.size() + 4));
}

// `vismask footprint SCENE --json OPTIONS...`'s standard output.
std::string FootprintJson(const std::vector<std::string>& options,
                          const std::string& scene = "scenes/cornell.obj") {
  std::vector<std::string> args = {"footprint", scene, "--json"};
  args.insert(args.end(), options.begin(), options.end());
  testing::internal::CaptureStdout();
  auto r = RunMain(args);
  std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(r.code, 0) << r.err;
  return out;
}

TEST(FootprintTest, PredictionsMatchTheRendersHighWaterMark) {
  TempDir dir;
  const std::vector<std::vector<std::string>> configs = {
      {"--envs", "1"},
      {"--envs", "2", "--mask-res", "20"},
      {"--envs", "2", "--mask-res", "250"},
      {"--envs", "2x2x2", "--mask-res", "20"},
      {"--envs", "2x2x2", "--mask-res", "250"},
      {"--envs", "2x2x2", "--mask-method", "C", "--mask-res", "40"},
      {"--envs", "2x2x2", "--mask-method", "R", "--rays", "100"},
      {"--envs", "2x2x2", "--mask-method", "R", "--rays", "30000"},
  };
  int k = 0;
  for (auto config : configs) {
    config.insert(config.end(), {"--patch-size", "60", "--width", "64", "--height", "48"});
    std::string fp = FootprintJson(config);
    unsigned long long predicted = JsonNumber(fp, "total_bytes", fp.find("\"ranks\""));
    std::vector<std::string> args = {"render",      "scenes/cornell.obj",
                                     "--out",       dir.File(std::to_string(k++)),
                                     "--rays",      "64",
                                     "--max-shots", "40",
                                     "--quiet"};
    args.insert(args.end(), config.begin(), config.end());
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    std::string run = ReadFile(dir.File(std::to_string(k - 1) + "/run.json"));
    EXPECT_EQ(JsonNumber(run, "predicted_bytes"), predicted) << config[1];
    EXPECT_EQ(JsonNumber(run, "arena_high_water_bytes"), predicted) << config[1];
    // Every environment's arena, one by one.
    std::vector<unsigned long long> inRun, inFootprint;
    std::string list = run.substr(run.find("\"environment_arena_bytes\""));
    list = list.substr(list.find('[') + 1, list.find(']') - list.find('[') - 1);
    for (size_t at = 0; at < list.size();
         at = list.find(',', at) == std::string::npos ? list.size() : list.find(',', at) + 1)
      inRun.push_back(std::stoull(list.substr(at)));
    for (size_t at = fp.find("\"arena_bytes\": "); at != std::string::npos;
         at = fp.find("\"arena_bytes\": ", at + 1))
      inFootprint.push_back(JsonNumber(fp, "arena_bytes", at));
    EXPECT_EQ(inRun, inFootprint) << config[1];
    size_t env = inRun.size();
    EXPECT_GE(env, 1u);
  }
}

// Issue 20: footprint shows the balance. The Cornell box's uniform split
// at x = 278 is lopsided; --envs auto:2 cuts where the patches halve, and
// footprint's patch counts (the mesher's, not the estimate's) show it.
TEST(FootprintTest, ShowsTheBalanceOfTheEnvironments) {
  auto balance = [](const std::string& json) {
    size_t at = json.find("\"patch_balance\": ");
    EXPECT_NE(at, std::string::npos) << json;
    return at == std::string::npos ? 0.0 : std::atof(json.c_str() + at + 17);
  };
  std::string uniform = FootprintJson({"--envs", "2"});
  std::string balanced = FootprintJson({"--envs", "auto:2"});
  std::printf("most patches / mean: --envs 2 %.3f, --envs auto:2 %.3f\n", balance(uniform),
              balance(balanced));
  EXPECT_GT(balance(uniform), 1.25);
  EXPECT_LT(balance(balanced), 1.05);
  EXPECT_NE(balanced.find("\"balanced\": true"), std::string::npos);
  EXPECT_NE(uniform.find("\"balanced\": false"), std::string::npos);
}

TEST(FootprintTest, OneEnvironmentReservesNoExchange) {
  std::string fp = FootprintJson({"--envs", "1", "--mask-res", "250"});
  EXPECT_EQ(JsonNumber(fp, "queue_bytes"), 0u);
  EXPECT_EQ(JsonNumber(fp, "packet_bytes"), 0u);
  // A neighbour makes them appear, growing with the mask resolution.
  std::string two20 = FootprintJson({"--envs", "2", "--mask-res", "20"});
  std::string two250 = FootprintJson({"--envs", "2", "--mask-res", "250"});
  EXPECT_GT(JsonNumber(two20, "queue_bytes"), 0u);
  EXPECT_GT(JsonNumber(two250, "queue_bytes"), JsonNumber(two20, "queue_bytes"));
}

TEST(FootprintTest, MethodRSlotsHoldOneBitPerRay) {
  // --envs 2 --queue 64: each environment has one neighbour, so 64 slots of N bits.
  std::string small =
      FootprintJson({"--envs", "2", "--mask-method", "R", "--rays", "800", "--queue", "64"});
  std::string large =
      FootprintJson({"--envs", "2", "--mask-method", "R", "--rays", "80000", "--queue", "64"});
  EXPECT_EQ(JsonNumber(small, "packet_size_bytes"), 144u + 104u);  // 100 bytes padded to 8
  EXPECT_EQ(JsonNumber(large, "packet_size_bytes"), 144u + 10000u);
  // 64 slots, 13 words each against 1250: 64 * (1250 - 13) * 8 bytes more,
  // up to the arena's alignment of each part.
  unsigned long long grow = JsonNumber(large, "queue_bytes") - JsonNumber(small, "queue_bytes");
  EXPECT_GE(grow, 64ull * (1250 - 13) * 8);
  EXPECT_LE(grow, 64ull * (1250 - 13) * 8 + 128);
  // The mask's resolution plays no part.
  EXPECT_EQ(FootprintJson({"--envs", "2", "--mask-method", "R", "--rays", "800", "--queue", "64",
                           "--mask-res", "250"}),
            small);
}

TEST(FootprintTest, MemBudgetRefusesBelowTheNeedAndRunsAtIt) {
  TempDir dir;
  std::vector<std::string> config = {"--envs",      "2",        "--patch-size", "60",     "--width",
                                     "64",          "--height", "48",           "--rays", "64",
                                     "--max-shots", "20",       "--quiet"};
  std::string fp = FootprintJson(config);
  // What the budget must allow: the arenas, or init's own peak if larger
  // (issue 20: the prediction covers init).
  unsigned long long need = JsonNumber(fp, "budget_bytes", fp.find("\"ranks\""));
  EXPECT_GE(need, JsonNumber(fp, "total_bytes", fp.find("\"ranks\"")));
  EXPECT_GE(need, JsonNumber(fp, "init_peak_bytes", fp.find("\"ranks\"")));
  auto render = [&](unsigned long long budget, const std::string& out) {
    std::vector<std::string> args = {"render",      "scenes/cornell.obj", "--out",
                                     dir.File(out), "--mem-budget",       std::to_string(budget)};
    args.insert(args.end(), config.begin(), config.end());
    return RunMain(args);
  };
  auto under = render(need - 1, "under");
  EXPECT_EQ(under.code, 2);
  EXPECT_NE(under.err.find("needs " + std::to_string(need) + " bytes"), std::string::npos)
      << under.err;
  EXPECT_NE(under.err.find("budget of " + std::to_string(need - 1)), std::string::npos)
      << under.err;
  EXPECT_FALSE(test::FileExists(dir.File("under")));
  auto exact = render(need, "exact");
  EXPECT_EQ(exact.code, 0) << exact.err;
  EXPECT_TRUE(test::FileExists(dir.File("exact/image.png")));
}

// Textures: the texels each rank shows are in its arena (3 bytes a texel,
// only the textures of its own environments), the per-patch uv in each
// environment's, and a textured render reserves exactly what footprint says.
TEST(FootprintTest, CountsTextureBytes) {
  auto footprint = [](std::vector<std::string> extra) {
    extra.insert(extra.begin(), {"--width", "64", "--height", "48"});
    return FootprintJson(extra, "scenes/textured/room.obj");
  };
  const unsigned long long checker = 32 * 32 * 3, stripes = 16 * 16 * 3;
  std::string one = footprint({});
  unsigned long long texture = JsonNumber(one, "texture_bytes", one.find("\"ranks\""));
  EXPECT_GE(texture, checker + stripes);
  EXPECT_LE(texture, checker + stripes + 2 * 64 + 64);  // two Texture records and alignment
  EXPECT_GT(JsonNumber(one, "texcoord_bytes"), 0u);
  // Untextured: nothing.
  std::string cornell = FootprintJson({});
  EXPECT_EQ(JsonNumber(cornell, "texture_bytes", cornell.find("\"ranks\"")), 0u);
  EXPECT_EQ(JsonNumber(cornell, "texcoord_bytes"), 0u);
  // Two ranks split at x = 5: the striped wall (x = 10) is rank 1's only.
  std::string two = footprint({"--envs", "2", "--ranks", "2"});
  size_t r0 = two.find("{\"rank\": 0"), r1 = two.find("{\"rank\": 1");
  unsigned long long t0 = JsonNumber(two, "texture_bytes", r0),
                     t1 = JsonNumber(two, "texture_bytes", r1);
  EXPECT_GE(t0, checker);
  EXPECT_LT(t0, checker + stripes);
  EXPECT_GE(t1 - t0, stripes);
  EXPECT_LE(t1 - t0, stripes + 16);
  // The render reserves and uses exactly that, and reports it.
  TempDir dir;
  auto r = RunMain({"render", "scenes/textured/room.obj", "--out", dir.path(), "--width", "64",
                    "--height", "48", "--emitted-rays", "100000", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::string run = ReadFile(dir.File("run.json"));
  unsigned long long predicted = JsonNumber(one, "total_bytes", one.find("\"ranks\""));
  EXPECT_EQ(JsonNumber(run, "predicted_bytes"), predicted);
  EXPECT_EQ(JsonNumber(run, "arena_high_water_bytes"), predicted);
  EXPECT_EQ(JsonNumber(run, "rank0_texture_bytes"), texture);
  EXPECT_NE(run.find("\"path\": \"scenes/textured/checker.png\", \"width\": 32, \"height\": 32, "
                     "\"texel_bytes\": 3072}"),
            std::string::npos)
      << run;
}

TEST(FootprintTest, PeakRssIsExplainedByArenasAndMappedFiles) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP()
      << "AddressSanitizer's shadow memory is part of the RSS; the claim is about normal builds";
#endif
  TempDir dir;
  // A child process so that the test binary's own heap does not count.
  std::string bin = std::getenv("VISMASK_BIN") ? std::getenv("VISMASK_BIN") : "build/vismask";
  std::string cmd = bin + " render scenes/cornell.obj --out " + dir.path() +
                    " --rays 256 --max-shots 300 --quiet";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::string run = ReadFile(dir.File("run.json"));
  size_t at = run.find("\"peak_rss_explained\": ");
  ASSERT_NE(at, std::string::npos);
  double explained = std::stod(run.substr(at + 22));
  EXPECT_GT(explained, 0.90) << run;
  EXPECT_LT(explained, 1.10) << run;
}

}  // namespace
}  // namespace vismask
