// POSIX implementation of include/vismask/core/os.h's commits: OutFiles
// renamed all or nothing (CommitAll, with a journal a killed run's successor
// finishes: FinishInterruptedCommit) and one file written atomically
// (WriteFileAtomic, with its test hook).
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "posix_internal.h"
#include "vismask/core/os.h"

namespace vismask::os {

namespace {

constexpr char kJournalName[] = ".vismask.commit";
constexpr char kJournalHead[] = "vismask commit 1\n";
constexpr size_t kJournalBytes = 64 * 1024;

// The directory part of `path` into dir (kMaxPath): "." when it has none.
void DirOf(const char* path, char* dir) {
  const char* slash = std::strrchr(path, '/');
  if (slash == nullptr) {
    std::snprintf(dir, kMaxPath, ".");
  } else if (slash == path) {
    std::snprintf(dir, kMaxPath, "/");
  } else {
    std::snprintf(dir, kMaxPath, "%.*s", static_cast<int>(slash - path), path);
  }
}

// fsync on a directory: its entries (renames, unlinks) on the disk.
bool SyncDir(const char* dir) {
  int fd = ::open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return false;
  bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

// Writes all of `n` bytes to fd; false on an error.
bool WriteAll(int fd, const char* s, size_t n) {
  while (n > 0) {
    ssize_t w = ::write(fd, s, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    s += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

// The commit's journal, DIR/.vismask.commit: which temporary file becomes
// which output (and the previous output's second name), written and made
// durable before the first rename and removed after the last. A run killed
// between the two leaves it, and FinishInterruptedCommit completes the
// renames. Entries are NUL-separated: "tmp\0final\0old\0" after the head.
bool WriteJournal(const char* dir, OutFile* const* files, const char (*old)[kMaxPath + 24], int n,
                  char* journal, char* why) {
  char buf[kJournalBytes];
  size_t len = 0;
  auto add = [&](const char* text, size_t size) {
    if (len + size > sizeof buf) return false;
    std::memcpy(buf + len, text, size);
    len += size;
    return true;
  };
  // Names in `dir` itself are written bare (a reader may spell the
  // directory otherwise: "out", "./out"), others (--export) as they are.
  auto name = [&](const char* path, const char* final) {
    char fdir[kMaxPath];
    DirOf(final, fdir);
    if (std::strcmp(fdir, dir) != 0) return path;
    const char* slash = std::strrchr(path, '/');
    return slash ? slash + 1 : path;
  };
  bool fits = add(kJournalHead, sizeof kJournalHead - 1);
  for (int i = 0; i < n && fits; ++i) {
    const char* final = files[i]->path();
    const char* names[3] = {name(files[i]->tmpPath(), final), name(final, final),
                            name(old[i], final)};
    for (const char* e : names) fits = fits && add(e, std::strlen(e) + 1);
  }
  if (!fits) {
    if (why)
      std::snprintf(why, kWhyBytes, "the commit's journal would exceed %zu bytes", sizeof buf);
    return false;
  }
  std::snprintf(journal, kMaxPath + 32, "%s/%s", dir, kJournalName);
  char tmp[kMaxPath + 64];
  std::snprintf(tmp, sizeof tmp, "%s.tmp.%ld", journal, static_cast<long>(::getpid()));
  ::unlink(tmp);
  int fd = ::open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  if (fd < 0) {
    SetWhy(why, "cannot create the commit's journal", tmp);
    return false;
  }
  bool ok = WriteAll(fd, buf, len) && ::fsync(fd) == 0;
  ok = ::close(fd) == 0 && ok;
  if (!ok || ::rename(tmp, journal) != 0 || !SyncDir(dir)) {
    SetWhy(why, "cannot write the commit's journal", journal);
    ::unlink(tmp);
    ::unlink(journal);
    return false;
  }
  return true;
}

}  // namespace

bool CommitAll(OutFile* const* files, int n, char* why, const char* journalDir) {
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
  for (int i = 0; i < n; ++i)
    std::snprintf(old[i], sizeof old[i], "%s.old.%ld", files[i]->path_,
                  static_cast<long>(::getpid()));
  // Every temporary file is on the disk (Close synced it); the journal
  // then says what the renames are, so that a kill or a power cut during
  // them can be finished (FinishInterruptedCommit) instead of leaving some
  // outputs new and the others old.
  char journal[kMaxPath + 32] = "";
  if (journalDir != nullptr && !WriteJournal(journalDir, files, old, n, journal, why)) {
    for (int i = 0; i < n; ++i) ::unlink(files[i]->tmpPath_);
    return false;
  }
  int renamed = 0;
  for (int i = 0; i < n && ok; ++i) {
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
  // The renames on the disk (every directory an output is in), then the
  // journal gone: the commit is done.
  char synced[kMaxPath] = "";
  for (int i = 0; i < n; ++i) {
    char dir[kMaxPath];
    DirOf(files[i]->path_, dir);
    if (std::strcmp(dir, synced) == 0) continue;
    SyncDir(dir);
    std::memcpy(synced, dir, sizeof dir);
  }
  if (journal[0] != '\0') {
    ::unlink(journal);
    SyncDir(journalDir);
  }
  return ok;
}

namespace {

// VISMASK_TEST_CHECKPOINT_KILL=STAGE:K (WriteFileAtomic's test hook).
enum class KillStage { kNone, kWrite, kSync, kRename, kRenamed };
struct KillAt {
  KillStage stage = KillStage::kNone;
  long call = 0;
};
KillAt ReadKillAt() {
  KillAt k;
  const char* v = std::getenv("VISMASK_TEST_CHECKPOINT_KILL");
  if (v == nullptr) return k;
  const char* colon = std::strchr(v, ':');
  if (colon == nullptr) return k;
  const size_t len = static_cast<size_t>(colon - v);
  const char* names[] = {"write", "sync", "rename", "renamed"};
  const KillStage stages[] = {KillStage::kWrite, KillStage::kSync, KillStage::kRename,
                              KillStage::kRenamed};
  for (int i = 0; i < 4; ++i)
    if (std::strlen(names[i]) == len && std::strncmp(v, names[i], len) == 0) k.stage = stages[i];
  k.call = std::strtol(colon + 1, nullptr, 10);
  return k;
}
long gAtomicCalls = 0;

void MaybeKill(const KillAt& k, KillStage stage) {
  if (k.stage == stage && k.call == gAtomicCalls) ::kill(::getpid(), SIGKILL);
}

}  // namespace

bool WriteFileAtomic(const char* path, const FilePart* parts, int n, uint32_t* crc, char* why) {
  static const KillAt kill = ReadKillAt();
  ++gAtomicCalls;
  char tmp[kMaxPath + 24];
  if (std::strlen(path) >= kMaxPath) {
    if (why) std::snprintf(why, kWhyBytes, "path too long: %.200s...", path);
    return false;
  }
  std::snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, static_cast<long>(::getpid()));
  ::unlink(tmp);  // a leftover of a killed run that had this pid
  int fd = ::open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  if (fd < 0) {
    SetWhy(why, "cannot open", tmp);
    return false;
  }
  int slot = ClaimTempSlot(tmp);
  InstallSignalCleanup();
  uint64_t total = 0, done = 0;
  for (int i = 0; i < n; ++i) total += parts[i].bytes;
  uLong sum = ::crc32(0L, Z_NULL, 0);
  bool ok = true;
  for (int i = 0; i < n && ok; ++i) {
    const char* s = static_cast<const char*>(parts[i].data);
    for (size_t left = parts[i].bytes; left > 0 && ok;) {
      size_t step = left < (size_t{1} << 24) ? left : (size_t{1} << 24);
      // The test hook's torn file: half the bytes on the disk.
      if (kill.stage == KillStage::kWrite && done < total / 2 && done + step > total / 2)
        step = static_cast<size_t>(total / 2 - done);
      if (step == 0) step = left;
      sum = ::crc32(sum, reinterpret_cast<const Bytef*>(s), static_cast<uInt>(step));
      ok = WriteAll(fd, s, step);
      s += step;
      left -= step;
      done += step;
      if (done >= total / 2) MaybeKill(kill, KillStage::kWrite);
    }
  }
  if (!ok) SetWhy(why, "cannot write", tmp);
  MaybeKill(kill, KillStage::kSync);
  if (ok && ::fsync(fd) != 0) {
    ok = false;
    SetWhy(why, "cannot sync", tmp);
  }
  if (::close(fd) != 0 && ok) {
    ok = false;
    SetWhy(why, "cannot close", tmp);
  }
  if (ok) MaybeKill(kill, KillStage::kRename);
  if (ok && ::rename(tmp, path) != 0) {
    ok = false;
    SetWhy(why, "cannot rename to its final name", tmp);
  }
  if (!ok) ::unlink(tmp);
  ReleaseTempSlot(&slot);
  if (!ok) return false;
  MaybeKill(kill, KillStage::kRenamed);
  char dir[kMaxPath];
  DirOf(path, dir);
  if (!SyncDir(dir)) {
    SetWhy(why, "cannot sync the directory of", path);
    return false;
  }
  if (crc) *crc = static_cast<uint32_t>(sum);
  return true;
}

bool CommitAll(OutFile* const* files, int n, char* why) {
  return CommitAll(files, n, why, nullptr);
}

int FinishInterruptedCommit(const char* dir, int* renamed, char* why) {
  *renamed = 0;
  char journal[kMaxPath + 32];
  std::snprintf(journal, sizeof journal, "%s/%s", dir, kJournalName);
  int fd = ::open(journal, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0 && errno == ENOENT) return 0;
  if (fd < 0) {
    SetWhy(why, "cannot read the commit's journal", journal);
    return -1;
  }
  static char buf[kJournalBytes + 1];  // init only, one thread
  struct stat st;
  ssize_t len = -1;
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) &&
      st.st_size <= static_cast<off_t>(kJournalBytes))
    len = ::pread(fd, buf, kJournalBytes, 0);
  ::close(fd);
  const size_t head = sizeof kJournalHead - 1;
  if (len < static_cast<ssize_t>(head) || std::memcmp(buf, kJournalHead, head) != 0) {
    if (why) std::snprintf(why, kWhyBytes, "'%s' is not a commit journal of vismask", journal);
    return -1;
  }
  buf[len] = '\0';
  // Entries: bare names of outputs in `dir`, or .glb files (--export) by
  // their paths; each with its temporary name as OutFile makes it
  // ("FINAL.tmp.PID") and its second name ("FINAL.old.PID").
  int count = 0;
  for (size_t at = head; at < static_cast<size_t>(len);) {
    const char* entry[3];
    entry[0] = buf + at;
    entry[1] = entry[0] + std::strlen(entry[0]) + 1;
    if (entry[1] >= buf + len) break;
    entry[2] = entry[1] + std::strlen(entry[1]) + 1;
    if (entry[2] >= buf + len) break;
    at = static_cast<size_t>(entry[2] + std::strlen(entry[2]) + 1 - buf);
    const char* final = entry[1];
    const size_t fl = std::strlen(final);
    const bool bare = std::strchr(final, '/') == nullptr;
    const bool glb = fl > 4 && std::strcmp(final + fl - 4, ".glb") == 0;
    if (!(bare || glb) || std::strncmp(entry[0], final, fl) != 0 ||
        std::strncmp(entry[0] + fl, ".tmp.", 5) != 0 || std::strncmp(entry[2], final, fl) != 0 ||
        std::strncmp(entry[2] + fl, ".old.", 5) != 0)
      continue;
    char path[3][kMaxPath + 64];
    for (int k = 0; k < 3; ++k) {
      if (bare)
        std::snprintf(path[k], sizeof path[k], "%s/%s", dir, entry[k]);
      else
        std::snprintf(path[k], sizeof path[k], "%s", entry[k]);
    }
    struct stat t;
    if (::lstat(path[0], &t) == 0 && S_ISREG(t.st_mode) && ::rename(path[0], path[1]) == 0) ++count;
    ::unlink(path[2]);
    if (!bare) {
      char fdir[kMaxPath];
      DirOf(path[1], fdir);
      SyncDir(fdir);
    }
  }
  SyncDir(dir);
  ::unlink(journal);
  SyncDir(dir);
  *renamed = count;
  return 1;
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

}  // namespace vismask::os
