#include "test_util.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "vismask/app/app.h"

namespace vismask::test {

TempDir::TempDir() {
  char tmpl[] = "/tmp/vismask_test_XXXXXX";
  char* p = mkdtemp(tmpl);
  if (!p) std::abort();
  path_ = p;
}

TempDir::~TempDir() {
  std::string cmd = "rm -rf '" + path_ + "'";
  if (std::system(cmd.c_str()) != 0) std::fprintf(stderr, "could not remove %s\n", path_.c_str());
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

bool FileExists(const std::string& path) {
  return std::ifstream(path).good();
}

RunResult RunMain(const std::vector<std::string>& args) {
  std::vector<const char*> argv = {"vismask"};
  for (const auto& a : args) argv.push_back(a.c_str());
  RunResult r;
  testing::internal::CaptureStderr();
  r.code = Main(static_cast<int>(argv.size()), argv.data());
  r.err = testing::internal::GetCapturedStderr();
  return r;
}

std::vector<std::string> Words(const std::string& words) {
  std::vector<std::string> out;
  std::stringstream ss(words);
  for (std::string w; ss >> w;) out.push_back(w);
  return out;
}

std::vector<std::vector<std::string>> ReadCsv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) row.push_back(cell);
    rows.push_back(row);
  }
  return rows;
}

std::string VismaskBin() {
  const char* b = std::getenv("VISMASK_BIN");
  return b ? b : "build/vismask";
}

bool HaveNumpy() {
  return std::system("/usr/bin/python3 -c 'import numpy' 2> /dev/null") == 0;
}

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

int ShellOutput(const std::string& cmd, int timeoutSeconds, std::string* out) {
  FILE* p = popen(("timeout " + std::to_string(timeoutSeconds) + " " + cmd + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out->append(buf, n);
  int status = pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<std::string> Join(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

double JsonNumber(const std::string& json, const std::string& key, const std::string& section) {
  size_t at = json.find("\"" + key + "\":", json.find("\"" + section + "\":"));
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + at + key.size() + 3, nullptr);
}

}  // namespace vismask::test
