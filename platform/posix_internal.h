// What platform/posix_os.cpp shares with platform/posix_files.cpp and
// platform/posix_commit.cpp: the table of temporary names a fatal signal
// removes, and the guard that holds a fatal signal back while CommitAll renames.
#pragma once

namespace vismask::os {

// why = "<what> '<path>': <strerror(errno)>" (kWhyBytes); nothing if why is null.
void SetWhy(char* why, const char* what, const char* path);

// Records `path` as a temporary file a fatal signal removes; returns its
// slot, or -1 when the table is full (the file is then removed only by
// OutFile::Discard).
int ClaimTempSlot(const char* path);
// Forgets the slot's name (renamed or removed); *slot becomes -1.
void ReleaseTempSlot(int* slot);

// Marks CommitAll's renames: a fatal signal that comes meanwhile is only
// recorded, and raised again when the guard ends.
struct CommitGuard {
  CommitGuard();
  ~CommitGuard();
  CommitGuard(const CommitGuard&) = delete;
  CommitGuard& operator=(const CommitGuard&) = delete;
};

}  // namespace vismask::os
