// POSIX implementation of include/vismask/core/os.h: signals and the temporary
// files they remove, clocks, standard streams, memory figures (files and
// directories: posix_files.cpp; their commit: posix_commit.cpp).
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

#include "posix_internal.h"
#include "vismask/core/os.h"

namespace vismask::os {

namespace {

// Writes all of `n` bytes; errno (0 when done) of the failure.
int WriteAll(int fd, const char* s, size_t n) {
  while (n > 0) {
    ssize_t w = ::write(fd, s, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    s += w;
    n -= static_cast<size_t>(w);
  }
  return 0;
}

// Standard output was closed when vismask started (GuardStandardDescriptors
// put /dev/null there): what is written to it goes nowhere.
bool gStdoutWasClosed = false;

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
std::atomic<bool> gDeferInterrupts{false};
std::atomic<int> gInterrupt{0};
volatile sig_atomic_t gWaitSelf = -1;
volatile sig_atomic_t gWaitPeer = -1;
// SIGABRT too: a failed assertion in a library (or abort() anywhere) leaves
// no temporary file behind either.
constexpr int kFatalSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGABRT};

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
    case SIGABRT:
      return "SIGABRT";
    default:
      return "a signal";
  }
}

void OnFatalSignal(int sig) {
  int savedErrno = errno;
  // Checkpointing: the first signal waits for the round's end.
  if (gDeferInterrupts.load() && gInterrupt.load() == 0) {
    gInterrupt.store(sig);
    errno = savedErrno;
    return;
  }
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

}  // namespace

void SetWhy(char* why, const char* what, const char* path) {
  if (why) std::snprintf(why, kWhyBytes, "%s '%s': %s", what, path, std::strerror(errno));
}

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

CommitGuard::CommitGuard() {
  gCommitting.store(1);
}

CommitGuard::~CommitGuard() {
  gCommitting.store(0);
  int sig = gDeferred.exchange(0);
  if (sig != 0) ::raise(sig);
}

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

void DeferInterrupts(bool on) {
  InstallSignalCleanup();
  if (on) gInterrupt.store(0);  // a new solve (several renders in one process: the tests)
  gDeferInterrupts.store(on);
}

int PendingInterrupt() {
  return gInterrupt.load();
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
bool WriteOut(const char* s, size_t n, char* why) {
  if (gStdoutWasClosed) {
    if (why) std::snprintf(why, kWhyBytes, "cannot write to standard output: it is closed");
    return false;
  }
  const int err = WriteAll(1, s, n);
  if (err != 0 && why)
    std::snprintf(why, kWhyBytes, "cannot write to standard output: %s", std::strerror(err));
  return err == 0;
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
    if (fd == 1) gStdoutWasClosed = true;
    int opened = ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
    if (opened != fd && opened >= 0) ::close(opened);  // not ours to fill; leave it
  }
}

bool StderrIsTerminal() {
  return ::isatty(2) == 1;
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

}  // namespace vismask::os
