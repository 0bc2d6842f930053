// Helpers shared by the tests: temporary directories, files, and running the
// vismask command line in-process.
#pragma once
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace vismask::test {

// A float's bits, and the float of given bits (tests compare results bit
// for bit and build special values).
inline uint32_t Bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}
inline float FloatFromBits(uint32_t u) {
  float f;
  std::memcpy(&f, &u, sizeof f);
  return f;
}

// A fresh empty directory under /tmp, removed (with its contents) on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::string& path() const { return path_; }
  std::string File(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

std::string ReadFile(const std::string& path);
void WriteFile(const std::string& path, const std::string& text);
bool FileExists(const std::string& path);

// The vismask binary under test: $VISMASK_BIN (make test sets it), else
// build/vismask.
std::string VismaskBin();

// Runs `cmd` in a shell under `timeout timeoutSeconds`, its stdout and
// stderr together appended to *out; returns its exit status, or -1 when it
// could not start or did not exit normally.
int ShellOutput(const std::string& cmd, int timeoutSeconds, std::string* out);
// `cmd` run by the shell to its end, stderr joined to stdout: its exit
// status (-1 if it did not exit) and its output.
struct Shell {
  int code = -1;
  std::string out;  // stdout and stderr
};
Shell RunShell(const std::string& cmd);
// Whether /usr/bin/python3 has numpy (the report tools' tests need it).
bool HaveNumpy();

struct RunResult {
  int code = -1;
  std::string err;  // what was written to stderr
};
// Runs vismask::Main with `args` (without the program name), capturing stderr.
RunResult RunMain(const std::vector<std::string>& args);

// `words` split at spaces: a command line written as one string (no word
// holds a space; the paths of TempDir hold none).
std::vector<std::string> Words(const std::string& words);

// `a` followed by `b`: a command line with more words.
std::vector<std::string> Join(std::vector<std::string> a, const std::vector<std::string>& b);

// The number after `"key":` in run.json, searched from `"section":` on
// (NaN, and a failure, where there is none).
double JsonNumber(const std::string& json, const std::string& key,
                  const std::string& section = "result");

// Rows of a CSV file (header included), split on commas.
std::vector<std::vector<std::string>> ReadCsv(const std::string& path);

}  // namespace vismask::test
