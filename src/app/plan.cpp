// --max-seconds's plan (plan.h).
#include "vismask/app/plan.h"

#include <cmath>

namespace vismask {

namespace {

// The share of the budget's rays at the timed rate that the patch size's
// plan counts as traced (the rest is the margin for what a solve's ray does
// beside its walk: it lands, books and splits elements; kRaysPerPatch below
// was fitted with it), the share the emitted rays' plan fills, and the
// shots a patch makes at --min-rays in a converging solve's tail, per
// bounce. With kPlanShare for both, the Cornell box's planned solves ended
// at 63-68% of T (0.3-10 s, docs/RESULTS.md at 2765efe); with kFillShare
// they end at 80-87%. Several environments unpaced keep kPlanShare and the
// default as the most (plan.h).
constexpr double kPlanShare = 0.7;
constexpr double kFillShare = 0.9;
constexpr double kTailShotsPerPatch = 2.0;
// A budget the tail alone would overrun ends cut, whatever the plan: then
// the emitters' own shots get this share of its rays, so that what is shot
// before the cut is shot with rays enough.
constexpr double kCutShare = 0.25;
// The patch size's plan: the share of the budget's rays the tail of small
// shots may take; a plan that would change the patch count by less than
// kReplan keeps the mesh.
constexpr double kTailShare = 0.2;
constexpr double kReplan = 1.5;
// The rays a solve traces per patch of the automatic mesh at which that
// mesh is the one whose indirect noise (which falls as the rays a patch
// receives grow) and discretisation (which falls as patches shrink)
// balance: fitted on the Cornell box against its path-traced reference
// (docs/RESULTS.md), where fewer rays are best spent on fewer patches, the
// patches going as the square root of the rays.
constexpr double kRaysPerPatch = 3000.0;
// The rays the balance counts, as a share of the rays timed in T:
// kRaysPerPatch was fitted counting kPlanShare of them when the solves
// traced 0.87 of them (the Cornell box, 0.3-3 s); paced (pace.h) they
// trace 1.02-1.08, so the same count is 0.7 x 1.05 / 0.87.
constexpr double kBalanceShare = 0.85;

// The rays the solve traces, as the patch size's plan counts them.
double TracedRays(const PlanInput& in) {
  return kBalanceShare * in.rate * in.seconds;
}

}  // namespace

double TailShots(double patches, double rho) {
  return kTailShotsPerPatch * patches / (1.0 - rho);
}

double TailRays(double patches, uint32_t minRays, double rho) {
  return kTailShotsPerPatch * patches * minRays / (1.0 - rho);
}

double PlannedPatches(const PlanInput& in) {
  if (!(in.rate > 0.0) || !(in.patches > 0.0) || !(in.seconds > 0.0)) return 0.0;
  const double tail = std::fmax(
      kTailShare * in.rate * in.seconds * (1.0 - in.rho) / (kTailShotsPerPatch * in.minRays), 1.0);
  const double balance = std::fmax(std::sqrt(in.patches * TracedRays(in) / kRaysPerPatch), 1.0);
  const double want = in.oneEnvironment ? std::fmin(tail, balance) : tail;
  return want * kReplan >= in.patches ? 0.0 : want;
}

uint64_t PlannedEmittedRays(const PlanInput& in) {
  const double tail = TailRays(in.patches, in.minRays, in.rho);
  const bool capped = !in.oneEnvironment && (!in.paced || in.shotCosts);
  const double share = capped ? kPlanShare : kFillShare;
  // An emitted ray's worth leads to F + rho / (1 - rho) rays traced (F:
  // --emission-rays, its own shots; then the reflected power's, which
  // trace all their worth).
  const double traced = in.emissionRays + in.rho / (1.0 - in.rho);
  const double emitted =
      std::fmax(share * in.rate * in.seconds - tail, kCutShare * in.rate * in.seconds) / traced;
  const double most = capped ? static_cast<double>(in.emittedRays) : emitted;
  return static_cast<uint64_t>(std::fmax(std::fmin(emitted, most), 10000.0));
}

}  // namespace vismask
