// POSIX implementation of include/vismask/os.h.
#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <cstdarg>
#include <cstdio>
#include <cstring>

#include "vismask/os.h"

namespace vismask::os {

namespace {

void WriteAll(int fd, const char* s, size_t n) {
  while (n > 0) {
    ssize_t w = ::write(fd, s, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      return;
    }
    s += w;
    n -= static_cast<size_t>(w);
  }
}

void SetWhy(char* why, const char* what, const char* path) {
  if (why) std::snprintf(why, kWhyBytes, "%s '%s': %s", what, path, std::strerror(errno));
}

}  // namespace

double Seconds() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double CpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void WriteErr(const char* s, size_t n) { WriteAll(2, s, n); }
void WriteOut(const char* s, size_t n) { WriteAll(1, s, n); }

void PrintErr(const char* fmt, ...) {
  char buf[1024];
  va_list ap;
  va_start(ap, fmt);
  int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  if (n < 0) return;
  WriteErr(buf, static_cast<size_t>(n) < sizeof buf ? static_cast<size_t>(n) : sizeof buf - 1);
}

void GuardStandardDescriptors() {
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) != -1 || errno != EBADF) continue;
    // open() returns the lowest free descriptor: this one.
    int opened = ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
    if (opened != fd && opened >= 0) ::close(opened);  // not ours to fill; leave it
  }
}

bool StderrIsTerminal() { return ::isatty(2) == 1; }

bool MakeDirs(const char* path, char* why) {
  char buf[kMaxPath];
  if (std::strlen(path) >= sizeof buf) {
    if (why) std::snprintf(why, kWhyBytes, "path too long");
    return false;
  }
  std::strcpy(buf, path);
  for (char* p = buf + 1;; ++p) {
    if (*p == '/' || *p == '\0') {
      char saved = *p;
      *p = '\0';
      if (::mkdir(buf, 0777) != 0 && errno != EEXIST) {
        SetWhy(why, "cannot create directory", buf);
        return false;
      }
      struct stat st;
      if (::stat(buf, &st) != 0 || !S_ISDIR(st.st_mode)) {
        errno = ENOTDIR;
        SetWhy(why, "cannot create directory", buf);
        return false;
      }
      *p = saved;
      if (saved == '\0') break;
    }
  }
  return true;
}

bool Exists(const char* path) {
  struct stat st;
  return ::stat(path, &st) == 0;
}

namespace {
// Reads a small /proc file into `buf` (NUL-terminated). False if unreadable.
bool ReadProcFile(const char* path, char* buf, size_t size) {
  int fd = ::open(path, O_RDONLY);
  if (fd < 0) return false;
  ssize_t n = ::read(fd, buf, size - 1);
  ::close(fd);
  if (n <= 0) return false;
  buf[n] = '\0';
  return true;
}

// The value in kB after `key` in /proc text, in bytes; 0 if absent.
uint64_t ProcField(const char* text, const char* key) {
  const char* p = std::strstr(text, key);
  unsigned long long kb = 0;
  if (!p || std::sscanf(p + std::strlen(key), "%llu", &kb) != 1) return 0;
  return kb * 1024ull;
}
}  // namespace

uint64_t PeakRssBytes() {
  char buf[8192];
  return ReadProcFile("/proc/self/status", buf, sizeof buf) ? ProcField(buf, "VmHWM:") : 0;
}

uint64_t FileRssBytes() {
  char buf[4096];
  if (!ReadProcFile("/proc/self/smaps_rollup", buf, sizeof buf)) return 0;
  uint64_t rss = ProcField(buf, "\nRss:"), anon = ProcField(buf, "\nAnonymous:");
  return rss > anon ? rss - anon : 0;
}

OutFile::~OutFile() { Discard(); }

bool OutFile::Open(const char* path, char* why) {
  Discard();
  if (std::strlen(path) >= kMaxPath) {
    if (why) std::snprintf(why, kWhyBytes, "path too long: %.200s...", path);
    return false;
  }
  std::strcpy(path_, path);
  std::snprintf(tmpPath_, sizeof tmpPath_, "%s.tmp", path);
  fd_ = ::open(tmpPath_, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    SetWhy(why, "cannot open", tmpPath_);
    return false;
  }
  failed_ = false;
  return true;
}

bool OutFile::Write(const void* data, size_t n) {
  if (fd_ < 0 || failed_) return false;
  const char* s = static_cast<const char*>(data);
  while (n > 0) {
    ssize_t w = ::write(fd_, s, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      failed_ = true;
      return false;
    }
    s += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

bool OutFile::Commit(char* why) {
  if (fd_ < 0) return false;
  bool ok = !failed_;
  if (::close(fd_) != 0) ok = false;
  fd_ = -1;
  if (!ok) {
    if (why) std::snprintf(why, kWhyBytes, "write failed: %s", tmpPath_);
    ::unlink(tmpPath_);
    return false;
  }
  if (::rename(tmpPath_, path_) != 0) {
    SetWhy(why, "cannot rename", tmpPath_);
    ::unlink(tmpPath_);
    return false;
  }
  return true;
}

void OutFile::Discard() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
    ::unlink(tmpPath_);
  }
}

}  // namespace vismask::os
