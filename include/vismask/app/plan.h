// --max-seconds's plan (src/app/app.cpp: PlanPatchSize, PlanBudget): what a
// budget of T seconds affords a one-rank solve, from the rays per second
// timed through the scene's grids at init (docs/design/direct-light.md,
// Anytime). Pure arithmetic, so that its rules are tested apart from the
// timing.
#pragma once
#include <cstdint>

namespace vismask {

struct PlanInput {
  double rate = 0.0;         // rays a second through the automatic mesh's grids
  double rho = 0.0;          // the mean kd (at most 0.95)
  double patches = 0.0;      // the automatic mesh's patches
  double seconds = 0.0;      // T
  uint32_t minRays = 16;     // --min-rays
  uint64_t emittedRays = 0;  // the default --emitted-rays (the plan never exceeds it)
  // Whether the noise's balance applies: one environment. Cut into several,
  // the patches the cuts clip are slivers that receive few rays whatever
  // the patch size, and the coarser mesh measured worse there (the Cornell
  // box in two environments at a 10 s budget, docs/RESULTS.md at d1281fe).
  bool balance = true;
};

// The patches the budget's mesh should have, or 0 to keep the automatic
// mesh: the fewer of (a) the patches whose tail of small shots takes
// kTailShare of the budget's rays, and (b) with `balance`, those at which the
// indirect part's noise and its discretisation balance,
// sqrt(patches * R / kRaysPerPatch) for the R rays the solve traces;
// kept when that is within kReplan of the automatic mesh.
double PlannedPatches(const PlanInput& in);

// The emitted rays a solve that converges within about T affords on a
// mesh of `patches` timed at `rate` (at least 10 000; never more than the
// default).
uint64_t PlannedEmittedRays(const PlanInput& in);

}  // namespace vismask
