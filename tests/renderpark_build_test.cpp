// tools/renderpark-build (issue 41) without building anything: it skips with
// a clear line when RPK_SRC is absent, and refuses (exit 2, nothing built) a
// source whose optionsGetArgumentIntValue is not the one it knows how to fix.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>

#include "test_util.h"

namespace vismask {
namespace {

using test::FileExists;
using test::RunShell;
using test::Shell;
using test::TempDir;
using test::WriteFile;

TEST(RenderparkBuildTest, SkipsWithoutTheSource) {
  TempDir dir;
  Shell r = RunShell("unset RPK_SRC; tools/renderpark-build --out " + dir.File("rp"));
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("skipped: RPK_SRC is not a checkout"), std::string::npos) << r.out;
  EXPECT_FALSE(FileExists(dir.File("rp")));
}

TEST(RenderparkBuildTest, RefusesASourceItCannotFix) {
  TempDir dir;
  ASSERT_EQ(mkdir(dir.File("rpk").c_str(), 0755), 0);
  ASSERT_EQ(mkdir(dir.File("rpk/src").c_str(), 0755), 0);
  ASSERT_EQ(mkdir(dir.File("rpk/src/app").c_str(), 0755), 0);
  ASSERT_EQ(mkdir(dir.File("rpk/etc").c_str(), 0755), 0);
  WriteFile(dir.File("rpk/CMakeLists.txt"), "project(rpk)\n");
  WriteFile(dir.File("rpk/src/app/options.cpp"),
            "static bool optionsGetArgumentIntValue(int *res) { return false; }\n");
  Shell r =
      RunShell("RPK_SRC=" + dir.File("rpk") + " tools/renderpark-build --out " + dir.File("rp"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("is not the one of rpkCpp 37e5ff4e"), std::string::npos) << r.out;
  EXPECT_FALSE(FileExists(dir.File("rp/build")));
}

}  // namespace
}  // namespace vismask
