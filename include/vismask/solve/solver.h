// Solver: progressive-refinement radiosity with Monte Carlo form factors
// (Cohen et al. 1988) over local environments, in bulk-synchronous rounds.
//
// In each round every environment makes up to --round-shots shots on its own
// (its largest local patch or queued foreign shooter, see environment.h),
// then the packets and every environment's report are exchanged in one
// collective, and the packets delivered in a fixed order (sender
// environment, then send order). An environment's state after a round depends
// only on its state before and on what it was delivered, so the result does
// not depend on the order in which environments run or on how they are
// grouped onto processes. Stop rules are checked between rounds.
#pragma once
#include <cstdint>

#include "vismask/core/span.h"
#include "vismask/output/text_writer.h"
#include "vismask/parallel/ranks.h"
#include "vismask/parallel/transport.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/exchange.h"
#include "vismask/solve/pace.h"

namespace vismask {

// Measures the image against a reference between rounds (--reference).
// Called on every rank at the same rounds (it may use the transport); the
// time it takes is kept out of the solve's clock.
class ErrorProbe {
 public:
  virtual ~ErrorProbe() = default;
  // The relative RMSE of the current solution's image (rank 0's value is
  // the one reported). Must not change the solution and must not allocate.
  virtual double Measure() = 0;
  // The solution moved on since the last Measure (a round ran), so the image
  // Measure drew is no longer the solution's.
  virtual void Moved() {}
};

struct SolveState;

// Called by Solve on every rank at each round's end (and before the first
// round), with the same state on every rank: checkpoint.h writes the state
// there. True ends the solve (StopReason::kInterrupted): a signal asked for
// it and the state was saved.
class RoundHook {
 public:
  virtual ~RoundHook() = default;
  virtual bool AtRoundEnd(const SolveState& state) = 0;
  // For the progress line: whether a checkpoint was written (or resumed
  // from), the rounds it holds and the solve's clock when it was written.
  virtual bool haveCheckpoint() const = 0;
  virtual uint64_t checkpointRounds() const = 0;
  virtual double checkpointElapsed() const = 0;
};

struct SolveOptions {
  double stopUnshot = 1e-3;  // stop when unshot/emitted power < this
  uint64_t maxShots = 0;     // 0: no limit
  uint64_t rayBudget = 0;    // stop once this many form-factor rays are traced; 0: no limit
  double maxSeconds = 0.0;   // 0: no limit
  uint32_t roundShots = 1;   // shots per environment per round (at most)
  uint64_t roundWork =
      0;  // a round ends for an environment after this many grid steps; 0: no limit
  uint32_t queueCapacity = 64;  // foreign shooters an environment can hold
  // Method R: a shot's packets go only where its rays go, so an environment
  // may never hear of it, and the queue's bound is the shots still on their
  // way (RoundTotals::held) rather than each environment's own count.
  bool routed = false;
  bool quiet = false;           // no progress line on stderr
  Span<const uint32_t> order;   // the order environments run in a round (empty: 0..n-1)
  ErrorProbe* probe = nullptr;  // measures after the last round, and
  uint64_t errorEvery = 0;      // after every round that crosses a multiple of this many shots
  // --stop-error: stop when BiasEstimate falls below this (0: off), with
  // --correct-unshot's choice of what the estimate is of.
  double stopError = 0.0;
  bool correctUnshot = false;
  RoundHook* hook = nullptr;  // --checkpoint
  // --max-seconds's pacing (pace.h; one environment on one rank): after
  // each round it may re-plan the environment's ray quantum.
  Pacer* pacer = nullptr;
  const SolveState* resume = nullptr;  // --resume: the state the checkpoint saved
};

// The progress line's estimate of the time left (stderr only: it never
// touches the outputs). Fed (seconds, shots, unshot fraction) at each
// update; ln(unshot) falls about linearly in time, so its smoothed slope
// gives the seconds until --stop-unshot, capped by what --max-seconds and
// --max-shots (at the recent shot rate) leave.
class TimeLeft {
 public:
  void Add(double seconds, uint64_t shots, double unshot);
  // Seconds left, or < 0 when there is no estimate yet (less than a second
  // of updates, or the unshot power not falling, and no bound).
  double Estimate(const SolveOptions& options) const;

 private:
  bool have_ = false;
  double seconds_ = 0.0, lnUnshot_ = 0.0, slope_ = 0.0, weight_ = 0.0, shotRate_ = 0.0;
  uint64_t shots_ = 0;
};

// kStalled: rounds without a shot while power was left to shoot (a bug in
// the admission of forwarded shots, never a convergence). kNoLoss: the
// unshot power did not fall by kStallFall of itself while kStallShot times
// as much was shot (power circulating where nothing absorbs it: a cavity
// closed by faces of Kd 1 that the scene-wide check cannot see).
// kInterrupted: a signal ended the solve at a round's end (RoundHook).
enum class StopReason {
  kConverged,
  kMaxShots,
  kMaxSeconds,
  kRayBudget,
  kStalled,
  kNoLoss,
  kInterrupted
};
// The no-loss stall's window: once kStallShot times the unshot power at
// the window's start U0 has been shot, the unshot power must have fallen
// by kStallFall U0 (a new window opens as soon as it has). Shots that keep rho of their power lose
// kStallShot (1 - rho) U0 in a window, so only rho above 1 - kStallFall / kStallShot (0.9995) can
// stall; counted power, never time, so the same on every transport and rank count. Not checked when
// the run has a bound of its own (--max-shots, --max-seconds, --ray-budget).
constexpr double kStallShot = 20.0;
constexpr double kStallFall = 0.01;
const char* StopReasonName(StopReason r);

struct SolveResult {
  StopReason reason = StopReason::kConverged;
  // kNoLoss: the unshot fraction at the window's start and at its end.
  double stallFrom = 0.0, stallTo = 0.0;
  uint64_t rounds = 0;
  // The collectives every rank of a run of several takes part in: the first
  // totals' AllGather and one AllToAll a round (exchange.h). What the
  // network's latency is paid for.
  uint64_t collectives = 0;
  uint64_t shots = 0;  // local and foreign
  uint64_t rays = 0;   // form-factor rays traced, all environments
  double seconds = 0.0;
  double unshotFraction = 1.0;  // (unshot + in flight) / emitted, channels summed
  // With a probe: how often it measured, the seconds that took (not in
  // `seconds`), and the last measurement (of the final solution).
  uint64_t errorMeasurements = 0;
  double errorSeconds = 0.0;
  double relativeRmse = 0.0;
  // Seconds this rank spent inside the transport's collectives:
  // blocked until the slowest rank arrives, plus the transfer itself. With
  // one rank the loop transport returns at once, so it is about zero.
  double waitSeconds = 0.0;
  double waitSecondsMax = 0.0;  // the most any rank spent there (as of the last gather)
  // CPU seconds of the rounds' shots (RunRound): this rank's, and the sum
  // over rounds of the most any rank used in that round, which is what the
  // solve would take with a core per rank and free communication.
  double computeSeconds = 0.0;
  double criticalSeconds = 0.0;
  // Every rank's CPU seconds of shots, summed: what the split costs in all.
  double totalComputeSeconds = 0.0;
  // The same with one environment per rank: over rounds, the sum of the
  // most CPU any one environment's shots used (measured per environment,
  // so a one-process run gives the critical path of a rank per environment).
  double criticalEnvSeconds = 0.0;
  // The same in grid steps (Grid::steps, a count: the same on every run):
  // all of them, and over rounds the sum of the most any environment, and
  // any rank, did in that round. gridSteps / criticalRankSteps is the
  // speedup the rounds allow this many ranks with a core each and free
  // communication, measured in work rather than time.
  uint64_t gridSteps = 0;
  uint64_t criticalEnvSteps = 0;
  uint64_t criticalRankSteps = 0;
  // The same in work (Environment::workSteps: grid steps plus the fixed
  // charges of work.h), what the rounds are sized by.
  uint64_t work = 0;
  uint64_t criticalEnvWork = 0;
  uint64_t criticalRankWork = 0;
  double biasEstimate = 0.0;  // BiasEstimate of the final totals
  double lossEstimate = 0.0;  // LossEstimate of the final totals
};

// The solver's own state at a round's end, beside its environments': with
// their states (Environment::SaveState and the arenas) what a checkpoint
// keeps, so that a resumed solve takes the same decisions as one never
// stopped. Trivially copyable; the same on every rank.
struct SolveState {
  SolveResult result;
  RoundTotals totals;  // the last round's (what the next round's admission reads)
  uint64_t measuredAt;
  double windowShot, windowUnshot;  // the no-loss window
  uint32_t idle;                    // rounds in a row without a shot
};

// The relative bias of the radiosity from the power not yet shot, estimated
// from the totals with Cohen's ambient argument: the unshot power U will
// add rho*U/(1-rho) of radiosity power (rho the area-mean kd) to the
// radiosity power so far, R. Uncorrected b misses that share,
// s = rho*U/(1-rho) / (R + rho*U/(1-rho)): the 1/(1-rho) amplification that
// makes stiff scenes slow. With the ambient correction (--correct-unshot on)
// the share is added as if spread uniformly; only its first bounce, a
// fraction (1-rho) of it, lands where the unshot power is, not uniformly,
// so the estimate is s*(1-rho) (docs/DESIGN.md).
double BiasEstimate(const RoundTotals& totals, bool corrected);

// The relative bias of the radiosity from the power the masks lost so far
// (or, if negative, let leak): the ledger's residual less the power in
// flight, L, would have added rho*L/(1-rho) of radiosity power, which
// neither the ambient term nor more shots restore. Its magnitude as a share
// of the radiosity with it, R + rho*(U + L)/(1-rho); 0 to rounding for one
// environment and for Method R (docs/DESIGN.md). Later shots lose more: it
// grows as the solve goes on.
double LossEstimate(const RoundTotals& totals);

// The reflectance behind the 1/(1 - rho) of the estimates above and the
// ambient term: `rhoKd` (the area-mean kd) while below 1; else, with no
// absorbing face, 1 - (emitted - unshot) / (radiosity - unshot), the share
// of the power shot so far that was absorbed (back faces) or escaped; 1 if
// nothing was shot or lost yet, which BiasEstimate and LossEstimate report
// as 1 (no estimate) and AmbientTerm as no ambient term.
double EffectiveReflectance(double rhoKd, double emitted, double unshot, double radiosity);

// Per-environment admission: how many new forwarded shots (local shots with
// neighbours) environment `env` of `numEnvs` may create this round, given
// how many each environment still has to receive. Keeps every queue within
// `capacity`, whatever order the forwarded shots arrive in.
uint32_t AdmittedForwards(uint64_t round, uint32_t env, uint32_t numEnvs, uint64_t capacity,
                          uint64_t maxOutstanding);

// The shot budget of environment `env` of `numEnvs` this round under
// --max-shots: the shots left spread evenly (the first environments one
// more), at most `roundShots` each, so that a budget smaller than a whole
// round still reaches every environment while it can.
uint32_t ShotBudget(uint32_t env, uint32_t numEnvs, uint32_t roundShots, uint64_t shotsSoFar,
                    uint64_t maxShots);

// Solves this rank's environments `envs` (those of `layout`) in place,
// exchanging with the other ranks through `transport`. `convergence` (may be
// null; rank 0) receives one row "shot,seconds,unshot_fraction" per round,
// and with a probe ",relative_rmse,error_seconds", filled where measured
// (always on the last row, which repeats the shot count when the solve ended
// on a round with nothing left to shoot and that state was not yet
// measured). Allocates nothing.
SolveResult Solve(Span<Environment* const> envs, const RankEnvs& rankEnvs, Transport* transport,
                  ExchangeBuffers* buffers, const SolveOptions& options, TextWriter* convergence);

// What an environment contributes to Cohen's ambient term.
struct AmbientReport {
  double area;
  double unshot[3];  // local unshot power plus the power in flight booked here
  double kdArea[3];
  double emitted[3];  // the ledger's (for EffectiveReflectance when kd is 1 everywhere)
  double radiosity[3];
  double emission[3];  // per-pixel direct light: the emitted power not yet shot (in `unshot` too)
};
AmbientReport AmbientOf(const Environment& env);
// Cohen's ambient radiosity estimate, per channel, from every environment's
// report (in environment order): the power not yet delivered (unshot and in
// flight) spread over all area and amplified by the mean interreflection
// 1/(1 - mean kd); where the mean kd is 1, 1/(the share of the power shot
// so far that was lost), and 0 (no estimate) while none was
// (EffectiveReflectance).
// With `direct` (per-pixel direct light, which shows the first bounce of
// every emitter's whole emission): the power still to be shown, reflected,
// is spread over kd * area, with the reflectance the shots so far met
// (rho: reflected power received over the power shot) in place of the
// mean kd: the unshot reflected power U gives U rho / (1 - rho), the
// unshot emission E (its first bounce already shown) E rho^2 / (1 - rho).
void AmbientTerm(Span<const AmbientReport> reports, double ambient[3], bool direct = false);

}  // namespace vismask
