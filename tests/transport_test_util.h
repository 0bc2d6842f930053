// Running a body as every rank of a `pipe` transport, from a process forked
// by the test (so the gtest process is never a rank).
#pragma once
#include <functional>
#include <string>

#include "vismask/parallel/transport.h"

namespace vismask::test {

struct RankRun {
  int status = -1;  // rank 0's wait status; -1 if it had to be killed
  std::string err;  // everything every rank wrote to stderr
};

// Runs `body` as every rank of a `pipe` transport of `ranks` ranks, in a
// process forked from the test, and finishes each rank with body's result.
RankRun RunPipeRanks(int ranks, const std::function<int(Transport&)>& body,
                     double timeoutSeconds = 60.0, double rankTimeout = kDefaultRankTimeout);

// Rank 0's exit code, or -1 if it did not exit.
int ExitCode(const RankRun& run);

}  // namespace vismask::test
