// The MPI side of the rank tests: whether it can run, and how.
#pragma once
#include <sys/types.h>

#include <string>

namespace vismask::test {

// Whether build/vismask-mpi (VismaskBin() + "-mpi") and mpirun are there.
bool HaveMpi();

// The mpirun command line that runs VismaskBin() + "-mpi" on `ranks` ranks
// (arguments to follow), as root too. detect_leaks=0: under SAN=1,
// LeakSanitizer reports Open MPI's own allocations from MPI_Init, which it
// never frees.
std::string MpiCommand(const std::string& ranks);

// Starts `cmd` under /bin/sh, SIGINT at its default; the pid is the command's own (exec).
pid_t StartCommand(const std::string& cmd);
// Waits up to `seconds` for `pid` to end; kills it (SIGKILL) if it does not.
// True if it ended by itself; *status is its wait status, *took the seconds.
bool WaitForExit(pid_t pid, double seconds, int* status, double* took);

}  // namespace vismask::test
