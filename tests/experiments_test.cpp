// The experiments pipeline (tools/experiments, make experiments) in
// miniature: every step runs on a tiny render and writes every table, image
// and plot docs/RESULTS.md shows, so the pipeline cannot rot unseen.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "test_util.h"

namespace vismask {
namespace {

using test::FileExists;
using test::ReadCsv;
using test::ReadFile;
using test::TempDir;

bool IsNumber(const std::string& s) {
  if (s.empty()) return false;
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size();
}

TEST(ExperimentsTest, MiniaturePipelineWritesEveryResult) {
  TempDir dir;
  const char* bin = std::getenv("VISMASK_BIN");
  std::string cmd = std::string("VISMASK_BIN=") + (bin ? bin : "build/vismask") +
                    " tools/experiments --quick --out " + dir.path() + " 2> " + dir.File("log.txt");
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadFile(dir.File("log.txt"));

  // Tables: a header and rows, with numbers where the figures are.
  struct Table {
    const char* file;
    size_t minRows;
    std::vector<int> numericColumns;
  } tables[] = {
      {"references.csv", 1, {2, 3, 4, 5}},
      {"fig2-quality.csv", 4, {4, 5, 6, 7}},  // R = 4, 8, 16 and the seed floor
      {"table1-time.csv", 8, {2, 3, 4, 5, 6, 7, 8}},
      {"fig3-leak.csv", 12, {2, 3}},
      {"closed-box.csv", 3, {3, 4, 5, 6, 7, 8}},
      {"pareto.csv", 1, {0, 1, 3}},
      {"curves.csv", 11, {1, 2, 3, 4, 5}},
  };
  for (const Table& t : tables) {
    auto rows = ReadCsv(dir.File(t.file));
    ASSERT_GE(rows.size(), 1 + t.minRows) << t.file;
    for (size_t r = 1; r < rows.size(); ++r)
      for (int c : t.numericColumns) {
        if (std::string(t.file) == "fig2-quality.csv" && r == 4) continue;  // the seed row
        ASSERT_LT(size_t(c), rows[r].size()) << t.file << " row " << r;
        EXPECT_TRUE(IsNumber(rows[r][c]))
            << t.file << " row " << r << " col " << c << ": '" << rows[r][c] << "'";
      }
  }
  // Table 1: a median of three, between its min and max.
  auto t1 = ReadCsv(dir.File("table1-time.csv"));
  for (size_t r = 1; r < t1.size(); ++r) {
    EXPECT_LE(std::stod(t1[r][3]), std::stod(t1[r][2]));
    EXPECT_LE(std::stod(t1[r][2]), std::stod(t1[r][4]));
  }
  // Methods B and C cast centre rays; none, A and R do not.
  ASSERT_EQ(t1.size(), 1u + 8);  // none, A, B and C at R = 4 and 8, R
  for (size_t r = 1; r < t1.size(); ++r)
    EXPECT_EQ(t1[r][0] == "B" || t1[r][0] == "C", std::stod(t1[r][7]) > 0) << t1[r][0];

  for (const char* png : {"error-time.png", "img/region.png", "img/ref-b.png", "img/fig2-B-4.png",
                          "img/fig2-B-16.png", "img/fig2-B-8-diff.png", "img/fig3-A-16.png",
                          "img/fig3-A-16-diff.png"}) {
    std::string bytes = ReadFile(dir.File(png));
    ASSERT_GT(bytes.size(), 8u) << png;
    EXPECT_EQ(bytes.substr(1, 3), "PNG") << png;
  }
  // The shadow region is not empty: some pixel differs from the darkened rest.
  std::string region = ReadFile(dir.File("runs/region-48x48.txt"));
  EXPECT_NE(region.find_first_of("12"), std::string::npos);

  std::string doc = ReadFile(dir.File("RESULTS.md"));
  for (const char* heading : {"## Fig. 2", "## Table 1", "## Fig. 3", "## Error against run time",
                              "## Reading", "(img/fig2-B-4.png)", "(error-time.png)"})
    EXPECT_NE(doc.find(heading), std::string::npos) << heading;
  EXPECT_EQ(doc.find("nan"), std::string::npos) << "a figure is not a number";

  // The ground truth (issue 15): with blender, its section, tables and images
  // and the ground-truth columns of the paper's tables; without, a clear line.
  EXPECT_NE(doc.find("## Against a path-traced ground truth"), std::string::npos);
  EXPECT_NE(doc.find("## Sun shadows against Cycles (issue 41)"), std::string::npos);
  EXPECT_NE(doc.find("## An occluded room against Cycles (issue 41)"), std::string::npos);
  if (std::system("command -v blender > /dev/null 2>&1") != 0) {
    EXPECT_NE(doc.find("**Skipped**: blender not found"), std::string::npos);
    return;
  }
  struct GtTable {
    const char* file;
    size_t rows;
    std::vector<int> numericColumns;
  } gtTables[] = {
      {"gt-time.csv", 4, {2, 3, 4, 6, 7, 8}},              // today, default, a cap, one setting
      {"gt-goals.csv", 5, {2, 3}},                         // three budgets, the ratio, the demo
      {"gt-decomposition.csv", 4, {2, 3, 4, 5, 6, 7, 8}},  // today, default, elements 0, aa off
      {"gt-envs.csv", 6, {2, 4, 5}},                       // 1 env, B, R: capped and converged
      {"gt-seam.csv", 2, {1, 2, 3, 4, 5}},
      {"gt-renderpark.csv", 3, {1, 2, 3}},
      {"gt-references.csv", 1, {2, 3, 4}},
      {"gt-experiments.csv", 1, {1, 2, 3, 4}},
      {"gt-silhouette-mask.csv", 3, {1, 2}},    // emitter, silhouettes, both
      {"gt-silhouettes.csv", 5, {3, 5, 6, 7}},  // --max-seconds at 2 budgets, 3 fixed settings
  };
  for (const GtTable& t : gtTables) {
    auto rows = ReadCsv(dir.File(t.file));
    ASSERT_EQ(rows.size(), 1 + t.rows) << t.file;
    for (size_t r = 1; r < rows.size(); ++r)
      for (int c : t.numericColumns) {
        ASSERT_LT(size_t(c), rows[r].size()) << t.file << " row " << r;
        EXPECT_TRUE(IsNumber(rows[r][c]))
            << t.file << " row " << r << " col " << c << ": '" << rows[r][c] << "'";
      }
  }
  // The --max-seconds rows: each the median of gt.reps repetitions, run by
  // turns with RenderPark's (when built), so their places in the one run
  // order interleave: the budgets' first repetitions all come before any
  // second one.
  {
    auto sil = ReadCsv(dir.File("gt-silhouettes.csv"));
    ASSERT_GE(sil[0].size(), 15u);
    EXPECT_EQ(sil[0][12], "reps");
    EXPECT_EQ(sil[0][14], "run_order");
    std::vector<std::pair<int, int>> orders;
    for (size_t r = 1; r < sil.size(); ++r) {
      if (sil[r][2].empty()) continue;  // a fixed setting
      EXPECT_TRUE(IsNumber(sil[r][11])) << sil[r][11];
      EXPECT_EQ(sil[r][12], "2");
      size_t semi = sil[r][14].find(';');
      ASSERT_NE(semi, std::string::npos) << sil[r][14];
      orders.push_back({std::stoi(sil[r][14]), std::stoi(sil[r][14].substr(semi + 1))});
    }
    ASSERT_EQ(orders.size(), 2u);
    for (const auto& a : orders)
      for (const auto& b : orders) EXPECT_LT(a.first, b.second);
  }
  // The sun room against Cycles (issue 41's sun-shadow goal): four edges
  // measured in each renderer, the whole image's error and the times.
  auto edges = ReadCsv(dir.File("sun-edges.csv"));
  auto sunImage = ReadCsv(dir.File("sun-image.csv"));
  ASSERT_GE(sunImage.size(), 1u + 2);                      // vismask's runs, then Cycles'
  ASSERT_EQ(edges.size(), 1 + 4 * (sunImage.size() - 2));  // four edges a run
  for (size_t r = 1; r < edges.size(); ++r)
    for (int c : {2, 3, 4, 5})
      EXPECT_TRUE(IsNumber(edges[r][c]))
          << "sun-edges.csv row " << r << ": '" << edges[r][c] << "'";
  for (size_t r = 1; r + 1 < sunImage.size(); ++r)
    for (int c : {1, 2, 3, 4, 5, 6})
      EXPECT_TRUE(IsNumber(sunImage[r][c]))
          << "sun-image.csv row " << r << ": '" << sunImage[r][c] << "'";
  EXPECT_EQ(sunImage.back()[0], "cycles");
  EXPECT_TRUE(IsNumber(sunImage.back()[6])) << sunImage.back()[6];
  EXPECT_NE(doc.find("| sill |"), std::string::npos);
  // The occluded room against Cycles (issue 41): an error, the reference's
  // noise and the estimate without it at each block size, then the times.
  auto room = ReadCsv(dir.File("room.csv"));
  ASSERT_EQ(room.size(), 1u + 2);  // blocks 1x1 and 4x4
  for (size_t r = 1; r < room.size(); ++r)
    for (int c : {2, 3, 4})
      EXPECT_TRUE(IsNumber(room[r][c])) << "room.csv row " << r << ": '" << room[r][c] << "'";
  EXPECT_EQ(room[1][0], "1x1");
  auto roomTimes = ReadCsv(dir.File("room-times.csv"));
  ASSERT_EQ(roomTimes.size(), 2u);
  EXPECT_TRUE(IsNumber(roomTimes[1][0])) << roomTimes[1][0];
  // --max-seconds beside the fixed settings, drawn (issue 41).
  std::string anytime = ReadFile(dir.File("gt-anytime.png"));
  ASSERT_GT(anytime.size(), 8u);
  EXPECT_EQ(anytime.substr(1, 3), "PNG");
  EXPECT_NE(doc.find("(gt-anytime.png)"), std::string::npos);
  // RenderPark measured (make renderpark built it) or a line saying it was not built.
  if (FileExists(dir.File("gt-renderpark-measured.csv"))) {
    auto rp = ReadCsv(dir.File("gt-renderpark-measured.csv"));
    ASSERT_GE(rp.size(), 2u);
    for (int c : {2, 3, 4}) EXPECT_TRUE(IsNumber(rp[1][c])) << rp[1][c];
    // Budget by budget (from --quick's vs_from, 0.02 s: both anytime budgets):
    // RenderPark's best setting within T, or none; the verdict its numbers'.
    auto vs = ReadCsv(dir.File("gt-renderpark-vs.csv"));
    ASSERT_EQ(vs.size(), 3u);
    ASSERT_EQ(vs[0].size(), 10u);
    EXPECT_EQ(vs[0][7], "below_renderpark");
    for (size_t i = 1; i < vs.size(); ++i) {
      const auto& r = vs[i];
      ASSERT_TRUE(IsNumber(r[0]) && IsNumber(r[3])) << r[0] << " " << r[3];
      if (r[4] == "none") {
        EXPECT_EQ(r[7], "");
        continue;
      }
      ASSERT_TRUE(IsNumber(r[5]) && IsNumber(r[6])) << r[5] << " " << r[6];
      EXPECT_LE(std::stod(r[5]), std::stod(r[0]));
      EXPECT_EQ(r[7], std::stod(r[3]) < std::stod(r[6]) ? "yes" : "NO");
    }
    EXPECT_NE(doc.find("| budget | vismask_run |"), std::string::npos);
  } else {
    EXPECT_NE(ReadFile(dir.File("gt-renderpark-skipped.txt")).find("make renderpark RPK_SRC="),
              std::string::npos);
    EXPECT_NE(doc.find("**Skipped**: RenderPark not built"), std::string::npos);
  }
  // The ground-truth columns beside reference (b)'s.
  auto fig2 = ReadCsv(dir.File("fig2-quality.csv"));
  ASSERT_GE(fig2[0].size(), 11u);
  EXPECT_EQ(fig2[0][8], "vs_gt_whole");
  EXPECT_TRUE(IsNumber(fig2[1][8]));
  auto fig3 = ReadCsv(dir.File("fig3-leak.csv"));
  EXPECT_EQ(fig3[0].back(), "image_leak_vs_gt_percent");
  EXPECT_TRUE(IsNumber(fig3[2].back()));
  auto pareto = ReadCsv(dir.File("pareto.csv"));
  EXPECT_EQ(pareto[0].back(), "run_final_vs_gt");
  EXPECT_TRUE(IsNumber(pareto[1].back()));
  for (const char* png :
       {"gt-error-time.png", "gt-seam.png", "img/gt-diff-today.png", "img/gt-diff-default.png",
        "img/gt-seam-env2-B.png", "img/gt-seam-env2-R.png"}) {
    std::string bytes = ReadFile(dir.File(png));
    ASSERT_GT(bytes.size(), 8u) << png;
    EXPECT_EQ(bytes.substr(1, 3), "PNG") << png;
  }
  for (const char* heading :
       {"### Error against solve time", "### The goals of issue 15", "### RenderPark, quoted",
        "not rerun by make experiments", "### Where the error comes from",
        "### Two environments against one", "### Without the 1-px silhouettes",
        "RenderPark measured in this run", "(gt-error-time.png)", "(img/gt-diff-default.png)",
        "Ground truth (c)"})
    EXPECT_NE(doc.find(heading), std::string::npos) << heading;
}

}  // namespace
}  // namespace vismask
