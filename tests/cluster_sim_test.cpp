// tools/cluster-sim's safe paths: --help, option errors (checked before it
// touches anything), and the refusal to run without root. The namespace run
// itself is not here: it needs root and takes minutes (make cluster-experiments).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "test_util.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::RunShell;
using test::Shell;
using test::TempDir;
using test::WriteFile;

TEST(ClusterSimTest, HelpSaysHowToRunIt) {
  Shell r = RunShell("tools/cluster-sim --help");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("usage: sudo tools/cluster-sim --nodes N --link 100mbit|1gbit"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("--mem SIZE"), std::string::npos) << r.out;
}

TEST(ClusterSimTest, BadOptionsExitTwoBeforeAnythingIsMade) {
  const struct {
    const char* args;
    const char* message;
  } cases[] = {
      {"--nodes 0 --link 100mbit -- render scenes/cornell.obj", "--nodes: expected 1..200"},
      {"--nodes 2 --link 10mbps -- render scenes/cornell.obj", "--link: expected 100mbit, 1gbit"},
      {"--nodes 2 --link 1gbit --latency fast -- render scenes/cornell.obj", "--latency: expected"},
      {"--nodes 2 --link 1gbit --mem 64M -- render scenes/cornell.obj",
       "--mem: must be more than --os-reserve"},
      {"--nodes 2 --link 1gbit --mem 1G -- render scenes/cornell.obj --mem-budget 1M",
       "--mem sets vismask's --mem-budget"},
      {"--nodes 2 --link 1gbit", "nothing to run"},
      {"--nodes 2 --link 1gbit --envs 4", "--envs: unknown option"},
  };
  for (const auto& c : cases) {
    Shell r = RunShell(std::string("tools/cluster-sim ") + c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(std::string("tools/cluster-sim: ") + c.message), std::string::npos)
        << c.args << "\n"
        << r.out;
  }
}

TEST(ClusterSimTest, RefusesToRunWithoutRoot) {
  // A copy under /tmp, so that an unprivileged user can read it wherever the
  // checkout is; as root, run it as nobody (setpriv, util-linux).
  TempDir dir;
  ASSERT_EQ(chmod(dir.path().c_str(), 0755), 0);
  ASSERT_EQ(mkdir(dir.File("tools").c_str(), 0755), 0);
  std::string script = dir.File("tools/cluster-sim");
  WriteFile(script, ReadFile("tools/cluster-sim"));
  ASSERT_EQ(chmod(script.c_str(), 0755), 0);
  std::string cmd = "cd " + dir.path() + " && ";
  if (getuid() == 0) cmd += "setpriv --reuid=65534 --regid=65534 --clear-groups ";
  cmd += "tools/cluster-sim --nodes 2 --link 100mbit -- render scenes/cornell.obj --envs 2";
  Shell r = RunShell(cmd);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("tools/cluster-sim: must run as root"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace vismask
