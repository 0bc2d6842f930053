// The sun room and its edge measure (issue 41's sun-shadow goal; the
// experiments' sun step): tools/sun-edge's selftest on synthetic ramps of
// known width, tools/gen-sunroom's bytes the same each time, and the sunlit
// patch of a small vismask render where the geometry says it is (a rise
// found across each of its four edges).
#include <gtest/gtest.h>

#include <string>

#include "test_util.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::RunShell;
using test::Shell;
using test::TempDir;
using test::VismaskBin;

TEST(SunEdgeTest, SelftestOnSyntheticRamps) {
  Shell r = RunShell("tools/sun-edge --selftest");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("tools/sun-edge --selftest: 0 failed"), std::string::npos) << r.out;
}

TEST(SunEdgeTest, GenSunroomIsDeterministic) {
  TempDir dir;
  ASSERT_EQ(RunShell("tools/gen-sunroom --out " + dir.File("a.obj")).code, 0);
  ASSERT_EQ(RunShell("tools/gen-sunroom --out " + dir.File("b.obj")).code, 0);
  std::string a = ReadFile(dir.File("a.obj"));
  EXPECT_NE(a.find("mtllib a.mtl"), std::string::npos);
  EXPECT_EQ(a.substr(a.find('\n', a.find("mtllib"))),
            ReadFile(dir.File("b.obj")).substr(a.find('\n', a.find("mtllib"))));
  EXPECT_EQ(ReadFile(dir.File("a.mtl")), ReadFile(dir.File("b.mtl")));
  EXPECT_EQ(RunShell("tools/gen-sunroom --bogus").code, 2);
}

TEST(SunEdgeTest, TheSunlitPatchIsWhereTheGeometrySays) {
  TempDir dir;
  ASSERT_EQ(RunShell("tools/gen-sunroom --out " + dir.File("room.obj")).code, 0);
  const std::string camera = RunShell("tools/gen-sunroom --camera").out;
  const std::string sun = RunShell("tools/gen-sunroom --sun").out;
  Shell r =
      RunShell(VismaskBin() + " render " + dir.File("room.obj") + " --camera " +
               camera.substr(0, camera.find('\n')) + " --sun " + sun.substr(0, sun.find('\n')) +
               " --width 128 --height 96 --emitted-rays 100000 --quiet --out " + dir.File("out"));
  ASSERT_EQ(r.code, 0) << r.out;
  r = RunShell("tools/sun-edge " + dir.File("out/image.pfm"));
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* edge : {"sill", "north jamb", "lintel", "south jamb"}) {
    size_t at = r.out.find(std::string(edge) + ": ");
    ASSERT_NE(at, std::string::npos) << edge << "\n" << r.out;
    double px = std::stod(r.out.substr(at + std::string(edge).size() + 2));
    // A rise was found (not nan), no wider than the profile's reach.
    EXPECT_GT(px, 0.0) << edge << "\n" << r.out;
    EXPECT_LT(px, 4.0) << edge << "\n" << r.out;
  }
}

}  // namespace
}  // namespace vismask
