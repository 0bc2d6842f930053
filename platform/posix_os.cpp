// POSIX implementation of include/vismask/os.h.
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
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

// The temporary names a fatal signal removes: OutFile's, from Open until
// its file is renamed or removed. Written by the main thread only; `used`
// is set after the name, so a handler never reads half a name.
constexpr int kMaxTempFiles = 32;
struct TempSlot {
  volatile sig_atomic_t used;
  char path[kMaxPath + 24];
};
TempSlot gTemp[kMaxTempFiles];
// While CommitAll renames, a fatal signal only records itself (gDeferred)
// and CommitAll raises it again when it is done. Atomics: the handler may
// run on another thread (Open MPI's), not the one committing.
std::atomic<int> gCommitting{0};
std::atomic<int> gDeferred{0};
std::atomic<bool> gHandlersInstalled{false};
volatile sig_atomic_t gWaitSelf = -1;
volatile sig_atomic_t gWaitPeer = -1;
constexpr int kFatalSignals[] = {SIGINT, SIGTERM, SIGHUP};

int ClaimTempSlot(const char* path) {
  for (int i = 0; i < kMaxTempFiles; ++i) {
    if (gTemp[i].used) continue;
    std::snprintf(gTemp[i].path, sizeof gTemp[i].path, "%s", path);
    std::atomic_signal_fence(std::memory_order_seq_cst);
    gTemp[i].used = 1;
    return i;
  }
  return -1;  // more files than the table: removed only by Discard
}

void ReleaseTempSlot(int* slot) {
  if (*slot >= 0) gTemp[*slot].used = 0;
  *slot = -1;
}

// Async-signal-safe text: appends `s`, or `v` in decimal, to buf[*n].
void Append(char* buf, size_t cap, size_t* n, const char* s) {
  while (*s && *n + 1 < cap) buf[(*n)++] = *s++;
}
void Append(char* buf, size_t cap, size_t* n, long v) {
  char digits[24];
  int k = 0;
  unsigned long u = v < 0 ? 0ul - static_cast<unsigned long>(v) : static_cast<unsigned long>(v);
  do {
    digits[k++] = static_cast<char>('0' + u % 10);
    u /= 10;
  } while (u > 0);
  if (v < 0) digits[k++] = '-';
  while (k > 0 && *n + 1 < cap) buf[(*n)++] = digits[--k];
}

const char* SignalName(int sig) {
  switch (sig) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "a signal";
  }
}

void OnFatalSignal(int sig) {
  int savedErrno = errno;
  if (gCommitting.load()) {
    gDeferred.store(sig);
    errno = savedErrno;
    return;
  }
  RemoveTempFiles();
  int self = gWaitSelf, peer = gWaitPeer;
  if (peer >= 0) {
    char line[128];
    size_t n = 0;
    Append(line, sizeof line, &n, "vismask: rank ");
    Append(line, sizeof line, &n, static_cast<long>(self));
    Append(line, sizeof line, &n, ": ended by ");
    Append(line, sizeof line, &n, SignalName(sig));
    Append(line, sizeof line, &n, " while waiting for rank ");
    Append(line, sizeof line, &n, static_cast<long>(peer));
    Append(line, sizeof line, &n, "\n");
    WriteAll(2, line, n);
  }
  // The signal's own course: blocked while this handler runs, it ends the
  // process when the handler returns.
  ::signal(sig, SIG_DFL);
  ::raise(sig);
  errno = savedErrno;
}

// Marks CommitAll's renames; a fatal signal that came meanwhile is raised
// again at the end.
struct CommitGuard {
  CommitGuard() { gCommitting.store(1); }
  ~CommitGuard() {
    gCommitting.store(0);
    int sig = gDeferred.exchange(0);
    if (sig != 0) ::raise(sig);
  }
};

}  // namespace

void RemoveTempFiles() {
  for (int i = 0; i < kMaxTempFiles; ++i) {
    if (gTemp[i].used) ::unlink(gTemp[i].path);
  }
}

void InstallSignalCleanup() {
  if (gHandlersInstalled.exchange(true)) return;
  for (int sig : kFatalSignals) {
    struct sigaction old = {};
    // A signal the caller ignores (nohup) or handles stays as it is.
    if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler != SIG_DFL) continue;
    struct sigaction act = {};
    act.sa_handler = OnFatalSignal;
    act.sa_flags = SA_RESTART;
    sigemptyset(&act.sa_mask);
    for (int other : kFatalSignals) sigaddset(&act.sa_mask, other);
    ::sigaction(sig, &act, nullptr);
  }
}

void NoteWaiting(int self, int peer) {
  gWaitSelf = self;
  gWaitPeer = peer;
}

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

void WriteErr(const char* s, size_t n) {
  WriteAll(2, s, n);
}
void WriteOut(const char* s, size_t n) {
  WriteAll(1, s, n);
}

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

bool StderrIsTerminal() {
  return ::isatty(2) == 1;
}

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

uint64_t MemAvailableBytes() {
  char buf[8192];
  return ReadProcFile("/proc/meminfo", buf, sizeof buf) ? ProcField(buf, "MemAvailable:") : 0;
}

uint64_t AnonRssBytes() {
  char buf[8192];
  return ReadProcFile("/proc/self/status", buf, sizeof buf) ? ProcField(buf, "RssAnon:") : 0;
}

uint64_t FileRssBytes() {
  char buf[4096];
  if (!ReadProcFile("/proc/self/smaps_rollup", buf, sizeof buf)) return 0;
  uint64_t rss = ProcField(buf, "\nRss:"), anon = ProcField(buf, "\nAnonymous:");
  return rss > anon ? rss - anon : 0;
}

InFile::~InFile() {
  if (fd_ >= 0) close(fd_);
}

bool InFile::Open(const char* path, std::string* why) {
  if (fd_ >= 0) close(fd_);
  do {
    fd_ = open(path, O_RDONLY | O_CLOEXEC);
  } while (fd_ < 0 && errno == EINTR);
  if (fd_ < 0) *why = std::strerror(errno);
  return fd_ >= 0;
}

int64_t InFile::Read(void* buf, size_t n, std::string* why) {
  size_t got = 0;
  while (got < n) {
    ssize_t r = read(fd_, static_cast<char*>(buf) + got, n - got);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      *why = std::strerror(errno);
      return -1;
    }
    if (r == 0) break;
    got += static_cast<size_t>(r);
  }
  return static_cast<int64_t>(got);
}

int64_t InFile::Size() const {
  struct stat st;
  if (fd_ < 0 || fstat(fd_, &st) != 0) return -1;
  return static_cast<int64_t>(st.st_size);
}

OutFile::~OutFile() {
  Discard();
}

bool OutFile::Open(const char* path, char* why) {
  Discard();
  if (std::strlen(path) >= kMaxPath) {
    if (why) std::snprintf(why, kWhyBytes, "path too long: %.200s...", path);
    return false;
  }
  struct stat st;
  if (::lstat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
    if (why) std::snprintf(why, kWhyBytes, "'%s' exists and is not a regular file", path);
    return false;
  }
  std::strcpy(path_, path);
  std::snprintf(tmpPath_, sizeof tmpPath_, "%s.tmp.%ld", path, static_cast<long>(::getpid()));
  fd_ = ::open(tmpPath_, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    SetWhy(why, "cannot open", tmpPath_);
    return false;
  }
  tempSlot_ = ClaimTempSlot(tmpPath_);
  InstallSignalCleanup();
  writeErrno_ = 0;
  return true;
}

bool OutFile::Write(const void* data, size_t n) {
  if (fd_ < 0 || writeErrno_ != 0) return false;
  const char* s = static_cast<const char*>(data);
  while (n > 0) {
    ssize_t w = ::write(fd_, s, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      writeErrno_ = errno;
      return false;
    }
    s += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

bool OutFile::Close(char* why) {
  if (fd_ < 0) {
    if (why) std::snprintf(why, kWhyBytes, "'%s' is not open", path_);
    return false;
  }
  int failed = writeErrno_;
  if (::close(fd_) != 0 && failed == 0) failed = errno;
  fd_ = -1;
  // CommitAll (the only caller) renames or removes it before a signal is handled.
  ReleaseTempSlot(&tempSlot_);
  if (failed != 0) {
    if (why)
      std::snprintf(why, kWhyBytes, "cannot write '%s': %s", tmpPath_, std::strerror(failed));
    ::unlink(tmpPath_);
    return false;
  }
  return true;
}

bool OutFile::Commit(char* why) {
  return CommitAll(this, 1, why);
}

void OutFile::Discard() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
    ::unlink(tmpPath_);
  }
  ReleaseTempSlot(&tempSlot_);
}

bool CommitAll(OutFile* const* files, int n, char* why) {
  CommitGuard guard;
  bool ok = true;
  for (int i = 0; i < n; ++i) {
    if (!ok) {
      files[i]->Discard();
      continue;
    }
    ok = files[i]->Close(why);
    if (!ok)
      for (int j = 0; j < i; ++j) ::unlink(files[j]->tmpPath_);
  }
  if (!ok) return false;
  // The files that exist keep a second name (a hard link, "NAME.old.PID")
  // until every rename has succeeded, so that a failure can put them back.
  constexpr int kMax = 16;
  if (n > kMax) {
    if (why) std::snprintf(why, kWhyBytes, "too many files to commit at once (%d)", n);
    for (int i = 0; i < n; ++i) ::unlink(files[i]->tmpPath_);
    return false;
  }
  char old[kMax][kMaxPath + 24];
  bool kept[kMax] = {};
  int renamed = 0;
  for (int i = 0; i < n && ok; ++i) {
    std::snprintf(old[i], sizeof old[i], "%s.old.%ld", files[i]->path_,
                  static_cast<long>(::getpid()));
    ::unlink(old[i]);
    if (::link(files[i]->path_, old[i]) == 0) {
      kept[i] = true;
    } else if (errno != ENOENT) {
      SetWhy(why, "cannot keep the previous", files[i]->path_);
      ok = false;
    }
  }
  for (int i = 0; i < n && ok; ++i) {
    if (::rename(files[i]->tmpPath_, files[i]->path_) != 0) {
      SetWhy(why, "cannot rename", files[i]->tmpPath_);
      ok = false;
    } else {
      ++renamed;
    }
  }
  for (int i = 0; i < n; ++i) {
    if (!ok && i < renamed) {
      // Put back what was there: the previous file, or nothing.
      if (kept[i])
        ::rename(old[i], files[i]->path_);
      else
        ::unlink(files[i]->path_);
    }
    if (!ok && i >= renamed) ::unlink(files[i]->tmpPath_);
    if (kept[i]) ::unlink(old[i]);  // a no-op after the rename back
  }
  return ok;
}

bool CommitAll(OutFile* files, int n, char* why) {
  constexpr int kMax = 16;
  if (n > kMax) {
    if (why) std::snprintf(why, kWhyBytes, "too many files to commit at once (%d)", n);
    for (int i = 0; i < n; ++i) files[i].Discard();
    return false;
  }
  OutFile* list[kMax];
  for (int i = 0; i < n; ++i) list[i] = &files[i];
  return CommitAll(list, n, why);
}

DirLock::~DirLock() {
  if (fd_ >= 0) ::close(fd_);
}

bool DirLock::Acquire(const char* dir, char* why) {
  char path[kMaxPath + 16];
  std::snprintf(path, sizeof path, "%s/.vismask.lock", dir);
  int fd = ::open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd < 0) {
    SetWhy(why, "cannot open the lock file", path);
    return false;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    int err = errno;
    char pid[32] = {};
    ssize_t got = ::pread(fd, pid, sizeof pid - 1, 0);
    ::close(fd);
    if (err == EWOULDBLOCK) {
      if (why)
        std::snprintf(why, kWhyBytes, "'%s' is in use by another vismask run (pid %s)", dir,
                      got > 0 ? pid : "unknown");
    } else if (why) {
      std::snprintf(why, kWhyBytes, "cannot lock '%s': %s", path, std::strerror(err));
    }
    return false;
  }
  char pid[32];
  int len = std::snprintf(pid, sizeof pid, "%ld", static_cast<long>(::getpid()));
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, pid, static_cast<size_t>(len), 0) != len) {
    SetWhy(why, "cannot write the lock file", path);
    ::close(fd);
    return false;
  }
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
  return true;
}

}  // namespace vismask::os
