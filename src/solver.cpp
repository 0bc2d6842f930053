#include "vismask/solver.h"

#include <cstdio>

#include "vismask/os.h"
#include "vismask/rng.h"

namespace vismask {

const char* StopReasonName(StopReason r) {
  switch (r) {
    case StopReason::kConverged: return "converged";
    case StopReason::kMaxShots: return "max-shots";
    case StopReason::kMaxSeconds: return "max-seconds";
  }
  return "?";
}

namespace {

double Sum3(const double v[3]) { return v[0] + v[1] + v[2]; }

// Unshot and emitted power over all environments, in environment order (the
// same order whatever the grouping onto ranks).
void Totals(Span<Environment* const> envs, double* unshot, double* emitted) {
  *unshot = 0.0;
  *emitted = 0.0;
  for (Environment* e : envs) {
    *unshot += Sum3(e->ledger().unshot);
    *emitted += Sum3(e->ledger().emitted);
  }
}

class Progress {
 public:
  explicit Progress(bool quiet) : quiet_(quiet), tty_(os::StderrIsTerminal()) {}
  void Update(double now, double elapsed, uint64_t shots, double unshot, bool final) {
    if (quiet_) return;
    if (!final && now < next_) return;
    next_ = now + (tty_ ? 0.25 : 2.0);
    double rate = elapsed > 0.0 ? static_cast<double>(shots) / elapsed : 0.0;
    os::PrintErr("%svismask: shot %llu  unshot %.4f%%  %.1f s  %.0f shots/s%s", tty_ ? "\r" : "",
                 static_cast<unsigned long long>(shots), 100.0 * unshot, elapsed, rate,
                 tty_ && !final ? "   " : "\n");
  }

 private:
  bool quiet_;
  bool tty_;
  double next_ = 0.0;
};

}  // namespace

SolveResult Solve(Span<Environment* const> envs, const SolveOptions& options,
                  TextWriter* convergence) {
  // Energy crosses environments only with visibility masks (local
  // environments); until then a solve is one environment.
  CHECK_MSG(envs.size() == 1, "multi-environment solves need the mask propagation");
  CHECK(options.rays > 0);
  SolveResult result;
  Progress progress(options.quiet);
  double start = os::Seconds();
  double unshot = 0.0, emitted = 0.0;
  Totals(envs, &unshot, &emitted);
  result.unshotFraction = emitted > 0.0 ? unshot / emitted : 0.0;
  if (convergence) convergence->Printf("shot,seconds,unshot_fraction\n");

  for (;;) {
    double now = os::Seconds();
    double elapsed = now - start;
    if (result.unshotFraction < options.stopUnshot) {
      result.reason = StopReason::kConverged;
      break;
    }
    if (options.maxShots > 0 && result.shots >= options.maxShots) {
      result.reason = StopReason::kMaxShots;
      break;
    }
    if (options.maxSeconds > 0.0 && elapsed >= options.maxSeconds) {
      result.reason = StopReason::kMaxSeconds;
      break;
    }
    for (Environment* env : envs) {
      uint32_t i = env->TopShooter();
      if (i == kNoPatch || env->ShooterKey(i) <= 0.0) continue;
      uint64_t key = ShotKey(options.seed, env->patches()[i].globalId, env->ShotCount(i));
      env->Shoot(i, options.rays, key);
      ++result.shots;
    }
    Totals(envs, &unshot, &emitted);
    result.unshotFraction = emitted > 0.0 ? unshot / emitted : 0.0;
    double t = os::Seconds() - start;
    if (convergence)
      convergence->Printf("%llu,%.6f,%.9g\n", static_cast<unsigned long long>(result.shots), t,
                          result.unshotFraction);
    progress.Update(now, t, result.shots, result.unshotFraction, false);
  }
  result.seconds = os::Seconds() - start;
  for (Environment* env : envs) {
    result.rays += env->stats().rays;
    result.hits += env->stats().hits;
  }
  progress.Update(os::Seconds(), result.seconds, result.shots, result.unshotFraction, true);
  return result;
}

void AmbientTerm(Span<Environment* const> envs, double ambient[3]) {
  double area = 0.0, unshot[3] = {0, 0, 0}, kdArea[3] = {0, 0, 0};
  for (Environment* env : envs) {
    area += env->totalArea();
    for (int c = 0; c < 3; ++c) unshot[c] += env->ledger().unshot[c];
    for (const Patch& p : env->patches())
      for (int c = 0; c < 3; ++c) kdArea[c] += static_cast<double>(p.kd[c]) * p.area;
  }
  for (int c = 0; c < 3; ++c) {
    double meanKd = area > 0.0 ? kdArea[c] / area : 0.0;
    ambient[c] = area > 0.0 ? unshot[c] / area / (1.0 - meanKd) : 0.0;
  }
}

}  // namespace vismask
