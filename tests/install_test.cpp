// make install / make uninstall (issue 21): into a temporary DESTDIR, the
// files where a Debian tool has them, the installed binary finding its own
// viewer page (and serving its three.js files), then nothing left.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include "test_util.h"
#include "vismask/app/options_table.h"

namespace vismask {
namespace {

using test::FileExists;
using test::ReadFile;
using test::TempDir;
using test::VismaskBin;
namespace fs = std::filesystem;

// A shell command, stopped after 300 s.
int Sh(const std::string& cmd, std::string* out) {
  return test::ShellOutput(cmd, 300, out);
}

// make in the source tree, outside the make that runs the suite (its
// jobserver and flags are not for this one); VISMASK_MAKE_ARGS (set by make
// test) names the build being tested: BUILD=... SAN=... DEBUG=...
int Make(const std::string& args, std::string* out) {
  const char* extra = std::getenv("VISMASK_MAKE_ARGS");
  return Sh("env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make --no-print-directory " +
                std::string(extra ? extra : "") + " " + args,
            out);
}

TEST(InstallTest, InstallsFindsItsPageAndUninstalls) {
  for (const char* tool : {"help2man", "python3"})
    if (std::system((std::string("command -v ") + tool + " >/dev/null").c_str()) != 0)
      GTEST_SKIP() << tool << " not found (tools/install-deps installs it)";
  if (!FileExists("viewer/node_modules/three/package.json"))
    GTEST_SKIP() << "viewer/node_modules/three missing (npm ci in viewer/: tools/install-deps)";
  TempDir dir;
  const std::string dest = dir.File("dest"), prefix = "/usr/local", root = dest + prefix;
  std::string log;
  ASSERT_EQ(Make("install PREFIX=" + prefix + " DESTDIR=" + dest, &log), 0) << log;

  // The files, as a Debian tool lays them out.
  const bool mpi = FileExists(fs::path(VismaskBin()).parent_path().string() + "/vismask-mpi");
  EXPECT_EQ(ReadFile(root + "/bin/vismask"), ReadFile(VismaskBin()));
  EXPECT_TRUE(fs::status(root + "/bin/vismask").permissions() == fs::perms(0755));
  EXPECT_EQ(FileExists(root + "/bin/vismask-mpi"), mpi);
  for (const char* f : {"index.html", "viewer.js", "serve.py"})
    EXPECT_EQ(ReadFile(root + "/share/vismask/viewer/" + f), ReadFile(std::string("viewer/") + f))
        << f;
  // Every module the page imports, so that the installed viewer works offline.
  for (const char* f : {"three.module.js", "three.core.js", "LICENSE",
                        "addons/loaders/GLTFLoader.js", "addons/controls/OrbitControls.js",
                        "addons/utils/BufferGeometryUtils.js", "addons/utils/SkeletonUtils.js"})
    EXPECT_GT(ReadFile(root + "/share/vismask/viewer/vendor/" + f).size(), 0u) << f;
  std::string man = ReadFile(root + "/share/man/man1/vismask.1");
  EXPECT_NE(man.find(".TH VISMASK \"1\""), std::string::npos);
  EXPECT_NE(man.find("vismask view OUT_DIR"), std::string::npos);
  // Made from --help all, so from the option table: every option is in it
  // (help2man writes '-' as "\-").
  for (const OptionSpec& s : OptionTable()) {
    std::string name;
    for (const char* c = s.name; *c; ++c)
      name += *c == '-' ? std::string("\\-") : std::string(1, *c);
    EXPECT_NE(man.find(name), std::string::npos) << s.name;
  }
  EXPECT_EQ(FileExists(root + "/share/man/man1/vismask-mpi.1"), mpi);

  // The installed binary finds the installed page (nothing else lies beside
  // it: DESTDIR holds no source tree) and serves its three.js files.
  TempDir out;
  std::string glb("glTF\x02\x00\x00\x00\x0c\x00\x00\x00", 12);
  test::WriteFile(out.File("m.glb"), glb);
  std::string cmd = root + "/bin/vismask view " + out.path() + " > " + dir.File("view.out") +
                    " 2> " + dir.File("view.err") + " & echo $!";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  int pid = -1;
  ASSERT_EQ(std::fscanf(p, "%d", &pid), 1);
  pclose(p);
  std::string url;
  for (int i = 0; i < 600 && url.empty(); ++i) {
    std::string text = ReadFile(dir.File("view.out"));
    if (text.find('\n') != std::string::npos)
      url = text.substr(0, text.find('\n'));
    else
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::string origin = url.substr(0, url.find('/', 7)), fetched;
  int fetch =
      Sh("python3 -c 'import sys, urllib.request; "
         "sys.stdout.buffer.write(urllib.request.urlopen(sys.argv[1]).read())' " +
             origin + "/vendor/three.module.js > " + dir.File("fetched"),
         &fetched);
  std::string err = ReadFile(dir.File("view.err"));
  ::kill(pid, SIGTERM);
  ASSERT_FALSE(url.empty()) << err;
  EXPECT_EQ(fetch, 0) << fetched;
  EXPECT_EQ(ReadFile(dir.File("fetched")),
            ReadFile(root + "/share/vismask/viewer/vendor/three.module.js"));
  const std::string served = fs::weakly_canonical(root + "/share/vismask/viewer").string();
  EXPECT_NE(err.find("serving " + root + "/bin/../share/vismask/viewer"), std::string::npos)
      << err << " (expected " << served << ")";

  log.clear();
  ASSERT_EQ(Make("uninstall PREFIX=" + prefix + " DESTDIR=" + dest, &log), 0) << log;
  EXPECT_FALSE(FileExists(root + "/bin/vismask"));
  EXPECT_FALSE(FileExists(root + "/bin/vismask-mpi"));
  EXPECT_FALSE(FileExists(root + "/share/vismask"));
  EXPECT_FALSE(FileExists(root + "/share/man/man1/vismask.1"));
  EXPECT_FALSE(FileExists(root + "/share/man/man1/vismask-mpi.1"));
  // What is left is empty directories only.
  for (const auto& e : fs::recursive_directory_iterator(dest))
    EXPECT_TRUE(e.is_directory()) << e.path() << " left after make uninstall";
}

}  // namespace
}  // namespace vismask
