// The MPI side of the rank tests: whether it can run, and how.
#pragma once
#include <string>

namespace vismask::test {

// Whether build/vismask-mpi (VismaskBin() + "-mpi") and mpirun are there.
bool HaveMpi();

// The mpirun command line that runs VismaskBin() + "-mpi" on `ranks` ranks
// (arguments to follow), as root too. detect_leaks=0: under SAN=1,
// LeakSanitizer reports Open MPI's own allocations from MPI_Init, which it
// never frees.
std::string MpiCommand(const std::string& ranks);

}  // namespace vismask::test
