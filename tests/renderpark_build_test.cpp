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
using test::TempDir;
using test::WriteFile;

struct Shell {
  int code = -1;
  std::string out;  // stdout and stderr
};

Shell RunShell(const std::string& cmd) {
  Shell r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

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
