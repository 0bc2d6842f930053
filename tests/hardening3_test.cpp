// Hostile use, part 3 (issue 42): unbounded reads, budgets checked too late,
// outputs opened through symbolic links, the commit and its leftovers. Each
// case here once hung, ran out of memory, wrote where it should not, or
// exited 0 having written nothing.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/core/os.h"
#include "vismask/scene/texture.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::TempDir;
using test::VismaskBin;
using test::WriteFile;

// scenes/textured copied into `dir`, its MTL's first map_Kd naming `map`.
std::string TexturedRoom(const TempDir& dir, const std::string& map) {
  for (const char* f : {"room.obj", "checker.png", "stripes.png"})
    std::filesystem::copy_file(std::string("scenes/textured/") + f, dir.File(f));
  std::string mtl = ReadFile("scenes/textured/room.mtl");
  const std::string from = "map_Kd checker.png";
  mtl.replace(mtl.find(from), from.size(), "map_Kd " + map);
  WriteFile(dir.File("room.mtl"), mtl);
  return dir.File("room.obj");
}

// The line of `room.mtl` in `dir` that holds `text`.
int LineOf(const std::string& file, const std::string& text) {
  const std::string all = ReadFile(file);
  int line = 1;
  for (size_t i = 0; i < all.find(text); ++i) line += all[i] == '\n';
  return line;
}

// A render of `obj` run as its own process (under a time limit, and a
// memory limit where the sanitizers allow one): exit status and stderr.
int RenderShell(const TempDir& dir, const std::string& obj, const std::string& extra,
                std::string* err, int seconds = 30) {
  std::string limit = "ulimit -v 3000000; ";
#if defined(__SANITIZE_ADDRESS__)
  limit = "";
#endif
  const std::string cmd = "sh -c '" + limit + "exec " + VismaskBin() + " render " + obj +
                          " --width 16 --height 16 --max-shots 50 --quiet " + extra + " --out " +
                          dir.File("out") + "'";
  err->clear();
  return test::ShellOutput(cmd, seconds, err);
}

// Item 1: a texture that is a device, a link to one, or a FIFO was read
// until memory ran out, or forever. It is refused at once by its kind, at
// its map_Kd line, before any output exists.
TEST(Hardening3Test, TextureThatIsADeviceOrAFifoIsRefusedByItsKind) {
  struct Case {
    std::string map, kind;
  };
  TempDir fifoDir;
  ASSERT_EQ(mkfifo(fifoDir.File("fifo.png").c_str(), 0600), 0);
  for (const Case& c :
       {Case{"/dev/zero", "a character device"}, Case{"zero.png", "a character device"},
        Case{fifoDir.File("fifo.png"), "a FIFO"}, Case{"sub", "a directory"}}) {
    TempDir dir;
    const std::string obj = TexturedRoom(dir, c.map);
    std::filesystem::create_symlink("/dev/zero", dir.File("zero.png"));
    std::filesystem::create_directory(dir.File("sub"));
    std::string err;
    const double t0 = os::Seconds();
    EXPECT_EQ(RenderShell(dir, obj, "", &err), 2) << c.map << "\n" << err;
    EXPECT_LT(os::Seconds() - t0, 10.0) << c.map;
    const std::string path = c.map[0] == '/' ? c.map : dir.File(c.map);
    const std::string where = dir.File("room.mtl") + ":" +
                              std::to_string(LineOf(dir.File("room.mtl"), "map_Kd " + c.map));
    EXPECT_NE(err.find(where + ": cannot read texture '" + path + "': not a regular file (" +
                       c.kind + ")"),
              std::string::npos)
        << err;
    EXPECT_FALSE(test::FileExists(dir.File("out"))) << c.map;
  }
}

// A PNG of w x h one-bit grey texels, all zero (a few kilobytes for many
// megatexels), written with zlib.
void WriteBlankPng(const std::string& path, uint32_t w, uint32_t h) {
  const size_t row = 1 + (w + 7) / 8;
  std::vector<unsigned char> raw(row * h, 0);
  uLongf zn = compressBound(raw.size());
  std::vector<unsigned char> z(zn);
  ASSERT_EQ(compress2(z.data(), &zn, raw.data(), raw.size(), 9), Z_OK);
  z.resize(zn);
  std::string png("\x89PNG\r\n\x1a\n", 8);
  auto be32 = [](std::string* s, uint32_t v) {
    for (int k = 3; k >= 0; --k) s->push_back(static_cast<char>((v >> (8 * k)) & 0xff));
  };
  auto chunk = [&](const char* type, const std::string& data) {
    be32(&png, static_cast<uint32_t>(data.size()));
    std::string body = std::string(type, 4) + data;
    png += body;
    be32(&png,
         static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(body.data()), body.size())));
  };
  std::string ihdr;
  be32(&ihdr, w);
  be32(&ihdr, h);
  ihdr +=
      std::string("\x01\x00\x00\x00\x00", 5);  // depth 1, grey, deflate, no filter, no interlace
  chunk("IHDR", ihdr);
  chunk("IDAT", std::string(z.begin(), z.end()));
  chunk("IEND", "");
  WriteFile(path, png);
}

// Item 2: a small PNG of 12000 x 12000 texels was decoded whole (over
// 400 MB) before --mem-budget refused the run. Its size is read from the
// header and judged first: refused at once, naming the texels and bytes.
TEST(Hardening3Test, TextureDecodingIsJudgedAgainstTheBudgetBeforeItIsDone) {
  TempDir dir;
  const std::string obj = TexturedRoom(dir, "big.png");
  WriteBlankPng(dir.File("big.png"), 12000, 12000);
  ASSERT_LT(ReadFile(dir.File("big.png")).size(), 100000u);
  std::string err;
  // 200 MB: far below the 432 MB of RGB texels alone.
  EXPECT_EQ(RenderShell(dir, obj, "--mem-budget 200M", &err), 2) << err;
  const uint64_t need =
      ReadFile(dir.File("big.png")).size() + kTextureDecodeBytesPerTexel * uint64_t{12000} * 12000;
  EXPECT_NE(err.find("cannot read texture '" + dir.File("big.png") +
                     "': decoding its 12000x12000 texels needs " + std::to_string(need) +
                     " bytes, more than the "),
            std::string::npos)
      << err;
  EXPECT_FALSE(test::FileExists(dir.File("out")));
  // The same texture is decoded under a budget that holds it (the file is
  // a valid image: what refused it above was the budget alone).
  TextureImage image;
  Status s = ReadTexture(dir.File("big.png"), "m.mtl:1", &image, need);
  EXPECT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(image.width, 12000u);
  s = ReadTexture(dir.File("big.png"), "m.mtl:1", &image, need - 1);
  EXPECT_FALSE(s.ok());
}

// One lit triangle, to which the cases below add.
const char kTriangle[] = "mtllib t.mtl\nusemtl light\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

// Item 2: a 300 MB comment line was held whole (exit 0 under a 100 MB
// budget), and 1 GB of NUL bytes was read as one line. The line buffer is
// bounded (a longer line is refused at its number) and a binary file is
// refused by its first kilobyte.
TEST(Hardening3Test, SceneLinesAreBoundedAndBinaryFilesRefusedAtOnce) {
  TempDir dir;
  WriteFile(dir.File("t.mtl"), "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  // A comment line of 3 MB (the bound, not the size, is what is tested).
  {
    FILE* f = std::fopen(dir.File("long.obj").c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs(kTriangle, f);
    const std::string block(size_t{1} << 20, '#');
    for (int i = 0; i < 3; ++i) std::fwrite(block.data(), 1, block.size(), f);
    std::fputs("\n", f);
    std::fclose(f);
  }
  std::string err;
  EXPECT_EQ(RenderShell(dir, dir.File("long.obj"), "--mem-budget 100M", &err), 2) << err;
  EXPECT_NE(err.find(dir.File("long.obj") + ":7: line longer than 1048576 bytes"),
            std::string::npos)
      << err;
  EXPECT_FALSE(test::FileExists(dir.File("out")));
  // A sparse gigabyte of NUL bytes: refused by its first kilobyte, at once.
  {
    FILE* f = std::fopen(dir.File("zeros.obj").c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fclose(f);
    std::filesystem::resize_file(dir.File("zeros.obj"), uintmax_t{1} << 30);
  }
  const double t0 = os::Seconds();
  EXPECT_EQ(RenderShell(dir, dir.File("zeros.obj"), "", &err), 2) << err;
  EXPECT_LT(os::Seconds() - t0, 5.0);
  EXPECT_NE(err.find(dir.File("zeros.obj") + ":1: not a text file (a NUL byte at byte 1)"),
            std::string::npos)
      << err;
  // A NUL later on the first kilobyte names its line; an MTL file too.
  WriteFile(dir.File("nul.obj"), std::string(kTriangle) + std::string("# \0 x\n", 6));
  EXPECT_EQ(RenderShell(dir, dir.File("nul.obj"), "", &err), 2) << err;
  EXPECT_NE(err.find(dir.File("nul.obj") + ":7: not a text file (a NUL byte at byte " +
                     std::to_string(std::string(kTriangle).size() + 3) + ")"),
            std::string::npos)
      << err;
  WriteFile(dir.File("t.mtl"), std::string("newmtl light\0", 13));
  WriteFile(dir.File("ok.obj"), kTriangle);
  EXPECT_EQ(RenderShell(dir, dir.File("ok.obj"), "", &err), 2) << err;
  EXPECT_NE(err.find(dir.File("ok.obj") + ":1: MTL file '" + dir.File("t.mtl") +
                     "': not a text file (a NUL byte at byte 13)"),
            std::string::npos)
      << err;
}

// A small render into `out`, in this process (so that the temporary names
// carry this process's pid).
test::RunResult SmallRender(const std::string& out, const std::string& extra = "") {
  return test::RunMain(
      test::Words("render scenes/cornell.obj --width 16 --height 16 --max-shots "
                  "50 --quiet --out " +
                  out + (extra.empty() ? "" : " " + extra)));
}

// Item 6: the lock and the temporary files were opened through symbolic
// links: a link planted as .vismask.lock got the pid written into its
// target, and one planted as image.pfm.tmp.PID got the image, image.pfm
// becoming a link. Both are refused (exit 1: an output that cannot be
// written), their targets untouched.
TEST(Hardening3Test, SymbolicLinksPlantedInTheOutputFolderAreNeverFollowed) {
  TempDir dir;
  const std::string out = dir.File("out"), target = dir.File("target");
  WriteFile(target, "precious");
  std::filesystem::create_directory(out);
  std::filesystem::create_symlink(target, out + "/.vismask.lock");
  auto r = SmallRender(out);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("the lock file '" + out + "/.vismask.lock' is a symbolic link: refused"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(ReadFile(target), "precious");
  EXPECT_FALSE(test::FileExists(out + "/image.pfm"));
  std::filesystem::remove(out + "/.vismask.lock");
  // A temporary name planted as a link (this process's pid: RunMain runs
  // in it): refused, not followed, not removed.
  const std::string tmp = out + "/image.pfm.tmp." + std::to_string(getpid());
  std::filesystem::create_symlink(target, tmp);
  r = SmallRender(out);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("'" + tmp + "' exists and is a symbolic link: refused"), std::string::npos)
      << r.err;
  EXPECT_EQ(ReadFile(target), "precious");
  EXPECT_TRUE(std::filesystem::is_symlink(tmp));
  EXPECT_FALSE(test::FileExists(out + "/image.pfm"));
  // The final name as a link is refused too.
  std::filesystem::remove(tmp);
  std::filesystem::create_symlink(target, out + "/image.pfm");
  r = SmallRender(out);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("image.pfm' exists and is a symbolic link"), std::string::npos) << r.err;
  EXPECT_EQ(ReadFile(target), "precious");
  // A regular file left under the temporary name (a killed run that had
  // this pid) is replaced, not appended to or written through.
  std::filesystem::remove(out + "/image.pfm");
  WriteFile(tmp, "leftover");
  std::filesystem::create_hard_link(tmp, dir.File("hardlink"));
  r = SmallRender(out);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir.File("hardlink")), "leftover");
  EXPECT_EQ(ReadFile(out + "/image.pfm").substr(0, 9), "PF\n16 16\n");
  EXPECT_FALSE(std::filesystem::is_symlink(out + "/image.pfm"));
  EXPECT_FALSE(test::FileExists(tmp));
}

// Item 10: a lock file that cannot be used (a directory or a FIFO in its
// place) ended the run with 2, the status of bad input; it is an output
// that cannot be written: 1, as the README says for outputs. A folder in
// use by another run stays 2 (SecondRunIntoTheSameDirectoryIsRefused).
TEST(Hardening3Test, AnUnusableLockFileIsAnOutputError) {
  TempDir dir;
  const std::string out = dir.File("out");
  std::filesystem::create_directories(out + "/.vismask.lock");
  auto r = SmallRender(out);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("vismask: --out: "), std::string::npos) << r.err;
  std::filesystem::remove(out + "/.vismask.lock");
  ASSERT_EQ(mkfifo((out + "/.vismask.lock").c_str(), 0600), 0);
  r = SmallRender(out);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("the lock file '" + out + "/.vismask.lock' is not a regular file"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(test::FileExists(out + "/image.pfm"));
}

// How many times the syscall `name` shows in an strace log.
int CountCalls(const std::string& log, const std::string& name) {
  int n = 0;
  for (size_t at = log.find(" " + name + "("); at != std::string::npos;
       at = log.find(" " + name + "(", at + 1))
    ++n;
  return n;
}

// The outputs of a render in `dir` (run.json aside), as bytes.
std::vector<std::string> OutputBytes(const std::string& dir) {
  std::vector<std::string> all;
  for (const char* f : {"image.png", "image.pfm", "patches.csv", "convergence.csv"})
    all.push_back(test::FileExists(dir + "/" + f) ? ReadFile(dir + "/" + f) : "(none)");
  return all;
}

// Item 4: a kill during the commit left image.png and image.pfm new and the
// rest old, with no way to tell. The commit now syncs every file, writes a
// journal before the first rename, and run.json lists every output's size
// and CRC-32. Killed at every rename, link, unlink, fsync and write of a
// run, a folder that held one run's outputs holds, once `vismask
// verify` (or the next render) has finished an interrupted commit, either
// the whole old set or the whole new one, and verify says it is complete.
TEST(Hardening3Test, AKillAtAnyStepOfTheCommitLeavesTheOldSetOrTheNew) {
  if (std::system("command -v strace > /dev/null") != 0) GTEST_SKIP() << "no strace";
  TempDir dir;
  const std::string render = VismaskBin() +
                             " render scenes/cornell.obj --width 16 --height 16 --max-shots 50 "
                             "--quiet --out ";
  // The old set (seed 1) and, elsewhere, what the new run (seed 2) makes.
  ASSERT_EQ(std::system((render + dir.File("old") + " --seed 1").c_str()), 0);
  ASSERT_EQ(std::system((render + dir.File("new") + " --seed 2").c_str()), 0);
  const std::vector<std::string> oldSet = OutputBytes(dir.File("old")),
                                 newSet = OutputBytes(dir.File("new"));
  const std::string oldJson = ReadFile(dir.File("old/run.json"));
  ASSERT_NE(oldSet[1], newSet[1]);  // the images differ
  // The new run's syscalls, counted. (LeakSanitizer cannot run under
  // ptrace: off for the traced runs of make SAN=1 test.)
  const std::string noLeakCheck = "ASAN_OPTIONS=detect_leaks=0 ";
  const std::string traced = dir.File("traced");
  std::filesystem::copy(dir.File("old"), traced);
  const std::string calls = "rename,link,unlink,fsync,write";
  ASSERT_EQ(std::system((noLeakCheck + "strace -f -qq -o " + dir.File("log") +
                         " -e trace=" + calls + " " + render + traced + " --seed 2")
                            .c_str()),
            0);
  const std::string log = ReadFile(dir.File("log"));
  struct Kill {
    std::string call;
    int when;
  };
  std::vector<Kill> kills;
  for (const char* call : {"rename", "link", "unlink", "fsync"})
    for (int k = 1; k <= CountCalls(log, call); ++k) kills.push_back({call, k});
  const int writes = CountCalls(log, "write");
  ASSERT_GT(writes, 4);
  for (int k = 1; k <= writes; ++k) kills.push_back({"write", k});
  int sawOld = 0, sawNew = 0;
  for (const Kill& kill : kills) {
    const std::string what = kill.call + " #" + std::to_string(kill.when);
    const std::string out = dir.File("kill");
    std::filesystem::remove_all(out);
    std::filesystem::copy(dir.File("old"), out);
    const std::string cmd = noLeakCheck + "strace -f -qq -o /dev/null -e trace=" + kill.call +
                            " -e inject=" + kill.call +
                            ":signal=SIGKILL:when=" + std::to_string(kill.when) + " " + render +
                            out + " --seed 2 2> /dev/null";
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status)) << what;
    EXPECT_EQ(WEXITSTATUS(status), 137) << what;  // strace reports the kill
    std::string said;
    // (OUT_DIR spelt otherwise than the render spelt it: the journal names
    // the outputs in it bare.)
    EXPECT_EQ(test::ShellOutput(VismaskBin() + " verify " + out + "/.", 30, &said), 0)
        << what << "\n"
        << said;
    const std::vector<std::string> now = OutputBytes(out);
    const bool isOld = now == oldSet && ReadFile(out + "/run.json") == oldJson;
    // The new set: its images and patches as the reference run made them
    // (convergence.csv and run.json hold timings: verify binds them).
    const bool isNew = now[0] == newSet[0] && now[1] == newSet[1] && now[2] == newSet[2];
    EXPECT_TRUE(isOld || isNew) << what;
    sawOld += isOld;
    sawNew += isNew;
    EXPECT_FALSE(test::FileExists(out + "/.vismask.commit")) << what;
    for (const auto& e : std::filesystem::directory_iterator(out))
      EXPECT_EQ(e.path().filename().string().find(".old."), std::string::npos)
          << what << ": " << e.path();
  }
  // Both ends were reached: kills before the journal, and after it.
  EXPECT_GT(sawOld, 0);
  EXPECT_GT(sawNew, 0);
}

// A pid no process has: a child that has exited and been reaped.
long DeadPid() {
  pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  return static_cast<long>(child);
}

// Item 5: the .tmp.PID files of a killed run were never removed, and a
// moved --export folder kept x.glb.tmp.PID. A run removes those (and the
// commit's .old.PID names) whose pid is not alive, and says so; a live
// pid's are left alone.
TEST(Hardening3Test, TemporariesOfKilledRunsAreRemovedWithOneLine) {
  TempDir dir;
  const std::string out = dir.File("out");
  std::filesystem::create_directories(out);
  std::filesystem::create_directories(dir.File("exp"));
  const std::string dead = std::to_string(DeadPid());
  const std::vector<std::string> stale = {
      out + "/image.png.tmp." + dead, out + "/run.json.tmp." + dead,
      out + "/patches.csv.old." + dead, out + "/.vismask.commit.tmp." + dead,
      dir.File("exp/x.glb.tmp." + dead)};
  for (const std::string& f : stale) WriteFile(f, "half");
  // pid 1 is alive: its files may be a live run's.
  const std::string live = out + "/image.pfm.tmp.1";
  WriteFile(live, "live");
  // Not ours to judge: other names, and a directory.
  WriteFile(out + "/image.png.tmp.x", "mine");
  std::filesystem::create_directories(out + "/image.png.tmp.12");
  auto r = SmallRender(out, "--export " + dir.File("exp/x.glb"));
  ASSERT_EQ(r.code, 0) << r.err;
  for (const std::string& f : stale) EXPECT_FALSE(test::FileExists(f)) << f;
  EXPECT_EQ(ReadFile(live), "live");
  EXPECT_EQ(ReadFile(out + "/image.png.tmp.x"), "mine");
  EXPECT_TRUE(std::filesystem::is_directory(out + "/image.png.tmp.12"));
  EXPECT_NE(r.err.find("vismask: warning: removed 5 temporary files that killed runs left ("),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(test::FileExists(dir.File("exp/x.glb")));
  // Nothing left: no line.
  r = SmallRender(out);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("removed"), std::string::npos) << r.err;
}

// Item 8: results written to a full disk or a closed standard output were
// lost with exit 0. Exit 1, naming standard output.
TEST(Hardening3Test, AResultThatCannotReachStandardOutputIsExit1) {
  TempDir dir;
  ASSERT_EQ(SmallRender(dir.File("out")).code, 0);
  const std::string pfm = dir.File("out/image.pfm");
  const std::string bin = VismaskBin();
  const std::string commands[] = {
      bin + " compare " + pfm + " " + pfm,
      bin + " footprint scenes/cornell.obj --json",
      bin + " footprint scenes/cornell.obj",
      bin + " verify " + dir.File("out"),
      bin + " --help",
  };
  for (const std::string& c : commands) {
    for (const char* redirect : {" > /dev/full", " >&-"}) {
      std::string err;
      EXPECT_EQ(test::ShellOutput("sh -c '" + c + redirect + "'", 60, &err), 1) << c << redirect;
      EXPECT_NE(err.find(std::string("vismask: cannot write to standard output: ") +
                         (redirect[3] == '/' ? "No space left on device" : "it is closed")),
                std::string::npos)
          << c << redirect << "\n"
          << err;
    }
    // And to a pipe that takes it: 0.
    std::string said;
    EXPECT_EQ(test::ShellOutput(c, 60, &said), 0) << c;
  }
}

// A w x h PFM of one colour, little-endian, with `scale` and `tail` after.
std::string Pfm(int w, int h, float v, const std::string& scale = "-1",
                const std::string& tail = "") {
  std::string s = "PF\n" + std::to_string(w) + " " + std::to_string(h) + "\n" + scale + "\n";
  for (int i = 0; i < w * h * 3; ++i) s.append(reinterpret_cast<const char*>(&v), 4);
  return s + tail;
}

// Item 12: compare with every pixel excluded printed relative_rmse 0; a
// PFM with bytes after its pixels, or a scale other than -1 or 1, was
// read; --stop-unshot 0 with no other stop ran for ever (the ledger's
// unshot power, a running double sum, can stay a rounding above 0).
TEST(Hardening3Test, CompareAndStopEdgeCasesAreRefusedOrStated) {
  TempDir dir;
  WriteFile(dir.File("a.pfm"), Pfm(2, 2, 0.5f));
  WriteFile(dir.File("b.pfm"), Pfm(2, 2, 0.25f));
  WriteFile(dir.File("all.pgm"), std::string("P5\n2 2\n255\n") + std::string(4, '\xff'));
  WriteFile(dir.File("one.pgm"), std::string("P5\n2 2\n255\n\xff\0\0\0", 15));
  auto r = test::RunMain(
      {"compare", dir.File("a.pfm"), dir.File("b.pfm"), "--exclude", dir.File("all.pgm")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("every pixel is excluded: nothing is left to compare"), std::string::npos)
      << r.err;
  r = test::RunMain(
      {"compare", dir.File("a.pfm"), dir.File("b.pfm"), "--exclude", dir.File("one.pgm")});
  EXPECT_EQ(r.code, 0) << r.err;
  // Bytes after the pixels, and scales that are not the byte order alone.
  WriteFile(dir.File("tail.pfm"), Pfm(2, 2, 0.5f, "-1", "garbage"));
  r = test::RunMain({"compare", dir.File("tail.pfm"), dir.File("a.pfm")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(dir.File("tail.pfm") + ": 7 bytes after the pixels (the header says 2 x 2)"),
            std::string::npos)
      << r.err;
  for (const char* scale : {"-2", "-0.5", "3"}) {
    WriteFile(dir.File("scale.pfm"), Pfm(2, 2, 0.5f, scale));
    r = test::RunMain({"compare", dir.File("scale.pfm"), dir.File("a.pfm")});
    EXPECT_EQ(r.code, 2) << scale;
    EXPECT_NE(r.err.find(": only 1 (big-endian) and -1 (little-endian) are read"),
              std::string::npos)
        << scale << ": " << r.err;
  }
  WriteFile(dir.File("one.pfm"), Pfm(2, 2, 0.5f, "-1.0"));
  EXPECT_EQ(test::RunMain({"compare", dir.File("one.pfm"), dir.File("a.pfm")}).code, 0);
  // --stop-unshot 0 alone is refused (the ledger's rounding can keep the
  // unshot fraction above 0 for ever); with another stop it is taken.
  r = test::RunMain(
      test::Words("render scenes/cornell.obj --stop-unshot 0 --quiet --out " + dir.File("out")));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("vismask: --stop-unshot 0: would stop only when every queue drains"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(test::FileExists(dir.File("out")));
  for (const char* other :
       {"--max-shots 20", "--max-seconds 0.5", "--ray-budget 100000", "--stop-error 0.5"}) {
    r = test::RunMain(
        test::Words("render scenes/cornell.obj --width 8 --height 8 --stop-unshot 0 --quiet "
                    "--out " +
                    dir.File("out") + " " + other));
    EXPECT_EQ(r.code, 0) << other << ": " << r.err;
  }
}

// Item 13: messages that misled or harmed.
TEST(Hardening3Test, MessagesNameWhatHappened) {
  TempDir dir;
  auto render = [&](const std::string& obj) {
    return test::RunMain({"render", obj, "--width", "8", "--height", "8", "--max-shots", "50",
                          "--quiet", "--out", dir.File("out")});
  };
  // The only emitting face dropped as degenerate: said at that face, not
  // "no emitter" with the warning about the face never shown.
  WriteFile(dir.File("d.mtl"),
            "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\nnewmtl white\nKd 0.5 0.5 0.5\n");
  WriteFile(dir.File("d.obj"),
            "mtllib d.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nusemtl light\nf 1 2 3\n"
            "usemtl white\nf 1 2 4\n");
  auto r = render(dir.File("d.obj"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(dir.File("d.obj") +
                       ":7: no emitter left: this face of emitting material 'light' has no area "
                       "and was dropped"),
            std::string::npos)
      << r.err;
  // CR-only line ends (old Mac files) are line ends: the Cornell box reads
  // as it does with LF, and so do its patches.
  std::string obj = ReadFile("scenes/cornell.obj"), mtl = ReadFile("scenes/cornell.mtl");
  for (std::string* t : {&obj, &mtl})
    for (char& c : *t)
      if (c == '\n') c = '\r';
  WriteFile(dir.File("cornell.obj"), obj);
  WriteFile(dir.File("cornell.mtl"), mtl);
  r = render(dir.File("cornell.obj"));
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string crPatches = ReadFile(dir.File("out/patches.csv"));
  r = render("scenes/cornell.obj");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(crPatches, ReadFile(dir.File("out/patches.csv")));
  // A CR LF split by the reader's 64 KiB buffer is one line end: the line
  // of a later error is counted right.
  std::string padded;
  int lines = 0;
  while (padded.size() < 65535 - 8) {
    padded += "# pad\r\n";
    ++lines;
  }
  padded += std::string(65535 - padded.size(), '#') + "\r\n";  // the CR is byte 65535
  ++lines;
  padded += "# after\r\nbogus\r\n";
  lines += 2;
  WriteFile(dir.File("split.obj"), padded);
  r = render(dir.File("split.obj"));
  EXPECT_NE(r.err.find(dir.File("split.obj") + ":" + std::to_string(lines) +
                       ": unknown statement 'bogus'"),
            std::string::npos)
      << r.err.substr(0, 300);
  // A texture decoder's message quotes no raw byte of the file: a PNG chunk
  // named ESC [ 2 J cleared the terminal.
  {
    std::string png("\x89PNG\r\n\x1a\n", 8);
    auto be32 = [&](uint32_t v) {
      for (int k = 3; k >= 0; --k) png.push_back(static_cast<char>((v >> (8 * k)) & 0xff));
    };
    auto chunk = [&](const std::string& type, const std::string& data) {
      be32(static_cast<uint32_t>(data.size()));
      const std::string body = type + data;
      png += body;
      be32(static_cast<uint32_t>(
          crc32(0, reinterpret_cast<const Bytef*>(body.data()), body.size())));
    };
    chunk("IHDR", std::string("\0\0\0\2\0\0\0\2\x08\x02\0\0\0", 13));
    chunk("\x1b[2J", "");
    WriteFile(dir.File("esc.png"), png);
    TextureImage image;
    Status st = ReadTexture(dir.File("esc.png"), "m.mtl:1", &image);
    ASSERT_FALSE(st.ok());
    EXPECT_EQ(st.ToString().find('\x1b'), std::string::npos) << st.ToString();
    EXPECT_NE(st.ToString().find("\\x1b[2J"), std::string::npos) << st.ToString();
  }
  // Whole sentences: the file first, then what went wrong with it. (A
  // missing MTL is a repair with a warning unless --strict: issue 40.)
  WriteFile(dir.File("m.obj"), "mtllib none.mtl\n");
  r = test::RunMain({"render", dir.File("m.obj"), "--strict", "--width", "8", "--height", "8",
                     "--max-shots", "50", "--quiet", "--out", dir.File("out")});
  EXPECT_NE(r.err.find(dir.File("m.obj") + ":1: MTL file '" + dir.File("none.mtl") +
                       "': cannot open (No such file or directory)"),
            std::string::npos)
      << r.err;
  {
    FILE* f = std::fopen(dir.File("huge.obj").c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fclose(f);
    std::filesystem::resize_file(dir.File("huge.obj"), (uintmax_t{4} << 30) + 1);
  }
  r = render(dir.File("huge.obj"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(dir.File("huge.obj") +
                       ": cannot read: it has 4294967297 bytes, more than the 4294967296 a "
                       "scene file may have\n"),
            std::string::npos)
      << r.err;
}

// Whether the file at `path` is valid JSON in valid UTF-8 (python3's
// strict reading); true when there is no python3 to ask.
bool IsValidJson(const std::string& path) {
  if (std::system("command -v /usr/bin/python3 > /dev/null") != 0) return true;
  const std::string check =
      "/usr/bin/python3 -c 'import json,sys; "
      "json.loads(open(sys.argv[1],\"rb\").read().decode(\"utf-8\"))' " +
      path + " 2> /dev/null";
  return std::system(check.c_str()) == 0;
}

// Item 9: a path with bytes that are not UTF-8 (\xff\xfe) was written raw
// into run.json, which was then not JSON. Such bytes are \u00XX.
TEST(Hardening3Test, RunJsonIsValidJsonWhateverBytesPathsHold) {
  TempDir dir;
  const std::string odd = dir.File("sc\xff\xfe");
  std::filesystem::create_directories(odd);
  std::filesystem::copy_file("scenes/cornell.obj", odd + "/cornell.obj");
  std::filesystem::copy_file("scenes/cornell.mtl", odd + "/cornell.mtl");
  const std::string out = dir.File("out\xff"), glb = dir.File("x\xfe\xc3\xa9.glb");
  auto r = test::RunMain({"render", odd + "/cornell.obj", "--width", "8", "--height", "8",
                          "--max-shots", "50", "--quiet", "--out", out, "--export", glb});
  ASSERT_EQ(r.code, 0) << r.err;
  std::filesystem::copy_file(out + "/run.json", dir.File("run.json"));
  const std::string json = ReadFile(dir.File("run.json"));
  EXPECT_TRUE(IsValidJson(dir.File("run.json"))) << json.substr(0, 300);
  EXPECT_NE(json.find("sc\\u00ff\\u00fe/cornell.obj\""), std::string::npos) << json.substr(0, 300);
  EXPECT_NE(json.find("out\\u00ff\""), std::string::npos);
  // Valid UTF-8 (é) stays as it is; the stray byte before it does not.
  EXPECT_NE(json.find("x\\u00fe\xc3\xa9.glb\""), std::string::npos) << json.substr(0, 600);
  // The commit record names the .glb so that verify finds it again.
  std::string said;
  EXPECT_EQ(test::ShellOutput(VismaskBin() + " verify '" + out + "'", 30, &said), 0) << said;
  // footprint --json too.
  const std::string cmd =
      VismaskBin() + " footprint '" + odd + "/cornell.obj' --json > " + dir.File("fp.json");
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_TRUE(IsValidJson(dir.File("fp.json"))) << ReadFile(dir.File("fp.json")).substr(0, 200);
}

// Item 11: a 1 x 1 or 2 x 2 image of the lit Cornell box was called black
// (the pixel's kept fragments stood for its colour, not for its front-facing
// share); a field of view of 1e-8 degrees rendered black with exit 0.
TEST(Hardening3Test, TheBlackImageWarningLooksAtTheImageAndTinyFieldsOfViewAreRefused) {
  TempDir dir;
  for (const char* size : {"1", "2", "3"}) {
    auto r = test::RunMain({"render", "scenes/cornell.obj", "--width", size, "--height", size,
                            "--max-shots", "300", "--quiet", "--out", dir.File("out")});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("the image is black"), std::string::npos) << size << ": " << r.err;
  }
  const std::string camera = "278,273,-800,278,273,0,0,1,0,";
  auto r = test::RunMain({"render", "scenes/cornell.obj", "--width", "64", "--height", "64",
                          "--camera", camera + "1e-8", "--quiet", "--out", dir.File("tiny")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("vismask: --camera: a field of view of 1e-08 degrees over 64 pixels gives "
                       "each pixel"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(test::FileExists(dir.File("tiny")));
  // Just above the bound (2^-20 radians a pixel): taken, and the lit back
  // wall fills the image.
  const double fov = std::ldexp(1.0, -20) * 64 * 180.0 / 3.14159265358979 * 1.01;
  char deg[32];
  std::snprintf(deg, sizeof deg, "%.6g", fov);
  r = test::RunMain({"render", "scenes/cornell.obj", "--width", "64", "--height", "64",
                     "--max-shots", "300", "--camera", camera + deg, "--quiet", "--out",
                     dir.File("narrow")});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("the image is black"), std::string::npos) << r.err;
  // One step below it: refused.
  std::snprintf(deg, sizeof deg, "%.6g", fov / 1.01 * 0.99);
  r = test::RunMain({"render", "scenes/cornell.obj", "--width", "64", "--height", "64", "--camera",
                     camera + deg, "--quiet", "--out", dir.File("narrower")});
  EXPECT_EQ(r.code, 2) << deg;
}

// Item 7: `vismask view` served what symbolic links in OUT_DIR point at
// (/etc/passwd, /etc), listed directories, answered any Host (DNS
// rebinding) and dropped the connection on /out/%00. Now: only regular
// files whose real path is inside OUT_DIR or the viewer folder, no
// listings, 403 for another Host, 400 for a bad path.
TEST(Hardening3Test, ViewServesOnlyRealFilesInsideItsFoldersToLocalHosts) {
  if (std::system("command -v python3 > /dev/null") != 0) GTEST_SKIP() << "no python3";
  TempDir dir;
  const std::string out = dir.File("out");
  std::filesystem::create_directories(out);
  // A file with a binary glTF 2.0 header of its own length (all view checks).
  std::string glb("glTF\x02\x00\x00\x00\x20\x00\x00\x00", 12);
  glb += std::string(20, ' ');
  WriteFile(out + "/m.glb", glb);
  WriteFile(out + "/run.json", "{}\n");
  WriteFile(dir.File("secret.txt"), "secret");
  std::filesystem::create_symlink(dir.File("secret.txt"), out + "/pw.txt");
  std::filesystem::create_directory_symlink(dir.path(), out + "/up");
  std::filesystem::create_directories(out + "/sub");
  WriteFile(out + "/sub/in.txt", "inside");
  std::filesystem::create_symlink(out + "/run.json", out + "/alias.json");  // inside: served
  const std::string log = dir.File("view.out");
  // serve.py as `vismask view` execs it (view itself also wants the
  // three.js files of 'make viewer', which this does not need).
  const std::string start = "python3 viewer/serve.py --viewer viewer --out " + out +
                            " --glb m.glb --run > " + log + " 2> " + dir.File("view.err") +
                            " & echo $!";
  FILE* p = popen(start.c_str(), "r");
  ASSERT_NE(p, nullptr);
  int pid = -1;
  ASSERT_EQ(std::fscanf(p, "%d", &pid), 1);
  pclose(p);
  std::string url;
  for (int i = 0; i < 600 && url.empty(); ++i) {
    const std::string text = ReadFile(log);
    if (text.find('\n') != std::string::npos) url = text.substr(0, text.find('\n'));
    usleep(50000);
  }
  ASSERT_FALSE(url.empty()) << ReadFile(dir.File("view.err"));
  const std::string origin = url.substr(0, url.find('/', 7));
  const std::string port = origin.substr(origin.rfind(':') + 1);
  // The status of GET `path` with Host `host` (raw: no client rewrites it).
  auto status = [&](const std::string& path, const std::string& host) {
    const std::string py =
        "import socket,sys\n"
        "s=socket.create_connection(('127.0.0.1'," +
        port +
        "))\n"
        "s.sendall(('GET '+sys.argv[1]+' HTTP/1.0\\r\\nHost: '+sys.argv[2]+'\\r\\n\\r\\n')"
        ".encode('latin-1'))\n"
        "d=b''\n"
        "while True:\n"
        "  c=s.recv(65536)\n"
        "  if not c: break\n"
        "  d+=c\n"
        "print(d.split(b' ')[1].decode() if d else 'closed')\n";
    WriteFile(dir.File("get.py"), py);
    std::string said;
    test::ShellOutput("python3 " + dir.File("get.py") + " '" + path + "' '" + host + "'", 20,
                      &said);
    return said.substr(0, said.find('\n'));
  };
  const std::string local = "127.0.0.1:" + port;
  EXPECT_EQ(status("/out/run.json", local), "200");
  EXPECT_EQ(status("/out/m.glb", "localhost:" + port), "200");
  EXPECT_EQ(status("/out/sub/in.txt", "[::1]:" + port), "200");
  EXPECT_EQ(status("/out/alias.json", local), "200");
  EXPECT_EQ(status("/", local), "200");  // the page
  EXPECT_EQ(status("/out/pw.txt", local), "404");
  EXPECT_EQ(status("/out/up/secret.txt", local), "404");
  EXPECT_EQ(status("/out/up/", local), "404");
  EXPECT_EQ(status("/out/", local), "404");
  EXPECT_EQ(status("/out/sub/", local), "404");
  EXPECT_EQ(status("/out/run.json", "evil.example:" + port), "403");
  EXPECT_EQ(status("/out/run.json", "127.0.0.1"), "403");
  EXPECT_EQ(status("/out/%00", local), "400");
  EXPECT_EQ(status("/out/%ff", local), "400");
  kill(pid, SIGTERM);
}

// The texture fuzz target's finds: a JPEG whose Huffman table declares
// more than 256 codes made stb_image 2.27 write past its arrays (refused
// before the decoder sees it); a PNG with an empty first IDAT chunk; a PNG
// chunk longer than the file; a BMP without its palette; a BMP of width 0.
// (A JPEG whose DC terms
// overflow stb_image's int is a seed of the fuzz target, whose clang UBSan
// stops there unless texture_decode.cpp is compiled with -fwrapv.)
TEST(Hardening3Test, AJpegHuffmanTableOfMoreThan256CodesIsRefused) {
  TextureImage image;
  // The second: its DHT segment runs past the file's end (stb_image reads
  // the missing bytes as 0 and overflows first); the third: bytes between
  // segments, which stb_image skips to the next marker; the fourth: fill
  // bytes before its SOI (0xff 0xff 0xd8).
  for (const std::string name : {"dht-overflow.jpg", "dht-overflow-cut.jpg",
                                 "dht-overflow-junk.jpg", "dht-overflow-fill.jpg"}) {
    const std::string path = "tests/data/" + name;
    Status s = ReadTexture(path, "m.mtl:2", &image);
    ASSERT_FALSE(s.ok()) << name;
    EXPECT_NE(s.ToString().find("m.mtl:2: cannot read texture '" + path +
                                "': corrupt JPEG: a Huffman table (DHT) of "),
              std::string::npos)
        << s.ToString();
    EXPECT_NE(s.ToString().find(" codes, more than the 256 JPEG allows"), std::string::npos);
  }
  Status s;
  // A PNG whose first IDAT chunk is empty: stb_image copied 0 bytes into a
  // null buffer (undefined behaviour, which make SAN=1 test stops at); a
  // plain error now.
  s = ReadTexture("tests/data/png-empty-idat.png", "m.mtl:2", &image);
  EXPECT_FALSE(s.ok());
  // A PNG of 126 bytes whose chunk claims 1.6 GB: stb_image grew its
  // buffer to 2 GiB before finding the bytes missing.
  s = ReadTexture("tests/data/png-chunk-too-long.png", "m.mtl:2", &image);
  EXPECT_NE(s.ToString().find("': corrupt PNG: a chunk (IDAT) of 1610621199 bytes and its CRC, "
                              "where the file has 20 left"),
            std::string::npos)
      << s.ToString();
  // A 1-bit BMP without its palette: stb_image read the colours from a
  // stack array it never filled (two decodes differed).
  // (The second: its pixels start 3 bytes before the header's end, which
  // stb_image counts as -1 colours, not 0.)
  for (const char* name : {"tests/data/bmp-no-palette.bmp", "tests/data/bmp-palette-offset.bmp"}) {
    s = ReadTexture(name, "m.mtl:2", &image);
    EXPECT_NE(s.ToString().find("': unsupported BMP: no palette (its pixels start inside the "
                                "header) for 1-bit pixels (2 colours needed)"),
              std::string::npos)
        << s.ToString();
  }
  // A BMP of width 0: stb_image returned it, of no texels and a mean of NaN.
  s = ReadTexture("tests/data/bmp-width-0.bmp", "m.mtl:2", &image);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.ToString().find("': the image is 0x"), std::string::npos) << s.ToString();
  EXPECT_NE(s.ToString().find(" texels: it has none"), std::string::npos) << s.ToString();
  // The committed JPEG, whose tables are sound, still reads.
  EXPECT_TRUE(ReadTexture("tests/data/flat-8x4.jpg", "m.mtl:2", &image).ok());
}

// The texture fuzz target's ninth find: a corrupt Huffman stream on which
// stb_image 2.27 shifted a 32-bit value by 32 (undefined behaviour, which
// no check of the headers rules out). JPEG goes through libjpeg-turbo now,
// which refuses it with its own message; a truncated copy too.
TEST(Hardening3Test, ACorruptJpegHuffmanStreamIsRefusedByTheDecoder) {
  const std::string path = "tests/data/jpeg-code-bits-shift-32.jpg";
  TextureImage image;
  Status s = ReadTexture(path, "m.mtl:3", &image);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.ToString().find("m.mtl:3: cannot read texture '" + path + "': corrupt JPEG: "),
            std::string::npos)
      << s.ToString();
  std::string bytes = test::ReadFile("tests/data/flat-8x4.jpg");
  ASSERT_TRUE(DecodeTexture(bytes, "f.jpg", "m.mtl:4", &image).ok());
  bytes.resize(bytes.size() - 40);  // cut inside the scan
  s = DecodeTexture(bytes, "f.jpg", "m.mtl:4", &image);
  EXPECT_NE(s.ToString().find("m.mtl:4: cannot read texture 'f.jpg': corrupt JPEG: "),
            std::string::npos)
      << s.ToString();
}

// Item 3: a planar convex disc of 10,000 corners became over a million
// patches (36 s, 1.9 GB). It is meshed in strips now: its patches follow
// its area and outline, with one warning line that says so.
TEST(Hardening3Test, ADiscOfManyCornersMakesPatchesByItsArea) {
  TempDir dir;
  const int n = 10000;
  std::string obj = "mtllib d.mtl\nusemtl white\n";
  char line[128];
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * 3.14159265358979 * k / n;
    std::snprintf(line, sizeof line, "v %.17g %.17g 0\n", std::cos(a), std::sin(a));
    obj += line;
  }
  obj += "f";
  for (int k = 1; k <= n; ++k) obj += " " + std::to_string(k);
  obj += "\nusemtl light\nv -0.1 -0.1 1\nv -0.1 0.1 1\nv 0.1 0.1 1\nv 0.1 -0.1 1\n";
  obj += "f " + std::to_string(n + 1) + " " + std::to_string(n + 2) + " " + std::to_string(n + 3) +
         " " + std::to_string(n + 4) + "\n";
  WriteFile(dir.File("disc.obj"), obj);
  WriteFile(dir.File("d.mtl"),
            "newmtl white\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0.5 0.5 0.5\nKe 10 10 10\n");
  // No time bound here (tests count, benchmarks time): the patch count below
  // is what a fan of thin triangles used to blow up.
  auto r =
      test::RunMain({"render", dir.File("disc.obj"), "--patch-size", "0.1", "--width", "32",
                     "--height", "32", "--max-shots", "300", "--quiet", "--out", dir.File("out")});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string json = ReadFile(dir.File("out/run.json"));
  const size_t at = json.find("\"patches\": ");
  ASSERT_NE(at, std::string::npos);
  const double patches = std::strtod(json.c_str() + at + 11, nullptr);
  // The disc's 2 (A / s^2 + P / s) (its area about pi, its outline 2 pi) and
  // the light's 2 x 2.
  const double pi = 3.14159265358979;
  EXPECT_LE(patches, 2.0 * (pi / 0.01 + 2.0 * pi / 0.1) + 4.0);
  EXPECT_NE(r.err.find(dir.File("disc.obj") +
                       ":10003: warning: 1 convex face of many corners (here 10000) meshed in "
                       "strips"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace vismask
