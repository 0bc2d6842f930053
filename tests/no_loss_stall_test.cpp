// The no-loss stall (issue 40): power that goes round a cavity closed by
// faces of Kd 1, while the rest of the scene absorbs (so the scene-wide
// check passes it), stops the solve with exit 4 and a message instead of
// running forever; a bound of the user's own still gets its outputs, and a
// stiff but lossy cavity still converges.
#include <gtest/gtest.h>

#include <string>

#include "test_util.h"
#include "vismask/solve/solver.h"

namespace vismask {
namespace {

using test::TempDir;

// A closed unit cube of Kd `kd` (faces in), one face its lamp, and a floor
// of Kd 0.5 elsewhere: the scene can lose power, the cube cannot when kd is 1.
void WriteCavity(const TempDir& dir, const std::string& kd) {
  test::WriteFile(dir.File("c.mtl"), "newmtl mirror\nKd " + kd + " " + kd + " " + kd +
                                         "\nnewmtl lamp\nKd " + kd + " " + kd + " " + kd +
                                         "\nKe 1 1 1\nnewmtl floor\nKd 0.5 0.5 0.5\n");
  test::WriteFile(dir.File("c.obj"),
                  "mtllib c.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\n"
                  "v 0 1 1\nusemtl mirror\nf 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 1 4 8 5\nf 2 6 7 3\n"
                  "usemtl lamp\nf 4 3 7 8\nusemtl floor\nv 3 0 0\nv 4 0 0\nv 4 0 1\nv 3 0 1\n"
                  "f 9 12 11 10\n");
}

// Runs the binary (under a time limit: a solve that never stops fails the
// test instead of hanging it).
int RunCavity(const TempDir& dir, const std::string& extra, std::string* out) {
  return test::ShellOutput(test::VismaskBin() + " render " + dir.File("c.obj") + " --out " +
                               dir.File("out") +
                               " --emitted-rays 2000 --width 32 --height 32 --quiet " + extra,
                           120, out);
}

TEST(NoLossStallTest, ACavityOfKdOneStopsWithExitFourAndNothingWritten) {
  TempDir dir;
  WriteCavity(dir, "1");
  for (const char* extra : {"", "--envs 2 --ranks 2", "--envs 2 --mask-method R"}) {
    std::string out;
    EXPECT_EQ(RunCavity(dir, extra, &out), 4) << extra << "\n" << out;
    EXPECT_NE(out.find("vismask: the solve stalled after "), std::string::npos) << out;
    EXPECT_NE(out.find("not down by 1% of itself, while 20 times as much power was shot"),
              std::string::npos)
        << out;
    EXPECT_FALSE(test::FileExists(dir.File("out/image.pfm")));
    EXPECT_FALSE(test::FileExists(dir.File("out/run.json")));
  }
  // A bound of the user's own: the solve runs to it and writes its outputs.
  std::string out;
  EXPECT_EQ(RunCavity(dir, "--max-shots 4000", &out), 0) << out;
  EXPECT_NE(test::ReadFile(dir.File("out/run.json")).find("\"stop_reason\": \"max-shots\""),
            std::string::npos);
}

// Kd 0.99 keeps 99% of each shot: the unshot power falls by 20% of the
// emitted in a window, and the cavity converges.
TEST(NoLossStallTest, AStiffButLossyCavityConverges) {
  TempDir dir;
  WriteCavity(dir, "0.99");
  std::string out;
  EXPECT_EQ(RunCavity(dir, "--stop-unshot 0.05", &out), 0) << out;
  EXPECT_NE(test::ReadFile(dir.File("out/run.json")).find("\"stop_reason\": \"converged\""),
            std::string::npos);
}

}  // namespace
}  // namespace vismask
