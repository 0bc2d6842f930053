// Hostile use (issue 17): closed standard descriptors, and the like. Each
// case here once gave a wrong result, a lost output or a crash.
#include <cstdlib>
#include <string>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include "test_util.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::TempDir;

std::string Bin() {
  const char* b = std::getenv("VISMASK_BIN");
  return b ? b : "build/vismask";
}

// With descriptor 0, 1 or 2 closed, the first output file opened used to get
// that number: with 2>&- the progress lines went into image.png.
TEST(HardeningTest, ClosedStandardDescriptorsNeverBecomeOutputs) {
  TempDir dir;
  for (const char* redirect : {"2>&-", "1>&- 2>&-", "0<&- 1>&- 2>&-"}) {
    std::string out = dir.File("out");
    std::string cmd = Bin() + " render scenes/cornell.obj --width 32 --height 32 --max-shots 300 --out " +
                      out + " " + redirect;
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::string png = ReadFile(out + "/image.png");
    ASSERT_GE(png.size(), 8u) << redirect;
    EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << redirect;
    std::string pfm = ReadFile(out + "/image.pfm");
    EXPECT_EQ(pfm.substr(0, 3), "PF\n") << redirect;
    EXPECT_EQ(ReadFile(out + "/run.json").substr(0, 1), "{") << redirect;
  }
}

// Memory the budget allowed but the system refuses (ulimit -v here) is a
// user error that names the bytes (exit 2, no outputs), not a CHECK (134).
TEST(HardeningTest, RefusedArenaMemoryIsAUserError) {
  TempDir dir;
  const std::string cases[] = {
      "--width 16384 --height 16384",                     // the rank's buffers
      "--round-shots 1000000 --envs 2 --ranks 2",         // the environments' arenas
  };
  for (const std::string& extra : cases) {
    std::string out = dir.File("out");
    std::string cmd = "(ulimit -v 4000000; " + Bin() + " render scenes/cornell.obj " + extra +
                      " --out " + out + " 2> " + dir.File("err") + ")";
    int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status)) << cmd;
    EXPECT_EQ(WEXITSTATUS(status), 2) << cmd << "\n" << ReadFile(dir.File("err"));
    std::string err = ReadFile(dir.File("err"));
    EXPECT_NE(err.find("the system refused"), std::string::npos) << err;
    EXPECT_NE(err.find(" bytes for "), std::string::npos) << err;
    EXPECT_EQ(err.find("internal error"), std::string::npos) << err;
    EXPECT_FALSE(test::FileExists(out)) << extra;
  }
}

}  // namespace
}  // namespace vismask
