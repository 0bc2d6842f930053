// Hostile use (issue 17): closed standard descriptors, and the like. Each
// case here once gave a wrong result, a lost output or a crash.
#include <cstdlib>
#include <string>

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

}  // namespace
}  // namespace vismask
