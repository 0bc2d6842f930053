// The coarse-scale error measure of make parallel (tools/parallel,
// vismask_tools/coarse.py): block means, the reference's noise from its
// halves falling k times under k x k blocks, a patch-scale error staying,
// and blocks with an excluded pixel left out, on synthetic images.
#include <gtest/gtest.h>

#include <string>

#include "test_util.h"

namespace vismask {
namespace {

using test::HaveNumpy;
using test::RunShell;
using test::Shell;

TEST(CoarseScaleTest, SelftestOnSyntheticImages) {
  if (!HaveNumpy()) GTEST_SKIP() << "numpy missing (tools/install-deps --reference)";
  Shell r = RunShell("tools/parallel --selftest");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("tools/parallel --selftest: 0 failed"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace vismask
