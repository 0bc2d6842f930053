#include "ranks_test_util.h"

#include <cstdlib>

#include "test_util.h"

namespace vismask::test {

bool HaveMpi() {
  return FileExists(VismaskBin() + "-mpi") && std::system("command -v mpirun >/dev/null 2>&1") == 0;
}

std::string MpiCommand(const std::string& ranks) {
  return "ASAN_OPTIONS=detect_leaks=0 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
         "mpirun -np " +
         ranks + " --oversubscribe " + VismaskBin() + "-mpi";
}

}  // namespace vismask::test
