// --max-seconds's plan and pace for a run (PlanPatchSize, PlanBudget,
// PaceInputOf): the timing at init, and plan.h's arithmetic and pace.h's
// pacer fed from the run's options and environments.
#include <cmath>

#include "run.h"
#include "vismask/app/plan.h"

namespace vismask {
namespace run {
namespace {

// --max-seconds's plan: the rays timed through the grid at init (the rest
// of the plan is plan.h's arithmetic).
constexpr uint32_t kPlanRays = 20000;
// Timed this many times, the least counting: a timing the machine
// interrupted (another process, the first touch of the grid's pages) is
// not the rate (the Cornell box at 0.3 s: one timing planned patches of
// 50.6-55.0 units over six runs).
constexpr int kPlanTimings = 3;

// The rate, the mean kd and the patches, timed now (PlanRate).
PlanRate MeasureRate(const RunState& r) {
  double seconds = 0.0, area = 0.0, kdArea = 0.0;
  uint64_t rays = 0;
  PlanRate p;
  for (Environment* env : r.envPtrs) {
    double least = env->TimeRays(kPlanRays);
    for (int k = 1; k < kPlanTimings; ++k) least = std::fmin(least, env->TimeRays(kPlanRays));
    seconds += least;
    rays += kPlanRays;
    area += env->totalArea();
    kdArea += env->kdArea();
    p.patches += static_cast<double>(env->patches().size());
  }
  if (!(seconds > 0.0) || !(area > 0.0)) return PlanRate{};
  p.rho = std::fmin(kdArea / area, 0.95);
  p.rate = static_cast<double>(rays) / seconds;
  return p;
}

// Whether a planned solve is paced (pace.h): no --checkpoint or --resume;
// and whether its pace pays the shots' costs apart (several environments,
// Methods A, B and C, whose masks cost whatever the rays).
bool PacedPlan(const Options& o) {
  return o.checkpointDir.empty() && o.resumeDir.empty();
}
bool ShotCosts(const Options& o, size_t environments) {
  return environments > 1 && o.maskMethod != MaskMethod::kR;
}

PlanInput PlanInputOf(const Options& o, const PlanRate& p, size_t environments) {
  PlanInput in;
  in.oneEnvironment = environments == 1;
  in.paced = PacedPlan(o);
  in.shotCosts = ShotCosts(o, environments);
  in.rate = p.rate;
  in.rho = p.rho;
  in.patches = p.patches;
  in.seconds = o.maxSeconds;
  in.minRays = o.minRays;
  in.emittedRays = o.emittedRays;
  in.emissionRays = SolveEmissionRays(o);
  return in;
}

bool Plans(const RunState& r) {
  const Options& o = r.options;
  return o.maxSeconds > 0.0 && !o.hasEmittedRays && o.rayAlloc == Options::RayAlloc::kPower &&
         r.transport->size() == 1 && !r.envPtrs.empty();
}

}  // namespace

// --max-seconds T without --patch-size (as PlanBudget, and no checkpoint):
// a converging solve's tail is about two shots a patch at --min-rays each,
// whatever the patch size, so a short budget spent on many small patches
// ends in their tail with the light half shot; and the fewer rays a patch
// receives, the noisier its indirect part. The plan (PlannedPatches) is
// the patches that keep the tail to a share of the budget's rays and
// balance the noise against the discretisation, at the rate timed on the
// automatic mesh, never more than it has: 0 (keep the mesh), or the patch
// size that gives about that many. *measured: the rate it timed (none when
// it did not plan).
float PlanPatchSize(const RunState& r, PlanRate* measured) {
  const Options& o = r.options;
  if (!Plans(r) || o.patchSize > 0.0f || !o.checkpointDir.empty() || !o.resumeDir.empty())
    return 0.0f;
  const PlanRate p = *measured = MeasureRate(r);
  const double want = PlannedPatches(PlanInputOf(o, p, r.envPtrs.size()));
  if (!(want > 0.0)) return 0.0f;
  return static_cast<float>(r.patchSize * std::sqrt(p.patches / want));
}

// --max-seconds T without --emitted-rays (one rank, power allocation):
// the emitted rays a solve that converges within about T can afford, from
// the rays per second this machine traces through the scene's grids now
// (PlannedEmittedRays: what the budget's rays leave once the tail of small
// shots is paid, at about 1 / (1 - mean kd) rays traced for each emitted),
// so that it ends converged or nearly rather than cut early in a plan made
// for a longer one; a budget longer than a default solve's plans more rays
// than the default (with shot costs or unpaced, not more; plan.h).
// `known`: the rate PlanPatchSize timed on this mesh, if it did. Returns
// the rate it planned with (none when it did not plan).
PlanRate PlanBudget(RunState* r, const PlanRate& known) {
  Options& o = r->options;
  if (!Plans(*r)) return PlanRate{};
  const PlanRate p = known.rate > 0.0 ? known : MeasureRate(*r);
  if (!(p.rate > 0.0)) return PlanRate{};
  const uint64_t planned = PlannedEmittedRays(PlanInputOf(o, p, r->envPtrs.size()));
  // Paced, the plan is the pace's start even when it is the default.
  if (planned == o.emittedRays && !PacedPlan(o)) return PlanRate{};
  for (Environment* env : r->envPtrs)
    env->SetRayQuantum(env->rayQuantum() * static_cast<double>(o.emittedRays) /
                       static_cast<double>(planned));
  o.emittedRays = planned;
  o.emittedRaysPlanned = true;
  return p;
}

namespace {

// A planned solve (PacedPlan) is paced (pace.h) to converge by kPaceEnd
// of --max-seconds: on the Cornell box at 0.3, 1 and 3 s the paced solves
// ended within 0.5% of T of one another (at 0.93, 0.96 and 0.97 of it with
// the tail paid first), against 77-81% planned alone.
constexpr double kPaceEnd = 0.97;
// The pace pays the tail first at this share of the plan's count (TailRays,
// which the patch size's plan keeps): timed from the pace's last re-plan,
// the Cornell box's tails took 0.56-0.63 of the count at 0.3, 1 and 3 s, so
// that at the full count the quantum coarsened in the last tenth and the
// solves ended at 0.91-0.94 of T (with 0.6: 0.96-0.97).
constexpr double kPaceTail = 0.6;

}  // namespace

bool Paces(const RunState& r) {
  const Options& o = r.options;
  return o.emittedRaysPlanned && PacedPlan(o);
}

// The pace of a solve planned with `planned` (PlanBudget) in `environments`:
// its reflectance, tail and shot costs as the plan counted them.
PaceInput PaceInputOf(const Options& o, const PlanRate& planned, size_t environments) {
  const PlanInput plan = PlanInputOf(o, planned, 1);
  PaceInput in;
  in.endSeconds = kPaceEnd * o.maxSeconds;
  in.stopUnshot = o.stopUnshot;
  in.rho = plan.rho;
  in.tailRays = kPaceTail * TailRays(plan.patches, plan.minRays, plan.rho);
  in.shotCosts = ShotCosts(o, environments);
  in.tailShots = TailShots(plan.patches, plan.rho);
  return in;
}

}  // namespace run
}  // namespace vismask
