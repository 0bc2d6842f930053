// The operating-system services vismask uses, implemented in platform/.
// Nothing here allocates after it is set up: paths are fixed char arrays and
// writes go straight to file descriptors. src/ uses only this header, never
// <unistd.h> or <fcntl.h>.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vismask::os {

constexpr size_t kMaxPath = 1024;
// Size of the buffers that receive an error description ("why").
constexpr size_t kWhyBytes = 2048;

// Seconds from an arbitrary fixed point (monotonic clock).
double Seconds();
// CPU seconds the calling thread has used (not counting time it was
// descheduled: what a rank would take on a core of its own).
double CpuSeconds();

// Writes all of `s` to standard error / standard output (no buffering).
void WriteErr(const char* s, size_t n);
// False (with *why, kWhyBytes, naming standard output) if the write failed
// (/dev/full, a closed pipe) or standard output was closed when vismask
// started (GuardStandardDescriptors): a result that reached nobody.
bool WriteOut(const char* s, size_t n, char* why = nullptr);
// printf-style to stderr; lines longer than 1 KiB are cut.
void PrintErr(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

// Opens /dev/null on any of descriptors 0, 1 and 2 that is closed, so that
// the first file vismask opens never becomes "standard error" (a run with
// 2>&- would otherwise write its progress lines into an output file). Call
// first thing in main.
void GuardStandardDescriptors();

// True if standard error is a terminal (progress lines then redraw in place).
bool StderrIsTerminal();

// Creates `path` and missing parents. False (with errno text in *why, which
// must hold kWhyBytes) on failure.
bool MakeDirs(const char* path, char* why);

// True if `path` exists (any kind of file).
bool Exists(const char* path);

// True if `path` is a directory (following symbolic links).
bool IsDirectory(const char* path);

// Init-time services for `vismask view` (they allocate; platform/posix_exec.cpp).
// The names in directory `dir` other than "." and "..", sorted bytewise.
// False (with *why) if it cannot be read.
bool ListDirectory(const char* dir, std::vector<std::string>* names, std::string* why);
// The directory holding the running executable (/proc/self/exe, symbolic
// links resolved); empty if unknown.
std::string ExecutableDir();
// Replaces the process with the program `argv[0]` (looked up in PATH),
// given argv (argv.size() >= 1). Returns only on failure, with *why.
void Exec(const std::vector<std::string>& argv, std::string* why);

// MemAvailable from /proc/meminfo: what the host can give new allocations
// without swapping, bytes; 0 if unknown.
uint64_t MemAvailableBytes();
// Anonymous resident bytes of this process now (its heap, stacks and
// arenas touched so far: RssAnon); 0 if unknown.
uint64_t AnonRssBytes();

// Peak resident set size of this process (VmHWM), bytes; 0 if unknown.
uint64_t PeakRssBytes();
// Resident bytes backed by files (the binary and its shared libraries):
// Rss - Anonymous from /proc/self/smaps_rollup; 0 if unknown.
uint64_t FileRssBytes();

// Temporary files and fatal signals. While an OutFile's temporary file
// exists, its name is in a fixed table (no allocation); RemoveTempFiles()
// unlinks every name there, and is async-signal-safe. The first
// OutFile::Open, or InstallSignalCleanup(), installs handlers for SIGINT,
// SIGTERM, SIGHUP and SIGABRT (those not ignored) that remove the temporary files,
// write the NoteWaiting line if one is set, and let the signal end the
// process as it would have. A signal that arrives during CommitAll waits
// until the commit is done (complete outputs, or the previous ones).
void RemoveTempFiles();
void InstallSignalCleanup();
// For the signal handler's line: rank `self` is waiting for rank `peer`
// (peer < 0: not waiting). It then writes "vismask: rank SELF: ended by
// signal N while waiting for rank PEER" (under mpirun, the rank that died).
void NoteWaiting(int self, int peer);

// Checkpointing (checkpoint.h): while deferring, the first SIGINT, SIGTERM
// or SIGHUP only records itself (PendingInterrupt: its number, else 0), so
// that the solve ends at the next round with a checkpoint; a second one
// ends the process as above. Off again: signals end the process at once.
void DeferInterrupts(bool on);
int PendingInterrupt();

// One piece of a file WriteFileAtomic writes.
struct FilePart {
  const void* data;
  size_t bytes;
};
// Writes the parts, in order, to PATH.tmp.PID (removed by a fatal signal,
// as OutFile's), syncs it, renames it to `path` and syncs the directory:
// `path` holds its old file or the whole new one, whatever ends the
// process. *crc (may be null) gets the CRC-32 of the bytes written. False
// (with *why, kWhyBytes) on failure, the temporary file removed. Allocates
// nothing. For tests, VISMASK_TEST_CHECKPOINT_KILL=STAGE:K kills the
// process with SIGKILL at the K-th call's STAGE: "write" (half the bytes
// written), "sync" (all written, before the sync), "rename" (synced, before
// the rename) or "renamed" (before the directory's sync).
bool WriteFileAtomic(const char* path, const FilePart* parts, int n, uint32_t* crc, char* why);

// What owns a file descriptor, fd_ (-1: none): InFile, OutFile and
// DirLock. It is closed on destruction (if still open) and never copied.
class FdOwner {
 public:
  FdOwner(const FdOwner&) = delete;
  FdOwner& operator=(const FdOwner&) = delete;
  bool isOpen() const { return fd_ >= 0; }

 protected:
  FdOwner() = default;
  ~FdOwner();

  int fd_ = -1;
};

// A regular file opened for reading (the loaders at init: OBJ, MTL, PFM,
// PGM, textures, a .glb's header). Read fills `buf` with up to n bytes, fewer
// only at the end of the file: the count, 0 at the end, -1 on an error
// (*why: strerror's text). Closed on destruction.
class InFile : public FdOwner {
 public:
  // Opens `path`, which must be a regular file: a device (/dev/zero), a
  // FIFO (never waited for), a directory or a socket is refused, *why
  // "not a regular file (a FIFO)" and kind() naming it.
  bool Open(const char* path, std::string* why);
  int64_t Read(void* buf, size_t n, std::string* why);
  // The file's size in bytes, -1 on an error.
  int64_t Size() const;
  // After Open refused a file that is not a regular one: what it is ("a
  // FIFO", "a character device", ...); null otherwise.
  const char* kind() const { return kind_; }

 private:
  const char* kind_ = nullptr;
};

// An output file written under a temporary name ("NAME.tmp.PID", unique to
// the process) and renamed to its final name only by Commit() or CommitAll(),
// so an interrupted run never leaves a file that looks complete. Discard()
// (or destruction without a commit), a fatal signal (above) and
// RemoveTempFiles() remove the temporary file.
class OutFile : public FdOwner {
 public:
  OutFile() = default;
  ~OutFile();

  // Opens the temporary file for writing, created anew (O_EXCL) and never
  // through a symbolic link (O_NOFOLLOW): a regular file already of that
  // name is a leftover, removed first; a symbolic link or anything else
  // there is refused. False (with *why, kWhyBytes) on failure, which
  // includes a final name that exists and is not a regular file (a
  // symbolic link, or what could not be replaced at the end of the run).
  bool Open(const char* path, char* why);
  // Writes all bytes. False on failure (remembered: the commit then fails
  // with the reason).
  bool Write(const void* data, size_t n);
  // Closes and renames to the final name. False (with *why, kWhyBytes) on failure.
  bool Commit(char* why);
  void Discard();
  const char* path() const { return path_; }
  const char* tmpPath() const { return tmpPath_; }
  // What Write has been given since Open: its byte count and CRC-32 (as
  // zlib and gzip compute it), for the commit record in run.json.
  uint64_t bytes() const { return bytes_; }
  uint32_t crc32() const { return crc_; }

 private:
  friend bool CommitAll(OutFile* const* files, int n, char* why, const char* journalDir);
  // Syncs and closes; false (with *why) if a write, the sync or the close
  // failed.
  bool Close(char* why);

  int tempSlot_ = -1;   // the temporary name's entry in the signal handler's table
  int writeErrno_ = 0;  // errno of the first failed write, 0 if none
  uint64_t bytes_ = 0;
  uint32_t crc_ = 0;
  char path_[kMaxPath] = {};
  char tmpPath_[kMaxPath + 24] = {};
};

// Removes what runs that were killed left beside the output `path`:
// PATH.tmp.PID and PATH.old.PID (regular files or links, never
// directories) whose PID is not a live process and not this one. Returns
// how many it removed; the first one's path into `first` (firstSize bytes)
// when not null. Init only (it reads the directory).
int RemoveStaleTemporaries(const char* path, char* first, size_t firstSize);

// Commits `n` open files as one: every final name then holds the new file,
// or, on failure (with *why), every final name holds what it held before
// (files that existed are restored, new ones removed) and no temporary file
// is left. Files are renamed in array order: put the one that marks a run
// complete (run.json) last. Each file is synced before the renames, and
// the directories after them.
bool CommitAll(OutFile* files, int n, char* why);
// The same for files that are not in one array (at most 16).
bool CommitAll(OutFile* const* files, int n, char* why);
// The same, with a journal: before the first rename, `journalDir`/
// .vismask.commit (written under a temporary name, synced, renamed, the
// directory synced) lists each temporary file and its final name; it is
// removed once every rename is on the disk. A kill or a power cut between
// the two leaves it, and FinishInterruptedCommit then completes the commit:
// the folder holds the whole old set or, once finished, the whole new one.
bool CommitAll(OutFile* const* files, int n, char* why, const char* journalDir);
// Completes a commit that a killed run left in `dir` (its journal): renames
// the temporary files it lists that are still there to their final names
// (only outputs in `dir` and .glb files, each as FINAL.tmp.PID), removes
// their second names (FINAL.old.PID) and the journal. Returns 0 if there was
// no journal, 1 when it finished one (*renamed: the files it renamed), -1 on
// an error (*why). Call with the directory's lock held.
int FinishInterruptedCommit(const char* dir, int* renamed, char* why);

// An exclusive lock on an output directory, held until destruction or the
// process's end (flock on DIR/.vismask.lock, which holds the holder's pid).
// A second run into the same directory is refused instead of the two
// splicing each other's files.
class DirLock : public FdOwner {
 public:
  // False (with *why, naming the holder's pid when known) if another
  // process holds the lock (inUse()) or the lock file cannot be made: it
  // is opened without following a symbolic link, and must be a regular
  // file.
  bool Acquire(const char* dir, char* why);
  // After a failed Acquire: whether another process holds the lock (else
  // the lock file could not be made or used).
  bool inUse() const { return inUse_; }

 private:
  bool inUse_ = false;
};

}  // namespace vismask::os
