// Which environments a rank holds: contiguous blocks of the environments in
// index order, the first ranks taking one more when they do not divide. One
// home for "which rank holds environment e" (the solver's gathers, the
// footprint report).
#pragma once
#include <cstdint>

namespace vismask {

// Which environments live on a rank: contiguous blocks, [first, first+count)
// of `total`; no rank holds more than `perRank`.
struct RankEnvs {
  uint32_t total = 1;
  uint32_t first = 0;
  uint32_t count = 1;
  uint32_t perRank = 1;
};
RankEnvs EnvsOfRank(uint32_t total, int ranks, int rank);

// The rank of `ranks` that holds environment `env` of `total`.
int RankOfEnv(uint32_t env, uint32_t total, int ranks);

}  // namespace vismask
