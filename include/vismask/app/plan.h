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
  uint64_t emittedRays = 0;  // the default --emitted-rays (several environments' cap)
  // --emission-rays (1 without per-pixel direct light): the emitted power
  // traces this share of its worth, the reflected power all of it.
  double emissionRays = 1.0;
  // One environment: the noise's balance applies, and the emitted rays may
  // exceed the default. Cut into several, (a) the patches the cuts clip are
  // slivers that receive few rays whatever the patch size, and the coarser
  // mesh measured worse (the Cornell box in two environments at a 10 s
  // budget, docs/RESULTS.md at d1281fe); (b) a ray costs more than the
  // timed walk (crossings, foreign shots, Method B's masks), so that a plan
  // past the default overran 10 s and was cut (12.3% from Cycles with
  // Method B, 4.3% with R, against 1.8% converged at the default).
  bool oneEnvironment = true;
  // Paced (pace.h; app.cpp's PacedPlan: without --checkpoint or --resume):
  // the solve re-plans its quantum by the rate it traces at, so several
  // environments too may plan past the default and fill the budget as one
  // does; unpaced, they keep (b)'s cap.
  bool paced = false;
  // Paced with shot costs (pace.h: several environments, Methods A-C): the
  // plan knows nothing of what a shot's mask costs, and the emitters' first
  // shots are made at its quantum before the pace can re-plan it, so it
  // starts from (b)'s cap, which the pace then refines.
  bool shotCosts = false;
};

// The patches the budget's mesh should have, or 0 to keep the automatic
// mesh: the fewer of (a) the patches whose tail of small shots takes
// kTailShare of the budget's rays, and (b) with oneEnvironment, those at which the
// indirect part's noise and its discretisation balance,
// sqrt(patches * R / kRaysPerPatch) for the R rays the solve traces;
// kept when that is within kReplan of the automatic mesh.
double PlannedPatches(const PlanInput& in);

// The emitted rays a solve that converges within about T affords on a
// mesh of `patches` timed at `rate` (at least 10 000). One environment:
// more than the default --emitted-rays where T affords more (a budget is
// spent, not capped at what a default solve traces); several, paced under
// Method R: the same; several unpaced or with shot costs: a smaller share
// of the budget, never more than the default.
uint64_t PlannedEmittedRays(const PlanInput& in);

// The rays of a converging solve's tail of small shots on `patches`
// patches: about two shots a patch at --min-rays each, per bounce.
double TailRays(double patches, uint32_t minRays, double rho);
// Those shots (TailRays without --min-rays): in a converging solve most of
// its local shots are these.
double TailShots(double patches, double rho);

}  // namespace vismask
