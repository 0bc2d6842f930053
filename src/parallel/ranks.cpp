#include "vismask/parallel/ranks.h"

namespace vismask {

RankEnvs EnvsOfRank(uint32_t total, int ranks, int rank) {
  RankEnvs r;
  r.total = total;
  uint32_t n = static_cast<uint32_t>(ranks), k = static_cast<uint32_t>(rank);
  uint32_t base = total / n, extra = total % n;  // the first `extra` ranks take one more
  r.first = k * base + (k < extra ? k : extra);
  r.count = base + (k < extra ? 1 : 0);
  r.perRank = base + (extra > 0 ? 1 : 0);
  return r;
}

int RankOfEnv(uint32_t env, uint32_t total, int ranks) {
  for (int r = 0; r < ranks; ++r) {
    RankEnvs re = EnvsOfRank(total, ranks, r);
    if (env < re.first + re.count) return r;
  }
  return ranks - 1;
}

}  // namespace vismask
