#include "vismask/solver.h"

#include <cstdio>

#include "vismask/os.h"

namespace vismask {

const char* StopReasonName(StopReason r) {
  switch (r) {
    case StopReason::kConverged: return "converged";
    case StopReason::kMaxShots: return "max-shots";
    case StopReason::kMaxSeconds: return "max-seconds";
  }
  return "?";
}

uint32_t AdmittedRecords(uint64_t round, uint32_t env, uint32_t numEnvs, uint64_t capacity,
                         uint64_t maxOutstanding) {
  if (numEnvs <= 1) return 0;
  // Every record created now may land in every other environment's queue,
  // so the total admitted across environments is what the fullest can take.
  uint64_t admit = capacity > maxOutstanding ? capacity - maxOutstanding : 0;
  uint64_t base = admit / numEnvs, extra = admit % numEnvs;
  uint64_t turn = (env + numEnvs - round % numEnvs) % numEnvs;  // rotate the remainder
  uint64_t mine = base + (turn < extra ? 1 : 0);
  return mine > 0xffffffffu ? 0xffffffffu : static_cast<uint32_t>(mine);
}

uint32_t ShotBudget(uint32_t env, uint32_t numEnvs, uint32_t roundShots, uint64_t shotsSoFar,
                    uint64_t maxShots) {
  (void)numEnvs;
  if (maxShots == 0) return roundShots;
  uint64_t remaining = maxShots > shotsSoFar ? maxShots - shotsSoFar : 0;
  uint64_t before = uint64_t(env) * roundShots;  // environments earlier in order go first
  if (remaining <= before) return 0;
  uint64_t left = remaining - before;
  return static_cast<uint32_t>(left < roundShots ? left : roundShots);
}

namespace {

double Sum3(const double v[3]) { return v[0] + v[1] + v[2]; }

RoundTotals Totals(Span<Environment* const> envs) {
  RoundTotals t;
  for (Environment* e : envs) {
    t.unshot += Sum3(e->ledger().unshot) + e->QueuedPower();
    t.emitted += Sum3(e->ledger().emitted);
    t.shots += e->stats().shots + e->stats().foreignShots;
    t.recordsCreated += e->stats().recordsCreated;
  }
  for (Environment* e : envs) {
    uint64_t fromOthers = t.recordsCreated - e->stats().recordsCreated;
    uint64_t outstanding = fromOthers - e->stats().foreignShots;
    if (outstanding > t.maxOutstanding) t.maxOutstanding = outstanding;
  }
  return t;
}

// Delivers every outbox packet to its receiver: receivers in order, and for
// each, senders in order and packets in the order they were sent.
void Exchange(Span<Environment* const> envs) {
  for (Environment* dest : envs) {
    for (Environment* src : envs) {
      for (uint32_t k = 0; k < src->outboxCount(); ++k) {
        const uint8_t* packet = src->OutboxPacket(k);
        if (ReadHeader(packet).toEnv == dest->index()) dest->Deliver(packet);
      }
    }
  }
  for (Environment* e : envs) e->ClearOutbox();
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
  const uint32_t n = static_cast<uint32_t>(envs.size());
  for (uint32_t i = 0; i < n; ++i) CHECK(envs[i]->index() == i);
  SolveResult result;
  Progress progress(options.quiet);
  double start = os::Seconds();
  RoundTotals totals = Totals(envs);
  result.unshotFraction = totals.emitted > 0.0 ? totals.unshot / totals.emitted : 0.0;
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
    for (uint32_t k = 0; k < n; ++k) {
      uint32_t i = options.order.empty() ? k : options.order[k];
      envs[i]->RunRound(
          ShotBudget(i, n, options.roundShots, result.shots, options.maxShots),
          AdmittedRecords(result.rounds, i, n, options.queueCapacity, totals.maxOutstanding));
    }
    Exchange(envs);
    ++result.rounds;
    uint64_t before = result.shots;
    totals = Totals(envs);
    result.shots = totals.shots;
    // A ready foreign shooter exists whenever any queue holds one, so a round
    // without a shot means no power is left to shoot (--stop-unshot 0).
    if (result.shots == before) {
      result.unshotFraction = totals.emitted > 0.0 ? totals.unshot / totals.emitted : 0.0;
      result.reason = StopReason::kConverged;
      break;
    }
    result.unshotFraction = totals.emitted > 0.0 ? totals.unshot / totals.emitted : 0.0;
    double t = os::Seconds() - start;
    if (convergence)
      convergence->Printf("%llu,%.6f,%.9g\n", static_cast<unsigned long long>(result.shots), t,
                          result.unshotFraction);
    progress.Update(now, t, result.shots, result.unshotFraction, false);
  }
  result.seconds = os::Seconds() - start;
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
