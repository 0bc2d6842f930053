#include "transport_test_util.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <memory>

#include "test_util.h"
#include "vismask/core/os.h"

namespace vismask::test {

RankRun RunPipeRanks(int ranks, const std::function<int(Transport&)>& body, double timeoutSeconds,
                     double rankTimeout) {
  TempDir dir;
  std::string errPath = dir.File("stderr");
  RankRun run;
  std::fflush(nullptr);
  pid_t helper = fork();
  if (helper == 0) {
    int fd = open(errPath.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd < 0 || dup2(fd, 2) < 0) _exit(100);
    Status error;
    std::unique_ptr<Transport> t = MakeTransport({"pipe", ranks, rankTimeout}, &error);
    if (!t) {
      os::PrintErr("MakeTransport: %s\n", error.ToString().c_str());
      _exit(101);
    }
    int code = body(*t);
    _exit(t->Finish(code));
  }
  double deadline = os::Seconds() + timeoutSeconds;
  for (;;) {
    int status;
    pid_t r = waitpid(helper, &status, WNOHANG);
    if (r == helper) {
      run.status = status;
      break;
    }
    if (os::Seconds() > deadline) {
      kill(helper, SIGKILL);  // its children get SIGTERM (PR_SET_PDEATHSIG)
      waitpid(helper, &status, 0);
      break;
    }
    usleep(2000);
  }
  run.err = ReadFile(errPath);
  return run;
}

int ExitCode(const RankRun& run) {
  return run.status >= 0 && WIFEXITED(run.status) ? WEXITSTATUS(run.status) : -1;
}

}  // namespace vismask::test
