// Solver: progressive-refinement radiosity with Monte Carlo form factors
// (Cohen et al. 1988). Each step, the patch with most unshot power shoots it
// with a fixed number of rays; the run stops when the unshot power falls
// below a fraction of the emitted power, or at a shot or time limit.
#pragma once
#include <cstdint>

#include "vismask/environment.h"
#include "vismask/span.h"
#include "vismask/text_writer.h"

namespace vismask {

struct SolveOptions {
  uint32_t rays = 4096;      // rays per shot
  uint64_t seed = 1;         // run seed
  double stopUnshot = 1e-3;  // stop when unshot/emitted power < this
  uint64_t maxShots = 0;     // 0: no limit
  double maxSeconds = 0.0;   // 0: no limit
  bool quiet = false;        // no progress line on stderr
};

enum class StopReason { kConverged, kMaxShots, kMaxSeconds };
const char* StopReasonName(StopReason r);

struct SolveResult {
  StopReason reason = StopReason::kConverged;
  uint64_t shots = 0;
  uint64_t rays = 0;
  uint64_t hits = 0;
  double seconds = 0.0;
  double unshotFraction = 1.0;  // unshot / emitted, channels summed
};

// Solves the environments in place. `convergence` (may be null) receives one
// row "shot,seconds,unshot_fraction" per shot. Allocates nothing.
SolveResult Solve(Span<Environment* const> envs, const SolveOptions& options,
                  TextWriter* convergence);

// Cohen's ambient radiosity estimate, per channel: the unshot power spread
// over all area and amplified by the mean interreflection 1/(1 - mean kd).
void AmbientTerm(Span<Environment* const> envs, double ambient[3]);

}  // namespace vismask
