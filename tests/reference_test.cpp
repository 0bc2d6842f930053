// --reference and --error-every: the error of the image against a reference,
// measured during the solve without changing it.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.h"
#include "vismask/image_io.h"

namespace vismask {
namespace {

using test::FileExists;
using test::ReadCsv;
using test::ReadFile;
using test::RunMain;
using test::TempDir;

const std::vector<std::string> kBase = {"render",  "scenes/cornell.obj", "--patch-size", "70",
                                        "--rays",  "512",  "--max-shots", "700",
                                        "--width", "48",   "--height",   "40",
                                        "--quiet", "--envs", "2"};

void Render(const std::string& out, std::vector<std::string> extra) {
  auto args = kBase;
  args.insert(args.end(), {"--out", out});
  args.insert(args.end(), extra.begin(), extra.end());
  auto r = RunMain(args);
  ASSERT_EQ(r.code, 0) << r.err;
}

double FileError(const std::string& a, const std::string& b) {
  PfmImage x, y;
  EXPECT_TRUE(ReadPfm(a, &x).ok());
  EXPECT_TRUE(ReadPfm(b, &y).ok());
  return CompareImages(Span<const float>(x.pixels.data(), x.pixels.size()),
                       Span<const float>(y.pixels.data(), y.pixels.size()))
      .relativeRmse;
}

TEST(ReferenceTest, CompareImagesIsTheRelativeRmse) {
  const float b[4] = {1, 2, 0, 2}, a[4] = {1, 1, 0, 4};
  ImageError e = CompareImages(Span<const float>(a, 4), Span<const float>(b, 4));
  EXPECT_DOUBLE_EQ(e.relativeRmse, std::sqrt(5.0 / 9.0));
  EXPECT_DOUBLE_EQ(e.maxAbs, 2.0);
  const float z[2] = {0, 0}, o[2] = {0, 1};
  EXPECT_EQ(CompareImages(Span<const float>(z, 2), Span<const float>(z, 2)).relativeRmse, 0.0);
  EXPECT_TRUE(std::isinf(CompareImages(Span<const float>(o, 2), Span<const float>(z, 2)).relativeRmse));
}

TEST(ReferenceTest, ErrorEveryKShotsWithoutChangingTheSolve) {
  TempDir dir;
  Render(dir.File("ref"), {"--envs", "1", "--rays", "4096", "--max-shots", "2000"});
  Render(dir.File("plain"), {});
  Render(dir.File("measured"), {"--reference", dir.File("ref/image.pfm"), "--error-every", "100"});
  // Measuring does not touch the solution.
  for (const char* f : {"image.pfm", "patches.csv", "image.png"})
    EXPECT_EQ(ReadFile(dir.File(std::string("plain/") + f)),
              ReadFile(dir.File(std::string("measured/") + f)))
        << f;

  auto plain = ReadCsv(dir.File("plain/convergence.csv"));
  auto rows = ReadCsv(dir.File("measured/convergence.csv"));
  ASSERT_EQ(rows[0], (std::vector<std::string>{"shot", "seconds", "unshot_fraction",
                                               "relative_rmse", "error_seconds"}));
  ASSERT_EQ(rows.size(), plain.size());
  // Every row has the five fields (ReadCsv drops a trailing empty one).
  std::string text = ReadFile(dir.File("measured/convergence.csv"));
  size_t lines = 0, commas = 0;
  for (char ch : text) {
    lines += ch == '\n';
    commas += ch == ',';
  }
  EXPECT_EQ(commas, 4 * lines);
  for (auto& row : rows) row.resize(5);
  uint64_t measured = 0, previousShot = 0;
  double previousSeconds = 0.0;
  for (size_t i = 1; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i][0], plain[i][0]);
    EXPECT_EQ(rows[i][2], plain[i][2]);
    uint64_t shot = std::stoull(rows[i][0]);
    bool crossed = shot / 100 > previousShot / 100 || i + 1 == rows.size();
    EXPECT_EQ(!rows[i][3].empty(), crossed) << "row " << i << " shot " << shot;
    EXPECT_EQ(rows[i][3].empty(), rows[i][4].empty());
    if (!rows[i][3].empty()) {
      ++measured;
      double e = std::stod(rows[i][3]);
      EXPECT_TRUE(e > 0.0 && e < 1.0) << e;
      double spent = std::stod(rows[i][4]);
      EXPECT_GE(spent, previousSeconds);
      previousSeconds = spent;
    }
    previousShot = shot;
  }
  EXPECT_EQ(measured, 7u);  // shots 100, 200, ..., 700 (the last is the final row)
  // The last row is the final image's error.
  double last = std::stod(rows.back()[3]);
  EXPECT_NEAR(last, FileError(dir.File("measured/image.pfm"), dir.File("ref/image.pfm")),
              1e-8 * last);
  // The error falls as the solve goes on (700 of ~2000 shots: first vs last).
  double first = 0.0;
  for (size_t i = 1; i < rows.size() && first == 0.0; ++i)
    if (!rows[i][3].empty()) first = std::stod(rows[i][3]);
  EXPECT_LT(last, first);
  std::string json = ReadFile(dir.File("measured/run.json"));
  EXPECT_NE(json.find("\"error_measurements\": 7"), std::string::npos) << json;
  EXPECT_NE(json.find("\"error_every\": 100"), std::string::npos) << json;
  EXPECT_NE(ReadFile(dir.File("plain/run.json")).find("\"relative_rmse\": null"), std::string::npos);
}

TEST(ReferenceTest, ReferenceAloneMeasuresTheFinalImage) {
  TempDir dir;
  Render(dir.File("ref"), {"--envs", "1", "--max-shots", "300"});
  Render(dir.File("a"), {"--reference", dir.File("ref/image.pfm"), "--seed", "3"});
  auto rows = ReadCsv(dir.File("a/convergence.csv"));
  for (auto& row : rows) row.resize(5);
  for (size_t i = 1; i + 1 < rows.size(); ++i) EXPECT_TRUE(rows[i][3].empty()) << i;
  double last = std::stod(rows.back()[3]);
  EXPECT_NEAR(last, FileError(dir.File("a/image.pfm"), dir.File("ref/image.pfm")), 1e-8 * last);
}

TEST(ReferenceTest, BadReferenceExitsTwoAndWritesNothing) {
  TempDir dir;
  Render(dir.File("ref"), {"--max-shots", "10"});
  test::WriteFile(dir.File("junk.pfm"), "P6\n1 1\n255\nabc");
  struct Case {
    std::vector<std::string> extra;
    const char* message;
  } cases[] = {
      {{"--error-every", "10"}, "--error-every: needs --reference"},
      {{"--reference", dir.File("ref/image.pfm"), "--error-every", "0"}, "--error-every"},
      {{"--reference", dir.File("ref/image.pfm"), "--width", "50"}, "is 48x40, the image is 50x40"},
      {{"--reference", dir.File("nothere.pfm")}, "nothere.pfm: cannot open"},
      {{"--reference", dir.File("junk.pfm")}, "junk.pfm: not a colour PFM"},
      // Rank 0 alone reads the reference and refuses it; rank 1 stops too.
      {{"--reference", dir.File("junk.pfm"), "--ranks", "2"}, "junk.pfm: not a colour PFM"},
  };
  for (const Case& c : cases) {
    auto args = kBase;
    args.insert(args.end(), {"--out", dir.File("out")});
    args.insert(args.end(), c.extra.begin(), c.extra.end());
    auto r = RunMain(args);
    EXPECT_EQ(r.code, 2) << c.message;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_FALSE(FileExists(dir.File("out"))) << c.message;
  }
}

}  // namespace
}  // namespace vismask

namespace vismask {
namespace {

// run.json's camera is the one the image was drawn with: given back as
// --camera, it draws the same bytes (the experiments use it to find pixels).
TEST(ReferenceTest, RunJsonCameraReproducesTheImage) {
  TempDir dir;
  Render(dir.File("a"), {"--max-shots", "50"});
  std::string json = ReadFile(dir.File("a/run.json"));
  size_t at = json.find("\"camera\": [");
  ASSERT_NE(at, std::string::npos);
  std::string list = json.substr(at + 11, json.find(']', at) - at - 11);
  std::string camera;
  for (char ch : list)
    if (ch != ' ') camera += ch;
  Render(dir.File("b"), {"--max-shots", "50", "--camera", camera});
  EXPECT_EQ(ReadFile(dir.File("a/image.pfm")), ReadFile(dir.File("b/image.pfm"))) << camera;
}

}  // namespace
}  // namespace vismask
