// POSIX implementation of include/vismask/core/os.h's files and directories:
// InFile, OutFile, DirLock, MakeDirs (the all-or-nothing commit of OutFiles
// and WriteFileAtomic are platform/posix_commit.cpp's).
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "posix_internal.h"
#include "vismask/core/os.h"

namespace vismask::os {

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

FdOwner::~FdOwner() {
  if (fd_ >= 0) ::close(fd_);
}

namespace {

// What a file that is not a regular file is, for messages.
const char* KindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

}  // namespace

bool InFile::Open(const char* path, std::string* why) {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  kind_ = nullptr;
  // Non-blocking, so that opening a FIFO without a writer returns at once;
  // then only a regular file is kept (a device such as /dev/zero or a FIFO
  // would be read without end).
  int fd;
  do {
    fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  } while (fd < 0 && errno == EINTR);
  if (fd < 0) {
    *why = std::strerror(errno);
    return false;
  }
  struct stat st;
  if (fstat(fd, &st) != 0) {
    *why = std::strerror(errno);
    close(fd);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    kind_ = KindOf(st.st_mode);
    *why = std::string("not a regular file (") + kind_ + ")";
    close(fd);
    return false;
  }
  const int flags = fcntl(fd, F_GETFL);
  if (flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
    *why = std::strerror(errno);
    close(fd);
    return false;
  }
  fd_ = fd;
  return true;
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

namespace {

// Whether process `pid` exists (one we may not signal exists too).
bool Alive(long pid) {
  return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
}

}  // namespace

int RemoveStaleTemporaries(const char* path, char* first, size_t firstSize) {
  char dir[kMaxPath];
  const char* slash = std::strrchr(path, '/');
  const char* base = slash ? slash + 1 : path;
  if (slash == nullptr)
    std::snprintf(dir, sizeof dir, ".");
  else
    std::snprintf(dir, sizeof dir, "%.*s", slash == path ? 1 : static_cast<int>(slash - path),
                  path);
  DIR* d = ::opendir(dir);
  if (d == nullptr) return 0;
  const size_t baseLen = std::strlen(base);
  int removed = 0;
  while (const struct dirent* e = ::readdir(d)) {
    // BASE.tmp.PID (a temporary file) or BASE.old.PID (a second name the
    // commit keeps), PID all digits, not this process and not alive.
    const char* name = e->d_name;
    if (std::strncmp(name, base, baseLen) != 0) continue;
    const char* rest = name + baseLen;
    if (std::strncmp(rest, ".tmp.", 5) != 0 && std::strncmp(rest, ".old.", 5) != 0) continue;
    const char* digits = rest + 5;
    if (*digits == '\0' || std::strspn(digits, "0123456789") != std::strlen(digits) ||
        std::strlen(digits) > 9)
      continue;
    const long pid = std::strtol(digits, nullptr, 10);
    if (pid <= 0 || pid == static_cast<long>(::getpid()) || Alive(pid)) continue;
    char full[kMaxPath + 256];
    std::snprintf(full, sizeof full, "%s/%s", dir, name);
    struct stat st;
    if (::lstat(full, &st) != 0 || S_ISDIR(st.st_mode)) continue;
    if (::unlink(full) != 0) continue;
    if (removed++ == 0 && first != nullptr) std::snprintf(first, firstSize, "%s", full);
  }
  ::closedir(d);
  return removed;
}

bool OutFile::Open(const char* path, char* why) {
  Discard();
  if (std::strlen(path) >= kMaxPath) {
    if (why) std::snprintf(why, kWhyBytes, "path too long: %.200s...", path);
    return false;
  }
  struct stat st;
  if (::lstat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
    if (why)
      std::snprintf(why, kWhyBytes, "'%s' exists and is %s", path,
                    S_ISLNK(st.st_mode) ? "a symbolic link (an output is never written through one)"
                                        : "not a regular file");
    return false;
  }
  std::strcpy(path_, path);
  std::snprintf(tmpPath_, sizeof tmpPath_, "%s.tmp.%ld", path, static_cast<long>(::getpid()));
  // Created new, never through a symbolic link: a name planted in its
  // place (the pid is easy to guess) must not redirect the output.
  constexpr int kCreate = O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC;
  fd_ = ::open(tmpPath_, kCreate, 0666);
  if (fd_ < 0 && errno == EEXIST) {
    // A regular file of that name is a leftover (a killed run that had
    // this pid): removed, and the file made anew. Anything else, a
    // symbolic link above all, is refused and left alone.
    if (::lstat(tmpPath_, &st) == 0 && !S_ISREG(st.st_mode)) {
      if (why)
        std::snprintf(why, kWhyBytes, "'%s' exists and is %s: refused", tmpPath_,
                      S_ISLNK(st.st_mode) ? "a symbolic link" : "not a regular file");
      return false;
    }
    ::unlink(tmpPath_);
    fd_ = ::open(tmpPath_, kCreate, 0666);
  }
  if (fd_ < 0) {
    SetWhy(why, "cannot open", tmpPath_);
    return false;
  }
  tempSlot_ = ClaimTempSlot(tmpPath_);
  InstallSignalCleanup();
  writeErrno_ = 0;
  bytes_ = 0;
  crc_ = static_cast<uint32_t>(::crc32(0L, Z_NULL, 0));
  return true;
}

bool OutFile::Write(const void* data, size_t n) {
  if (fd_ < 0 || writeErrno_ != 0) return false;
  const char* s = static_cast<const char*>(data);
  bytes_ += n;
  for (size_t done = 0; done < n;) {
    const size_t part = n - done < UINT_MAX ? n - done : UINT_MAX;
    crc_ = static_cast<uint32_t>(
        ::crc32(crc_, reinterpret_cast<const Bytef*>(s + done), static_cast<uInt>(part)));
    done += part;
  }
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
  // On the disk before any rename makes it an output (a power cut after
  // the commit must not leave an empty or short file under the final name).
  if (failed == 0 && ::fsync(fd_) != 0) failed = errno;
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

bool DirLock::Acquire(const char* dir, char* why) {
  char path[kMaxPath + 16];
  std::snprintf(path, sizeof path, "%s/.vismask.lock", dir);
  inUse_ = false;
  // Never through a symbolic link (the pid would be written into whatever
  // it names), and only into a regular file (not a FIFO or a device).
  int fd = ::open(path, O_RDWR | O_CREAT | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0666);
  if (fd < 0 && errno == ELOOP) {
    if (why) std::snprintf(why, kWhyBytes, "the lock file '%s' is a symbolic link: refused", path);
    return false;
  }
  if (fd < 0) {
    SetWhy(why, "cannot open the lock file", path);
    return false;
  }
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    if (why) std::snprintf(why, kWhyBytes, "the lock file '%s' is not a regular file", path);
    ::close(fd);
    return false;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    int err = errno;
    char pid[32] = {};
    ssize_t got = ::pread(fd, pid, sizeof pid - 1, 0);
    ::close(fd);
    if (err == EWOULDBLOCK) {
      inUse_ = true;
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
