// The experiments pipeline (tools/experiments, make experiments) in
// miniature: every step runs on a tiny render and writes every table, image
// and plot docs/RESULTS.md shows, so the pipeline cannot rot unseen.
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>

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
                    " tools/experiments/all --mini --out " + dir.path() + " 2> " +
                    dir.File("log.txt");
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadFile(dir.File("log.txt"));

  // Tables: a header and rows, with numbers where the figures are.
  struct Table {
    const char* file;
    size_t minRows;
    std::vector<int> numericColumns;
  } tables[] = {
      {"references.csv", 1, {2, 3, 4, 5}},
      {"fig2-quality.csv", 4, {4, 5, 6, 7}},        // R = 4, 8, 16 and the seed floor
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
        EXPECT_TRUE(IsNumber(rows[r][c])) << t.file << " row " << r << " col " << c << ": '"
                                          << rows[r][c] << "'";
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
}

}  // namespace
}  // namespace vismask
