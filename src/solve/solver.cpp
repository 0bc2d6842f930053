#include "vismask/solve/solver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <new>

#include "vismask/core/enum_name.h"
#include "vismask/core/os.h"

namespace vismask {

const char* StopReasonName(StopReason r) {
  static constexpr const char* kNames[] = {"converged", "max-shots", "max-seconds", "ray-budget",
                                           "stalled",   "no_loss",   "interrupted"};
  return EnumName<StopReason::kInterrupted>(r, kNames);
}

uint32_t AdmittedForwards(uint64_t round, uint32_t env, uint32_t numEnvs, uint64_t capacity,
                          uint64_t maxOutstanding) {
  if (numEnvs <= 1) return 0;
  // Every forwarded shot created now may land in every other environment's queue,
  // so the total admitted across environments is what the fullest can take.
  uint64_t admit = capacity > maxOutstanding ? capacity - maxOutstanding : 0;
  uint64_t base = admit / numEnvs, extra = admit % numEnvs;
  uint64_t turn = (env + numEnvs - round % numEnvs) % numEnvs;  // rotate the remainder
  uint64_t mine = base + (turn < extra ? 1 : 0);
  return mine > 0xffffffffu ? 0xffffffffu : static_cast<uint32_t>(mine);
}

uint32_t ShotBudget(uint32_t env, uint32_t numEnvs, uint32_t roundShots, uint64_t shotsSoFar,
                    uint64_t maxShots) {
  if (maxShots == 0) return roundShots;
  uint64_t remaining = maxShots > shotsSoFar ? maxShots - shotsSoFar : 0;
  uint64_t n = numEnvs > 0 ? numEnvs : 1;
  uint64_t mine = remaining / n + (env < remaining % n ? 1 : 0);
  return static_cast<uint32_t>(mine < roundShots ? mine : roundShots);
}

void TimeLeft::Add(double seconds, uint64_t shots, double unshot) {
  if (!(unshot > 0.0)) return;
  const double ln = std::log(unshot);
  if (have_ && seconds > seconds_) {
    // ln(unshot) falls about linearly in time for a progressive solve:
    // its slope, smoothed over the updates (each weighs its interval).
    const double dt = seconds - seconds_;
    const double slope = (lnUnshot_ - ln) / dt;
    const double w = std::min(1.0, dt / 10.0);
    slope_ = weight_ > 0.0 ? (1.0 - w) * slope_ + w * slope : slope;
    weight_ += dt;
    shotRate_ = (shots - shots_) / dt;
  }
  have_ = true;
  seconds_ = seconds;
  shots_ = shots;
  lnUnshot_ = ln;
}

double TimeLeft::Estimate(const SolveOptions& o) const {
  double left = -1.0;
  if (weight_ >= 1.0 && slope_ > 0.0 && o.stopUnshot > 0.0)
    left = std::max(0.0, (lnUnshot_ - std::log(o.stopUnshot)) / slope_);
  if (o.maxSeconds > 0.0) {
    const double rest = std::max(0.0, o.maxSeconds - seconds_);
    left = left < 0.0 ? rest : std::min(left, rest);
  }
  if (o.maxShots > 0 && shotRate_ > 0.0) {
    const double rest = o.maxShots > shots_ ? (o.maxShots - shots_) / shotRate_ : 0.0;
    left = left < 0.0 ? rest : std::min(left, rest);
  }
  return left;
}

namespace {

class Progress {
 public:
  Progress(bool quiet, const SolveOptions& options)
      : quiet_(quiet), tty_(os::StderrIsTerminal()), options_(options) {}
  void Update(double now, double elapsed, uint64_t shots, double unshot, bool final) {
    if (quiet_) return;
    if (!final && now < next_) return;
    next_ = now + (tty_ ? 0.25 : 2.0);
    left_.Add(elapsed, shots, unshot);
    double rate = elapsed > 0.0 ? static_cast<double>(shots) / elapsed : 0.0;
    char left[48] = "";
    const double estimate = left_.Estimate(options_);
    if (!final && estimate >= 1e6)
      std::snprintf(left, sizeof left, "  over 1e6 s left");
    else if (!final && estimate >= 0.0)
      std::snprintf(left, sizeof left, "  about %.0f s left", std::ceil(estimate));
    char saved[64] = "";
    if (options_.hook && options_.hook->haveCheckpoint())
      std::snprintf(saved, sizeof saved, "  checkpoint: round %llu, %.0f s ago",
                    static_cast<unsigned long long>(options_.hook->checkpointRounds()),
                    std::max(0.0, elapsed - options_.hook->checkpointElapsed()));
    os::PrintErr("%svismask: shot %llu  unshot %.4f%%  %.1f s  %.0f shots/s%s%s%s",
                 tty_ ? "\r" : "", static_cast<unsigned long long>(shots), 100.0 * unshot, elapsed,
                 rate, left, saved, tty_ && !final ? "   " : "\n");
  }

 private:
  bool quiet_;
  bool tty_;
  const SolveOptions& options_;
  TimeLeft left_;
  double next_ = 0.0;
};

// The stop rules, checked between rounds from the gathered totals.
bool ShouldStop(const RoundTotals& totals, const SolveOptions& options, SolveResult* result) {
  if (result->unshotFraction < options.stopUnshot) {
    result->reason = StopReason::kConverged;
    return true;
  }
  if (options.stopError > 0.0 && result->biasEstimate < options.stopError) {
    result->reason = StopReason::kConverged;
    return true;
  }
  if (options.maxShots > 0 && result->shots >= options.maxShots) {
    result->reason = StopReason::kMaxShots;
    return true;
  }
  if (options.rayBudget > 0 && totals.rays >= options.rayBudget) {
    result->reason = StopReason::kRayBudget;
    return true;
  }
  if (options.maxSeconds > 0.0 && totals.elapsed >= options.maxSeconds) {
    result->reason = StopReason::kMaxSeconds;
    return true;
  }
  return false;
}

// What the result reads of the totals: the unshot fraction and the bias
// and loss estimates (after the first gather and every round).
void SetEstimates(const RoundTotals& totals, const SolveOptions& options, SolveResult* result) {
  result->unshotFraction = totals.emitted > 0.0 ? totals.unshot / totals.emitted : 0.0;
  result->biasEstimate = BiasEstimate(totals, options.correctUnshot);
  result->lossEstimate = LossEstimate(totals);
}

// A round's totals into the result: the counts so far, the round's
// critical path (the most any rank or environment took) added, and the
// estimates.
void AddRound(const RoundTotals& totals, const SolveOptions& options, SolveResult* result) {
  result->waitSecondsMax = totals.waitedMax;
  result->criticalSeconds += totals.roundCpuMax;
  result->totalComputeSeconds += totals.roundCpuSum;
  result->criticalEnvSeconds += totals.envCpuMax;
  result->criticalEnvSteps += totals.envStepsMax;
  result->criticalRankSteps += totals.rankStepsMax;
  result->criticalEnvWork += totals.envWorkMax;
  result->criticalRankWork += totals.rankWorkMax;
  result->work = totals.work;
  result->gridSteps = totals.steps;
  result->shots = totals.shots;
  result->rays = totals.rays;
  SetEstimates(totals, options, result);
}

// One round's shots in this rank's environments, in the run's order, each
// environment's CPU seconds, grid steps and work recorded in *buffers.
void RunRoundShots(Span<Environment* const> envs, const RankEnvs& rankEnvs,
                   const SolveOptions& options, const SolveResult& result,
                   const RoundTotals& totals, ExchangeBuffers* buffers) {
  const uint32_t n = rankEnvs.total;
  for (uint32_t k = 0; k < n; ++k) {
    uint32_t i = options.order.empty() ? k : options.order[k];
    if (i < rankEnvs.first || i >= rankEnvs.first + rankEnvs.count) continue;
    double envCpu0 = os::CpuSeconds();
    uint64_t steps0 = envs[i - rankEnvs.first]->stats().gridSteps;
    uint64_t work0 = envs[i - rankEnvs.first]->workSteps();
    envs[i - rankEnvs.first]->RunRound(
        ShotBudget(i, n, options.roundShots, result.shots, options.maxShots),
        AdmittedForwards(result.rounds, i, n, options.queueCapacity,
                         options.routed ? totals.held : totals.maxOutstanding),
        options.roundWork);
    buffers->envCpu[i - rankEnvs.first] = os::CpuSeconds() - envCpu0;
    buffers->envSteps[i - rankEnvs.first] = envs[i - rankEnvs.first]->stats().gridSteps - steps0;
    buffers->envWork[i - rankEnvs.first] = envs[i - rankEnvs.first]->workSteps() - work0;
  }
}

}  // namespace

namespace {

// After a round without a shot (`idleRound`; else the idle count restarts):
// whether the solve ends, with the reason in the state's result.
bool IdleStop(bool idleRound, uint32_t n, const SolveOptions& options, SolveState* state) {
  SolveResult& result = state->result;
  if (idleRound && state->totals.shootable == 0) {
    result.reason = StopReason::kConverged;
    return true;
  }
  if (idleRound && options.maxShots > 0 && options.maxShots - result.shots < uint64_t(n)) {
    result.reason = StopReason::kMaxShots;  // the budget left went to environments with none
    return true;
  }
  state->idle = idleRound ? state->idle + 1 : 0;
  if (state->idle >= n) {
    result.reason = StopReason::kStalled;
    return true;
  }
  return false;
}

// The no-loss window after a round: a new one when the unshot power has
// fallen enough, else whether the window is a stall (then kNoLoss).
bool NoLossStall(SolveState* state) {
  const RoundTotals& totals = state->totals;
  if (totals.unshot < (1.0 - kStallFall) * state->windowUnshot) {
    state->windowShot = totals.radiosity - totals.unshot;
    state->windowUnshot = totals.unshot;
    return false;
  }
  if (!(totals.radiosity - totals.unshot - state->windowShot >= kStallShot * state->windowUnshot))
    return false;
  state->result.reason = StopReason::kNoLoss;
  state->result.stallFrom = state->windowUnshot / totals.emitted;
  state->result.stallTo = state->result.unshotFraction;
  return true;
}

}  // namespace

SolveResult Solve(Span<Environment* const> envs, const RankEnvs& rankEnvs, Transport* transport,
                  ExchangeBuffers* buffers, const SolveOptions& options, TextWriter* convergence) {
  const uint32_t n = rankEnvs.total;
  CHECK(envs.size() == rankEnvs.count);
  for (uint32_t i = 0; i < envs.size(); ++i) CHECK(envs[i]->index() == rankEnvs.first + i);
  // The solve's state at a round's end lives in one SolveState, what a
  // checkpoint keeps: zeroed (padding too: its bytes are the checkpoint's),
  // or the checkpoint's when resumed.
  const SolveState* resume = options.resume;
  SolveState state;
  std::memset(static_cast<void*>(&state), 0, sizeof state);
  if (resume)
    std::memcpy(static_cast<void*>(&state), resume, sizeof state);
  else
    new (&state.result) SolveResult();  // its defaults, over the zeroed padding
  SolveResult& result = state.result;
  RoundTotals& totals = state.totals;
  uint64_t& measuredAt = state.measuredAt;  // the shot count last measured
  double &windowShot = state.windowShot, &windowUnshot = state.windowUnshot;
  Progress progress(options.quiet || transport->rank() != 0, options);
  ErrorProbe* probe = options.probe;
  // Resumed: the clock goes on from the checkpoint's.
  const double start =
      os::Seconds() - (resume ? resume->totals.elapsed + result.errorSeconds : 0.0);
  // The solve's clock leaves out the seconds spent measuring the error.
  auto clock = [&] { return os::Seconds() - start - result.errorSeconds; };
  auto measure = [&] {
    double t0 = os::Seconds();
    result.relativeRmse = probe->Measure();
    ++result.errorMeasurements;
    result.errorSeconds += os::Seconds() - t0;
  };
  if (resume) {
    totals.interrupt = 0;
  } else {
    measuredAt = ~0ull;
    totals = GatherTotals(envs, rankEnvs, transport, buffers, 0.0, 0.0, &result.waitSeconds);
    result.collectives = 1;
    SetEstimates(totals, options, &result);
  }
  if (convergence)
    convergence->Printf("shot,seconds,unshot_fraction%s\n",
                        probe ? ",relative_rmse,error_seconds" : "");
  auto row = [&](bool measured) {
    if (!convergence) return;
    convergence->Printf("%llu,%.6f,%.9g", static_cast<unsigned long long>(result.shots),
                        totals.elapsed, result.unshotFraction);
    if (probe && measured)
      convergence->Printf(",%.9g,%.6f\n", result.relativeRmse, result.errorSeconds);
    else
      convergence->Printf(probe ? ",,\n" : "\n");
  };

  // A checkpoint is written only where the solve goes on: a resumed one is not done.
  bool done = resume ? false : ShouldStop(totals, options, &result);
  // The no-loss window: the power shot and the unshot at its start.
  if (!resume) {
    windowShot = totals.radiosity - totals.unshot;
    windowUnshot = totals.unshot;
  }
  const bool bounded = options.maxShots > 0 || options.maxSeconds > 0.0 || options.rayBudget > 0;
  // Each of this rank's environments' CPU seconds of the round.
  CHECK(buffers->envCpu.size() >= envs.size());
  while (!done) {
    if (options.hook && options.hook->AtRoundEnd(state)) {
      result.reason = StopReason::kInterrupted;
      break;
    }
    double cpu0 = os::CpuSeconds();
    RunRoundShots(envs, rankEnvs, options, result, totals, buffers);
    if (probe) probe->Moved();
    double roundCpu = os::CpuSeconds() - cpu0;
    result.computeSeconds += roundCpu;
    ++result.rounds;
    uint64_t before = result.shots;
    double elapsed = clock();
    totals =
        ExchangeRound(envs, rankEnvs, transport, buffers, elapsed, roundCpu, &result.waitSeconds);
    ++result.collectives;
    AddRound(totals, options, &result);
    if (options.pacer) options.pacer->AfterRound(totals, envs);
    // A round without a shot is convergence only when nothing is left to
    // shoot anywhere (--stop-unshot 0 drains every queue). Otherwise the
    // admission held back every environment that had power; its rotation
    // admits each within n rounds, so n such rounds in a row are a stall.
    bool idleRound = result.shots == before;
    if (IdleStop(idleRound, n, options, &state)) break;
    done = ShouldStop(totals, options, &result);
    // The no-loss window: a new one opens as soon as the unshot power has
    // fallen by kStallFall of the window's start; kStallShot times that
    // start shot without it is a stall. (Not when the run is bounded by
    // --max-shots, --max-seconds or --ray-budget: the user stops it, and
    // gets its outputs.)
    if (!done && !bounded && NoLossStall(&state)) break;
    if (idleRound && !done) continue;  // nothing new to measure or record
    bool due = probe && (done || (options.errorEvery > 0 &&
                                  result.shots / options.errorEvery > before / options.errorEvery));
    if (due) {
      measure();
      measuredAt = result.shots;
    }
    row(due);
    progress.Update(os::Seconds(), elapsed, result.shots, result.unshotFraction, false);
  }
  if (probe && measuredAt != result.shots && result.reason != StopReason::kInterrupted) {
    measure();
    row(true);
  }
  result.seconds = clock();
  progress.Update(os::Seconds(), result.seconds, result.shots, result.unshotFraction, true);
  return result;
}

// The reflectance behind Cohen's 1/(1 - rho): `rhoKd`, the area-mean kd,
// while it is below 1. At 1 (every face has kd 1, in a channel or in all)
// it bounds nothing: such a scene loses power only by back faces and
// escape (the loader refuses one that cannot lose any), and the share of
// the power shot so far that was lost stands in for 1 - rho: of the power
// shot, the radiosity power R less the unshot U, the emitted E less U was
// absorbed or escaped. 1 when nothing has been shot or lost yet: no
// estimate.
double EffectiveReflectance(double rhoKd, double emitted, double unshot, double radiosity) {
  if (rhoKd < 1.0) return rhoKd;
  double shot = radiosity - unshot, lost = emitted - unshot;
  if (!(shot > 0.0) || !(lost > 1e-12 * shot)) return 1.0;
  return std::fmax(0.0, 1.0 - lost / shot);
}

double BiasEstimate(const RoundTotals& t, bool corrected) {
  double rho = t.area > 0.0 ? t.kdArea / t.area : 0.0;
  rho = EffectiveReflectance(rho, t.emitted, t.unshot, t.radiosity);
  if (rho >= 1.0) return 1.0;  // no estimate: all of b may be still to come
  double future = t.unshot * rho / (1.0 - rho);
  double total = t.radiosity + future;
  double share = total > 0.0 ? future / total : 0.0;
  return corrected ? share * (1.0 - rho) : share;
}

double LossEstimate(const RoundTotals& t) {
  double rho = t.area > 0.0 ? t.kdArea / t.area : 0.0;
  rho = EffectiveReflectance(rho, t.emitted, t.unshot, t.radiosity);
  if (rho >= 1.0) return 1.0;  // no estimate
  double missing = t.lost * rho / (1.0 - rho);
  double total = t.radiosity + t.unshot * rho / (1.0 - rho) + missing;
  return total > 0.0 ? std::fabs(missing / total) : 0.0;
}

AmbientReport AmbientOf(const Environment& env) {
  AmbientReport r{};
  r.area = env.totalArea();
  double flight[3];
  env.FlightPower(flight);
  for (int c = 0; c < 3; ++c) {
    r.unshot[c] = env.ledger().unshot[c] + flight[c];
    r.emitted[c] = env.ledger().emitted[c];
    r.radiosity[c] = env.ledger().radiosity[c];
  }
  env.EmissionUnshot(r.emission);
  for (const Patch& p : env.patches())
    for (int c = 0; c < 3; ++c) r.kdArea[c] += static_cast<double>(p.kd[c]) * p.area;
  return r;
}

void AmbientTerm(Span<const AmbientReport> reports, double ambient[3], bool direct) {
  double area = 0.0, unshot[3] = {0, 0, 0}, kdArea[3] = {0, 0, 0}, emitted[3] = {0, 0, 0},
         radiosity[3] = {0, 0, 0}, emission[3] = {0, 0, 0};
  for (const AmbientReport& r : reports) {
    area += r.area;
    for (int c = 0; c < 3; ++c) {
      emission[c] += r.emission[c];
      unshot[c] += r.unshot[c];
      kdArea[c] += r.kdArea[c];
      emitted[c] += r.emitted[c];
      radiosity[c] += r.radiosity[c];
    }
  }
  for (int c = 0; c < 3; ++c) {
    double meanKd = area > 0.0 ? kdArea[c] / area : 0.0;
    meanKd = EffectiveReflectance(meanKd, emitted[c], unshot[c], radiosity[c]);
    // No estimate (nothing shot or lost yet in a channel where every face
    // has kd 1): no ambient term rather than an infinite one.
    ambient[c] = area > 0.0 && meanKd < 1.0 ? unshot[c] / area / (1.0 - meanKd) : 0.0;
    if (!direct) continue;
    // Per-pixel direct light: the reflectance the shots so far have met
    // (what came back reflected over the power shot: the open sides of a
    // scene lose light that the mean kd does not know of), and the image's
    // share of what is not yet shown: of the unshot emission only the
    // bounces after its first.
    double reflected = radiosity[c] - emitted[c], shot = emitted[c] + reflected - unshot[c];
    double rho = shot > 0.0 && reflected >= 0.0 ? std::fmin(reflected / shot, 0.999) : meanKd;
    ambient[c] = kdArea[c] > 0.0 && rho < 1.0
                     ? (unshot[c] - emission[c] + emission[c] * rho) * rho / (1.0 - rho) / kdArea[c]
                     : 0.0;
  }
}

}  // namespace vismask
