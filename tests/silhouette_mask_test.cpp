// tools/silhouette-mask (issue 41): on a synthetic scene whose edges fall
// between pixel centres, the mask is exactly the pixels within 1 px of them;
// coplanar faces of one material draw no edge; --exclude adds its pixels;
// a mismatched --exclude is refused with nothing written.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "test_util.h"

namespace vismask {
namespace {

using test::FileExists;
using test::HaveNumpy;
using test::ReadFile;
using test::RunShell;
using test::Shell;
using test::TempDir;
using test::WriteFile;

// A 16x16 view from the origin down +z, 90 degrees: pixel x's centre ray
// crosses z = 10 at x = 1.25 (x + 0.5 - 8). The back wall (z = 20, two
// coplanar triangles, one material) fills the view; a square at z = 10 over
// [-5, 5]^2 covers exactly the pixel centres 4..11 in both directions.
const char* kCamera = "0,0,0,0,0,1,0,1,0,90";

void WriteScene(const TempDir& dir) {
  WriteFile(dir.File("s.mtl"),
            "newmtl wall\nKd 0.5 0.5 0.5\nKe 1 1 1\nnewmtl box\nKd 0.5 0.5 0.5\n");
  WriteFile(dir.File("s.obj"),
            "mtllib s.mtl\n"
            "usemtl wall\n"
            "v -100 -100 20\nv 100 -100 20\nv 100 100 20\nv -100 100 20\n"
            "f 1 2 3\nf 1 3 4\n"
            "usemtl box\n"
            "v -5 -5 10\nv 5 -5 10\nv 5 5 10\nv -5 5 10\n"
            "f 5 6 7 8\n");
}

// The PGM's pixels (its last w*h bytes), nonzero as '1'.
std::string Pixels(const std::string& pgm, int w, int h) {
  std::string bytes = ReadFile(pgm);
  EXPECT_EQ(bytes.substr(0, 2), "P5");
  std::string out;
  for (char c : bytes.substr(bytes.size() - size_t(w * h))) out += c ? '1' : '0';
  return out;
}

TEST(SilhouetteMaskTest, MarksExactlyThePixelsWithin1PxOfAnEdge) {
  if (!HaveNumpy()) GTEST_SKIP() << "numpy missing (tools/install-deps --reference)";
  TempDir dir;
  WriteScene(dir);
  Shell r = RunShell("tools/silhouette-mask " + dir.File("s.obj") + " --camera " + kCamera +
                     " --size 16 16 --out " + dir.File("m.pgm"));
  ASSERT_EQ(r.code, 0) << r.out;
  std::string got = Pixels(dir.File("m.pgm"), 16, 16);
  std::string want;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      bool ring = x >= 3 && x <= 12 && y >= 3 && y <= 12;
      bool inner = x >= 5 && x <= 10 && y >= 5 && y <= 10;
      want += ring && !inner ? '1' : '0';
    }
  EXPECT_EQ(got, want);
  EXPECT_NE(r.out.find("silhouette pixels 64 (25.00%)"), std::string::npos) << r.out;

  // --exclude adds its pixels: one corner pixel, far from any edge.
  std::string base = "P5\n16 16\n255\n" + std::string(256, '\0');
  base[base.size() - 256] = char(255);
  WriteFile(dir.File("base.pgm"), base);
  r = RunShell("tools/silhouette-mask " + dir.File("s.obj") + " --camera " + kCamera +
               " --size 16 16 --exclude " + dir.File("base.pgm") + " --out " + dir.File("m2.pgm"));
  ASSERT_EQ(r.code, 0) << r.out;
  want[0] = '1';
  EXPECT_EQ(Pixels(dir.File("m2.pgm"), 16, 16), want);
  EXPECT_NE(r.out.find("left out with --exclude 65 (25.39%)"), std::string::npos) << r.out;
}

TEST(SilhouetteMaskTest, RefusesAMismatchedExcludeAndWritesNothing) {
  if (!HaveNumpy()) GTEST_SKIP() << "numpy missing (tools/install-deps --reference)";
  TempDir dir;
  WriteScene(dir);
  WriteFile(dir.File("base.pgm"), "P5\n8 8\n255\n" + std::string(64, '\0'));
  Shell r =
      RunShell("tools/silhouette-mask " + dir.File("s.obj") + " --camera " + kCamera +
               " --size 16 16 --exclude " + dir.File("base.pgm") + " --out " + dir.File("m.pgm"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("8x8, not 16x16"), std::string::npos) << r.out;
  EXPECT_FALSE(FileExists(dir.File("m.pgm")));
  EXPECT_FALSE(FileExists(dir.File("m.pgm.tmp")));
}

}  // namespace
}  // namespace vismask
