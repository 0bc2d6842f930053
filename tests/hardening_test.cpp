// Hostile use (issue 17): closed standard descriptors, and the like. Each
// case here once gave a wrong result, a lost output or a crash.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/core/check.h"
#include "vismask/core/os.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::TempDir;
using test::VismaskBin;

// With descriptor 0, 1 or 2 closed, the first output file opened used to get
// that number: with 2>&- the progress lines went into image.png.
TEST(HardeningTest, ClosedStandardDescriptorsNeverBecomeOutputs) {
  TempDir dir;
  for (const char* redirect : {"2>&-", "1>&- 2>&-", "0<&- 1>&- 2>&-"}) {
    std::string out = dir.File("out");
    std::string cmd = VismaskBin() +
                      " render scenes/cornell.obj --width 32 --height 32 --max-shots 300 --out " +
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
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "ulimit -v cannot apply under AddressSanitizer (it reserves its shadow memory up "
                  "front and aborts)";
#endif
  TempDir dir;
  const std::string cases[] = {
      // --mem-budget above what ulimit -v lets the system give: the budget
      // passes, the allocation fails.
      "--width 16384 --height 16384 --mem-budget 100G",              // the rank's buffers
      "--round-shots 1000000 --envs 2 --ranks 2 --mem-budget 100G",  // the environments' arenas
  };
  for (const std::string& extra : cases) {
    std::string out = dir.File("out");
    std::string cmd = "(ulimit -v 4000000; " + VismaskBin() + " render scenes/cornell.obj " +
                      extra + " --out " + out + " 2> " + dir.File("err") + ")";
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

// A failed CHECK_EQ, or an abort() anywhere (a library's assertion), leaves
// no temporary output behind, as a failed CHECK does.
TEST(HardeningDeathTest, FailedChecksAndAbortsRemoveTemporaryFiles) {
  for (int how = 0; how < 3; ++how) {
    TempDir dir;
    auto writeThenFail = [&] {
      os::OutFile f;
      char why[os::kWhyBytes] = "";
      if (!f.Open(dir.File("image.pfm").c_str(), why) || !f.Write("PF\n", 3)) return;
      if (how == 0) CHECK_EQ(2 + 2, 5);
      if (how == 1) CHECK(how == 0);
      std::abort();
    };
    EXPECT_DEATH(writeThenFail(), "") << how;
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                            std::filesystem::directory_iterator()),
              0)
        << how;
  }
}

// Outputs are committed as one: a rename that fails half-way puts back
// what every final name held (issue 17 item 4: image.png and image.pfm were
// already the new run's while run.json was still the old one's).
TEST(HardeningTest, CommitAllIsAllOrNothing) {
  TempDir dir;
  test::WriteFile(dir.File("a"), "old a");
  test::WriteFile(dir.File("c"), "old c");
  os::OutFile files[3];
  char why[os::kWhyBytes] = "";
  for (const char* name : {"a", "b", "c"}) {
    os::OutFile& f = files[name[0] - 'a'];
    ASSERT_TRUE(f.Open(dir.File(name).c_str(), why)) << why;
    ASSERT_TRUE(f.Write("new ", 4));
    ASSERT_TRUE(f.Write(name, 1));
  }
  // b becomes a non-empty directory after its file was opened.
  std::filesystem::create_directories(dir.File("b/inside"));
  EXPECT_FALSE(os::CommitAll(files, 3, why));
  EXPECT_NE(std::string(why).find(dir.File("b")), std::string::npos) << why;
  EXPECT_EQ(ReadFile(dir.File("a")), "old a");
  EXPECT_EQ(ReadFile(dir.File("c")), "old c");
  EXPECT_TRUE(std::filesystem::is_directory(dir.File("b/inside")));
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"a", "b", "c"}));
  // A rename that fails after others succeeded (c's temporary file gone):
  // a and b, already renamed, are put back (a to its old bytes, b removed).
  std::filesystem::remove_all(dir.File("b"));
  for (const char* name : {"a", "b", "c"}) {
    os::OutFile& f = files[name[0] - 'a'];
    ASSERT_TRUE(f.Open(dir.File(name).c_str(), why)) << why;
    ASSERT_TRUE(f.Write("new ", 4));
  }
  std::filesystem::remove(dir.File("c.tmp." + std::to_string(getpid())));
  EXPECT_FALSE(os::CommitAll(files, 3, why));
  EXPECT_NE(std::string(why).find("cannot rename"), std::string::npos) << why;
  EXPECT_EQ(ReadFile(dir.File("a")), "old a");
  EXPECT_FALSE(test::FileExists(dir.File("b")));
  EXPECT_EQ(ReadFile(dir.File("c")), "old c");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            2);
  // And without an obstacle, every file is the new one, nothing else left.
  for (const char* name : {"a", "b", "c"}) {
    os::OutFile& f = files[name[0] - 'a'];
    ASSERT_TRUE(f.Open(dir.File(name).c_str(), why)) << why;
    ASSERT_TRUE(f.Write("new ", 4));
    ASSERT_TRUE(f.Write(name, 1));
  }
  ASSERT_TRUE(os::CommitAll(files, 3, why)) << why;
  EXPECT_EQ(ReadFile(dir.File("a")), "new a");
  EXPECT_EQ(ReadFile(dir.File("b")), "new b");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            3);
}

// An output that cannot be replaced (a directory named patches.csv) is found
// at init, before the solve, and nothing of the previous run is touched.
TEST(HardeningTest, UnreplaceableOutputIsRefusedAtInit) {
  TempDir dir;
  std::string out = dir.File("out");
  const std::vector<std::string> run = {
      "render", "scenes/cornell.obj", "--width", "32",      "--height",
      "32",     "--max-shots",        "200",     "--quiet", "--out",
      out};
  ASSERT_EQ(test::RunMain(run).code, 0);
  std::string png = ReadFile(out + "/image.png"), json = ReadFile(out + "/run.json");
  std::filesystem::remove(out + "/patches.csv");
  std::filesystem::create_directories(out + "/patches.csv");
  auto second = run;
  second.insert(second.end(), {"--seed", "7"});
  auto r = test::RunMain(second);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("patches.csv' exists and is not a regular file"), std::string::npos)
      << r.err;
  EXPECT_EQ(ReadFile(out + "/image.png"), png);
  EXPECT_EQ(ReadFile(out + "/run.json"), json);
  for (const auto& e : std::filesystem::directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

// A second run into a directory in use is refused, naming the holder; the
// first run's outputs are its own (issue 17 item 3: two runs spliced
// patches.csv through fixed .tmp names).
TEST(HardeningTest, SecondRunIntoTheSameDirectoryIsRefused) {
  TempDir dir;
  std::string out = dir.File("out");
  std::string first = VismaskBin() +
                      " render scenes/cornell.obj --width 32 --height 32 --rays 4096 "
                      "--max-shots 1000000 --max-seconds 6 --quiet --out " +
                      out + " 2> " + dir.File("first.err") + " & echo $! > " + dir.File("pid");
  ASSERT_EQ(std::system(first.c_str()), 0);
  // Wait (up to 5 s) until the first run holds the lock.
  for (int i = 0; i < 100 && ReadFile(out + "/.vismask.lock").empty(); ++i) usleep(50000);
  std::string holder = ReadFile(out + "/.vismask.lock");
  ASSERT_FALSE(holder.empty());
  auto r = test::RunMain({"render", "scenes/cornell.obj", "--width", "16", "--height", "16",
                          "--max-shots", "10", "--quiet", "--out", out});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("is in use by another vismask run (pid " + holder + ")"), std::string::npos)
      << r.err;
  // The first run finishes with its own outputs.
  std::string pid = ReadFile(dir.File("pid"));
  std::string wait =
      "while kill -0 " + pid.substr(0, pid.find('\n')) + " 2>/dev/null; do sleep 0.1; done";
  ASSERT_EQ(std::system(wait.c_str()), 0);
  EXPECT_NE(ReadFile(out + "/run.json").find("\"width\": 32"), std::string::npos);
  EXPECT_EQ(ReadFile(out + "/image.pfm").substr(0, 9), "PF\n32 32\n");
}

// Issue 17 item 9: with no --mem-budget, the budget is the host's available
// memory over the ranks on it; a run beyond it is refused at init with the
// numbers instead of being killed by the kernel.
TEST(HardeningTest, DefaultBudgetIsTheAvailableMemory) {
  TempDir dir;
  // 64x64x64 environments and a 16384^2 image: some 60 GB a rank, beyond
  // the 24 GiB hosts this runs on.
  auto r = test::RunMain({"render", "scenes/cornell.obj", "--envs", "64x64x64", "--max-shots", "5",
                          "--rays", "64", "--width", "16384", "--height", "16384", "--quiet",
                          "--out", dir.File("out")});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("more than the memory available to it"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("MemAvailable over 1 rank on this host"), std::string::npos) << r.err;
  EXPECT_FALSE(test::FileExists(dir.File("out")));
  // An explicit budget is the user's word: the same run is then judged by it.
  r = test::RunMain({"render", "scenes/cornell.obj", "--envs", "64x64x64", "--max-shots", "5",
                     "--rays", "64", "--quiet", "--mem-budget", "1G", "--out", dir.File("out")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("more than the budget of 1073741824 bytes"), std::string::npos) << r.err;
}

// Issue 17 item 10: a scene too big for the memory init may use ended in
// an uncaught bad_alloc (exit 134); it is refused with exit 2.
TEST(HardeningTest, SceneTooBigToLoadIsRefused) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "ulimit -v cannot apply under AddressSanitizer (it reserves its shadow memory up "
                  "front and aborts)";
#endif
  TempDir dir;
  std::string obj = "mtllib big.mtl\nusemtl light\n";
  const int n = 300000;
  char line[256];
  for (int i = 0; i < n; ++i) {
    double x = (i % 97) * 1.01, y = (i / 97 % 97) * 1.01, z = (i / 9409) * 1.01;
    std::snprintf(line, sizeof line, "v %g %g %g\nv %g %g %g\nv %g %g %g\n", x, y, z, x + 1, y, z,
                  x, y + 1, z);
    obj += line;
  }
  for (int i = 0; i < n; ++i) {
    std::snprintf(line, sizeof line, "f %d %d %d\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    obj += line;
  }
  test::WriteFile(dir.File("big.obj"), obj);
  test::WriteFile(dir.File("big.mtl"), "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  std::string cmd = "(ulimit -v 250000; " + VismaskBin() + " render " + dir.File("big.obj") +
                    " --quiet --out " + dir.File("out") + " 2> " + dir.File("err") + ")";
  int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2) << ReadFile(dir.File("err"));
  std::string err = ReadFile(dir.File("err"));
  EXPECT_TRUE(err.find("out of memory at init") != std::string::npos ||
              err.find("the system refused") != std::string::npos)
      << err;
  EXPECT_FALSE(test::FileExists(dir.File("out")));
}

// Issue 17 items 14 and 15: values that silently became something else, and
// messages that misled.
TEST(HardeningTest, OptionsThatUnderflowOrLookLikeOptionsAreRefused) {
  TempDir dir;
  struct Case {
    std::vector<std::string> args;
    std::string message;
  } cases[] = {
      {{"render", "scenes/cornell.obj", "--patch-size", "1e-50"}, "a length float can hold"},
      {{"render", "scenes/cornell.obj", "--exposure", "1e-50"}, "a number float can hold"},
      {{"render", "scenes/cornell.obj", "--json"}, "--json is an option of 'vismask footprint'"},
      {{"render", "scenes/cornell.obj", "--out", "--quiet"},
       "--out: missing value (the next argument is the option '--quiet')"},
  };
  for (const Case& c : cases) {
    auto args = c.args;
    if (args.back() != "--quiet") args.insert(args.end(), {"--out", dir.File("out")});
    auto r = test::RunMain(args);
    EXPECT_EQ(r.code, 2) << c.message;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_FALSE(test::FileExists(dir.File("out")));
    EXPECT_FALSE(test::FileExists("--quiet"));
  }
}

// footprint --json printed the scene's path unescaped: invalid JSON.
TEST(HardeningTest, FootprintJsonEscapesTheScenePath) {
  TempDir dir;
  std::string odd = dir.File("q\"x\\y.obj");
  std::filesystem::copy_file("scenes/cornell.obj", odd);
  std::filesystem::copy_file("scenes/cornell.mtl", dir.File("cornell.mtl"));
  std::string cmd = VismaskBin() + " footprint '" + odd + "' --json > " + dir.File("fp.json");
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::string json = ReadFile(dir.File("fp.json"));
  EXPECT_NE(json.find("q\\\"x\\\\y.obj\""), std::string::npos) << json.substr(0, 200);
  if (std::system("command -v /usr/bin/python3 > /dev/null") == 0) {
    std::string check = "/usr/bin/python3 -c 'import json,sys; json.load(open(sys.argv[1]))' " +
                        dir.File("fp.json");
    EXPECT_EQ(std::system(check.c_str()), 0) << json.substr(0, 200);
  }
}

}  // namespace
}  // namespace vismask
