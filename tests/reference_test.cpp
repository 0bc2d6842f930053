// --reference and --error-every: the error of the image against a reference,
// measured during the solve without changing it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/output/image_io.h"

namespace vismask {
namespace {

using namespace test;

const std::vector<std::string> kBase = test::Words(
    "render scenes/cornell.obj --patch-size 70 --rays 512 --max-shots 700 --width 48 --height 40 "
    "--quiet --envs 2 --round-shots 1");
// (--round-shots 1: a round is a shot an environment, so --error-every 100
// measures at every hundredth shot; rounds by work would hold many.)

void Render(const std::string& out, std::vector<std::string> extra) {
  auto args = kBase;
  args.insert(args.end(), {"--out", out});
  args.insert(args.end(), extra.begin(), extra.end());
  auto r = RunMain(args);
  ASSERT_EQ(r.code, 0) << r.err;
}

// kBase with `extra`, into `out`.
struct Refusal {
  std::vector<std::string> extra;
  const char* message;  // a substring of the expected stderr
};

// The render of `c` exits 2, says `c.message` and writes nothing.
void ExpectRefused(const std::string& out, const Refusal& c) {
  auto args = kBase;
  args.insert(args.end(), {"--out", out});
  args.insert(args.end(), c.extra.begin(), c.extra.end());
  auto r = RunMain(args);
  EXPECT_EQ(r.code, 2) << c.message;
  EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
  EXPECT_FALSE(FileExists(out)) << c.message;
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
  EXPECT_TRUE(
      std::isinf(CompareImages(Span<const float>(o, 2), Span<const float>(z, 2)).relativeRmse));
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
  // The last measurement drew the final image, which the outputs then write
  // (the same bytes as the plain run's, above) without drawing it again.
  EXPECT_NE(json.find("\"images_drawn\": 7,"), std::string::npos) << json;
  EXPECT_NE(ReadFile(dir.File("plain/run.json")).find("\"images_drawn\": 1,"), std::string::npos);
  EXPECT_NE(json.find("\"error_every\": 100"), std::string::npos) << json;
  EXPECT_NE(ReadFile(dir.File("plain/run.json")).find("\"relative_rmse\": null"),
            std::string::npos);
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
  EXPECT_NE(ReadFile(dir.File("a/run.json")).find("\"images_drawn\": 1,"), std::string::npos);
}

TEST(ReferenceTest, BadReferenceExitsTwoAndWritesNothing) {
  TempDir dir;
  Render(dir.File("ref"), {"--max-shots", "10"});
  test::WriteFile(dir.File("junk.pfm"), "P6\n1 1\n255\nabc");
  // Headers that claim far more pixels than the file holds (issue 17: these
  // allocated first and aborted with bad_alloc or length_error).
  test::WriteFile(dir.File("huge.pfm"), "PF\n100000 100000\n-1\n");
  test::WriteFile(dir.File("max.pfm"), "PF\n2147483647 2147483647\n-1\n");
  // One non-finite pixel in a 48x40 reference (issue 17: a NaN compared as a
  // perfect match, an Inf wrote -nan into run.json).
  auto withPixel = [&](const std::string& name, float value) {
    std::string pfm = ReadFile(dir.File("ref/image.pfm"));
    size_t header = pfm.size() - 48 * 40 * 12;
    std::memcpy(&pfm[header + (40 * 48 - 1) * 12 + 4], &value, 4);  // top right, green
    test::WriteFile(dir.File(name), pfm);
  };
  withPixel("nan.pfm", std::nanf(""));
  withPixel("inf.pfm", INFINITY);
  const Refusal cases[] = {
      {{"--error-every", "10"}, "--error-every: needs --reference"},
      {{"--reference", dir.File("ref/image.pfm"), "--error-every", "0"}, "--error-every"},
      {{"--reference", dir.File("ref/image.pfm"), "--width", "50"}, "is 48x40, the image is 50x40"},
      {{"--reference", dir.File("nothere.pfm")}, "nothere.pfm: cannot open"},
      {{"--reference", dir.File("junk.pfm")}, "junk.pfm: not a colour PFM"},
      // Rank 0 alone reads the reference and refuses it; rank 1 stops too.
      {{"--reference", dir.File("junk.pfm"), "--ranks", "2"}, "junk.pfm: not a colour PFM"},
      {{"--reference", dir.File("huge.pfm")},
       "huge.pfm: truncated PFM: the header says 100000 x 100000"},
      {{"--reference", dir.File("max.pfm")}, "max.pfm: truncated PFM"},
      {{"--reference", dir.File("nan.pfm")},
       "nan.pfm: pixel (47, 0) (x, y from the top left) is not finite: NaN"},
      {{"--reference", dir.File("inf.pfm")},
       "inf.pfm: pixel (47, 0) (x, y from the top left) is not finite: Inf"},
  };
  for (const Refusal& c : cases) ExpectRefused(dir.File("out"), c);
  // compare reads with the same reader: refused too, exit 2.
  for (const char* bad : {"huge.pfm", "max.pfm", "nan.pfm", "inf.pfm"}) {
    auto r = RunMain({"compare", dir.File("ref/image.pfm"), dir.File(bad)});
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find(bad), std::string::npos) << r.err;
    r = RunMain({"compare", dir.File(bad), dir.File("ref/image.pfm")});
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
  }
}

// An 8-bit PGM of w x h whose pixel (x, y), y from the top, is f(x, y).
template <typename F>
std::string Pgm(int w, int h, F f) {
  std::string s = "P5\n" + std::to_string(w) + " " + std::to_string(h) + "\n255\n";
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) s += static_cast<char>(f(x, y));
  return s;
}

std::string JsonNumber(const std::string& json, const std::string& key) {
  size_t at = json.find("\"" + key + "\": ");
  if (at == std::string::npos) return "";
  at += key.size() + 4;
  return json.substr(at, json.find_first_of(",\n", at) - at);
}

TEST(ReferenceTest, CompareImagesLeavesOutExcludedPixels) {
  // Pixel 1 alone differs; pixel 0 counts only in the denominator.
  const float b[6] = {1, 1, 1, 3, 3, 3}, a[6] = {1, 1, 1, 1, 1, 1};
  const uint8_t none[2] = {0, 0}, first[2] = {255, 0}, second[2] = {0, 1};
  ImageError e =
      CompareImages(Span<const float>(a, 6), Span<const float>(b, 6), Span<const uint8_t>(none, 2));
  EXPECT_DOUBLE_EQ(e.relativeRmse, std::sqrt(12.0 / 30.0));
  EXPECT_EQ(e.excludedPixels, 0u);
  e = CompareImages(Span<const float>(a, 6), Span<const float>(b, 6),
                    Span<const uint8_t>(first, 2));
  EXPECT_DOUBLE_EQ(e.relativeRmse, std::sqrt(12.0 / 27.0));
  EXPECT_EQ(e.excludedPixels, 1u);
  // Excluding the only differing pixel leaves no error at all.
  e = CompareImages(Span<const float>(a, 6), Span<const float>(b, 6),
                    Span<const uint8_t>(second, 2));
  EXPECT_EQ(e.relativeRmse, 0.0);
  EXPECT_EQ(e.maxAbs, 0.0);
  EXPECT_EQ(e.excludedPixels, 1u);
}

TEST(ReferenceTest, ExcludeMaskLeavesPixelsOutOfTheRenderError) {
  TempDir dir;
  Render(dir.File("ref"), {"--envs", "1", "--max-shots", "300"});
  test::WriteFile(dir.File("none.pgm"), Pgm(48, 40, [](int, int) { return 0; }));
  test::WriteFile(dir.File("all.pgm"), Pgm(48, 40, [](int, int) { return 255; }));
  test::WriteFile(dir.File("top.pgm"), Pgm(48, 40, [](int, int y) { return y < 10 ? 7 : 0; }));
  const std::string ref = dir.File("ref/image.pfm");
  Render(dir.File("plain"), {"--reference", ref, "--seed", "3", "--max-shots", "150"});
  Render(dir.File("none"), {"--reference", ref, "--seed", "3", "--max-shots", "150", "--exclude",
                            dir.File("none.pgm")});
  Render(dir.File("all"), {"--reference", ref, "--seed", "3", "--max-shots", "150", "--exclude",
                           dir.File("all.pgm")});
  Render(dir.File("top"), {"--reference", ref, "--seed", "3", "--max-shots", "150", "--exclude",
                           dir.File("top.pgm")});
  std::string plain = ReadFile(dir.File("plain/run.json"));
  std::string none = ReadFile(dir.File("none/run.json"));
  std::string all = ReadFile(dir.File("all/run.json"));
  std::string top = ReadFile(dir.File("top/run.json"));
  EXPECT_EQ(JsonNumber(plain, "exclude"), "null");
  EXPECT_EQ(JsonNumber(plain, "excluded_pixels"), "0");
  EXPECT_EQ(JsonNumber(none, "exclude"), "\"" + dir.File("none.pgm") + "\"");
  EXPECT_EQ(JsonNumber(none, "relative_rmse"), JsonNumber(plain, "relative_rmse"));
  EXPECT_EQ(JsonNumber(all, "excluded_pixels"), "1920");
  EXPECT_EQ(std::stod(JsonNumber(all, "relative_rmse")), 0.0);
  // The top 10 rows left out: the same figure as CompareImages with that mask.
  EXPECT_EQ(JsonNumber(top, "excluded_pixels"), "480");
  PfmImage x, y;
  ASSERT_TRUE(ReadPfm(dir.File("top/image.pfm"), &x).ok());
  ASSERT_TRUE(ReadPfm(ref, &y).ok());
  std::vector<uint8_t> mask(48 * 40, 0);
  for (size_t i = 0; i < 480; ++i) mask[i] = 1;
  double want = CompareImages(Span<const float>(x.pixels.data(), x.pixels.size()),
                              Span<const float>(y.pixels.data(), y.pixels.size()),
                              Span<const uint8_t>(mask.data(), mask.size()))
                    .relativeRmse;
  double got = std::stod(JsonNumber(top, "relative_rmse"));
  EXPECT_NEAR(got, want, 1e-12 * want);
  EXPECT_NE(got, std::stod(JsonNumber(plain, "relative_rmse")));
  // The image itself does not depend on the mask.
  EXPECT_EQ(ReadFile(dir.File("top/image.pfm")), ReadFile(dir.File("plain/image.pfm")));
}

TEST(ReferenceTest, BadExcludeMaskExitsTwoAndWritesNothing) {
  TempDir dir;
  Render(dir.File("ref"), {"--max-shots", "10"});
  const std::string ref = dir.File("ref/image.pfm");
  test::WriteFile(dir.File("small.pgm"), Pgm(47, 40, [](int, int) { return 0; }));
  test::WriteFile(dir.File("ascii.pgm"), "P2\n48 40\n255\n0 0 0\n");
  test::WriteFile(dir.File("short.pgm"), "P5\n48 40\n255\nabc");
  test::WriteFile(dir.File("ok.pgm"), Pgm(48, 40, [](int, int) { return 0; }));
  const Refusal cases[] = {
      {{"--exclude", dir.File("ok.pgm")}, "--exclude: needs --reference"},
      {{"--reference", ref, "--exclude", dir.File("nothere.pgm")}, "nothere.pgm: cannot open"},
      {{"--reference", ref, "--exclude", dir.File("small.pgm")},
       "small.pgm: is 47x40, the image is 48x40"},
      {{"--reference", ref, "--exclude", dir.File("ascii.pgm")},
       "ascii.pgm: not an 8-bit binary PGM"},
      {{"--reference", ref, "--exclude", dir.File("short.pgm")}, "short.pgm: truncated PGM"},
      {{"--reference", ref, "--exclude", dir.File("small.pgm"), "--ranks", "2"},
       "small.pgm: is 47x40"},
  };
  for (const Refusal& c : cases) ExpectRefused(dir.File("out"), c);
  // vismask compare: the same checks on its mask.
  auto r = RunMain({"compare", ref, ref, "--exclude", dir.File("small.pgm")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("small.pgm: is 47x40, the images are 48x40"), std::string::npos) << r.err;
  r = RunMain({"compare", ref, ref, "--exclude", dir.File("ascii.pgm")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("ascii.pgm: not an 8-bit binary PGM"), std::string::npos) << r.err;
  EXPECT_EQ(RunMain({"compare", ref, ref, "--exclude"}).code, 2);
  EXPECT_EQ(RunMain({"compare", ref, ref, "--exclude", dir.File("ok.pgm")}).code, 0);
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
