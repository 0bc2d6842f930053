#include "ranks_test_util.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

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

// Starts `cmd` under /bin/sh; the pid is the command's own (exec).
pid_t StartCommand(const std::string& cmd) {
  std::fflush(nullptr);
  pid_t pid = fork();
  if (pid == 0) {
    // SIGINT as a terminal's Ctrl-C finds it: the test binary may run in
    // the background of a shell (tools/run-tests), which ignores it there.
    signal(SIGINT, SIG_DFL);
    execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// Waits up to `seconds` for `pid` to end; kills it (SIGKILL) if it does not.
// True if it ended by itself; *status is its wait status, *took the seconds.
bool WaitForExit(pid_t pid, double seconds, int* status, double* took) {
  auto start = std::chrono::steady_clock::now();
  for (;;) {
    *took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (waitpid(pid, status, WNOHANG) == pid) return true;
    if (*took > seconds) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(pid, SIGKILL);
  waitpid(pid, status, 0);
  return false;
}

}  // namespace vismask::test
