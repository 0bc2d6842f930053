// tools/renderpark-run's conversions (issue 41), without rpkCpp: a scene as
// MGF (scaled vertices; a grey Kd keeps white's chromaticity with Y = Kd;
// Ke as `ed` = Y * 183.07), and a Radiance RGBE image, run-length and flat
// scanlines, as a linear PFM with its rows bottom first.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "test_util.h"

namespace vismask {
namespace {

using test::FileExists;
using test::HaveNumpy;
using test::ReadFile;
using test::TempDir;
using test::WriteFile;

int RunCommand(const std::string& cmd) {
  int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(RenderparkRunTest, SceneAsMgfInMetres) {
  if (!HaveNumpy()) GTEST_SKIP() << "numpy missing (tools/install-deps --reference)";
  TempDir dir;
  WriteFile(dir.File("s.mtl"), "newmtl grey\nKd 0.5 0.5 0.5\nKe 2 2 2\n");
  WriteFile(dir.File("s.obj"),
            "mtllib s.mtl\nusemtl grey\nv 0 0 0\nv 1000 0 0\nv 1000 2000 0\nf 1 2 3\n");
  ASSERT_EQ(RunCommand("tools/renderpark-run mgf " + dir.File("s.obj") + " --out " +
                       dir.File("s.mgf") + " 2> " + dir.File("err.txt")),
            0)
      << ReadFile(dir.File("err.txt"));
  std::string mgf = ReadFile(dir.File("s.mgf"));
  for (const char* line : {"m m0 =\n", "\t\tcxy 0.333333 0.333333\n\trd 0.500000\n",
                           "\ted 366.140000\n", "v v2 =\n\tp 1 2 0\n", "m m0\nf v0 v1 v2\n"})
    EXPECT_NE(mgf.find(line), std::string::npos) << line << "\nin\n" << mgf;
}

TEST(RenderparkRunTest, RgbeAsPfm) {
  if (!HaveNumpy()) GTEST_SKIP() << "numpy missing (tools/install-deps --reference)";
  TempDir dir;
  // 8 x 2: the top row run-length (each channel one run of 8), the bottom
  // row flat. RGBE (r, g, b, e) is (r + 0.5, ...) * 2^(e - 136).
  std::string pic = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 8\n";
  pic += std::string("\x02\x02\x00\x08", 4);
  for (unsigned char v : {127, 63, 31, 129}) pic += std::string{char(128 + 8), char(v)};
  for (int x = 0; x < 8; ++x) pic += std::string{char(127), char(0), char(0), char(130)};
  WriteFile(dir.File("a.pic"), pic);
  ASSERT_EQ(
      RunCommand("tools/renderpark-run pfm " + dir.File("a.pic") + " --out " + dir.File("a.pfm")),
      0);
  std::string pfm = ReadFile(dir.File("a.pfm"));
  std::string header = "PF\n8 2\n-1.0\n";
  ASSERT_EQ(pfm.size(), header.size() + 8 * 2 * 3 * 4);
  ASSERT_EQ(pfm.substr(0, header.size()), header);
  float px[48];
  std::memcpy(px, pfm.data() + header.size(), sizeof px);
  // The file's first row is the image's bottom: the flat row, e = 130.
  EXPECT_FLOAT_EQ(px[0], 127.5f / 64.0f);
  EXPECT_FLOAT_EQ(px[1], 0.5f / 64.0f);
  // The top row: e = 129.
  EXPECT_FLOAT_EQ(px[24], 127.5f / 128.0f);
  EXPECT_FLOAT_EQ(px[25], 63.5f / 128.0f);
  EXPECT_FLOAT_EQ(px[47], 31.5f / 128.0f);
  EXPECT_FALSE(FileExists(dir.File("a.pfm.tmp")));
}

}  // namespace
}  // namespace vismask
