#include "vismask/solver.h"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "vismask/os.h"

namespace vismask {

const char* StopReasonName(StopReason r) {
  switch (r) {
    case StopReason::kConverged: return "converged";
    case StopReason::kMaxShots: return "max-shots";
    case StopReason::kMaxSeconds: return "max-seconds";
    case StopReason::kRayBudget: return "ray-budget";
    case StopReason::kStalled: return "stalled";
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

uint32_t ShotBudget(uint32_t env, uint32_t roundShots, uint64_t shotsSoFar, uint64_t maxShots) {
  if (maxShots == 0) return roundShots;
  uint64_t remaining = maxShots > shotsSoFar ? maxShots - shotsSoFar : 0;
  uint64_t before = uint64_t(env) * roundShots;  // environments earlier in order go first
  if (remaining <= before) return 0;
  uint64_t left = remaining - before;
  return static_cast<uint32_t>(left < roundShots ? left : roundShots);
}

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

void ExchangeBuffers::Layout(Arena& arena, const RankEnvs& envs, int ranks, uint32_t bytesPerPacket,
                             uint32_t packetsPerEnvRound) {
  packetBytes = bytesPerPacket;
  blockBytes = size_t(envs.perRank) * packetsPerEnvRound * bytesPerPacket;
  size_t n = static_cast<size_t>(ranks);
  sendBytes = arena.Alloc<uint8_t>(n * blockBytes);
  recvBytes = arena.Alloc<uint8_t>(n * blockBytes);
  send = arena.Alloc<Span<const uint8_t>>(n);
  recv = arena.Alloc<Span<uint8_t>>(n);
  received = arena.Alloc<size_t>(n);
  mine = arena.Alloc<EnvReport>(envs.perRank);
  all = arena.Alloc<EnvReport>(n * envs.perRank);
}

namespace {

double Sum3(const double v[3]) { return v[0] + v[1] + v[2]; }

// Runs a transport collective, adding the time it takes to *waited.
template <class Call>
void Timed(double* waited, Call&& call) {
  double t0 = os::Seconds();
  call();
  *waited += os::Seconds() - t0;
}

// Gathers every environment's report and sums them in environment order.

RoundTotals Totals(Span<Environment* const> envs, const RankEnvs& layout, Transport* t,
                   ExchangeBuffers* x, double elapsed, double roundCpu, double* waited) {
  for (uint32_t i = 0; i < layout.perRank; ++i) x->mine[i] = EnvReport{};
  for (uint32_t i = 0; i < envs.size(); ++i) {
    const Environment* e = envs[i];
    EnvReport& r = x->mine[i];
    double flight[3];
    e->FlightPower(flight);
    const EnergyLedger& l = e->ledger();
    r.flight = Sum3(flight);
    r.unshot = Sum3(l.unshot) + r.flight;
    r.emitted = Sum3(l.emitted);
    r.lost = r.emitted - Sum3(l.absorbed) - Sum3(l.escaped) - r.unshot;
    uint32_t top = e->TopShooter();
    r.shootable = e->queuedCount() + (top != kNoPatch && Sum3(e->energy()[top].unshot) > 0.0);
    r.shots = e->stats().shots + e->stats().foreignShots;
    r.rays = e->stats().rays;
    r.recordsCreated = e->stats().recordsCreated;
    r.foreignShots = e->stats().foreignShots;
    r.radiosity = Sum3(e->ledger().radiosity);
    r.area = e->totalArea();
    r.kdArea = e->kdArea();
  }
  x->mine[0].elapsed = elapsed;
  x->mine[0].waited = *waited;
  x->mine[0].roundCpu = roundCpu;
  Timed(waited, [&] { t->AllGather(x->mine.data(), x->mine.bytes(), x->all.data()); });
  // Rank r's block holds its environments first; the rest is padding.
  RoundTotals tot;
  tot.elapsed = x->all[0].elapsed;
  int ranks = t->size();
  for (int r = 0; r < ranks; ++r) {
    const EnvReport& first = x->all[size_t(r) * layout.perRank];
    if (first.waited > tot.waitedMax) tot.waitedMax = first.waited;
    if (first.roundCpu > tot.roundCpuMax) tot.roundCpuMax = first.roundCpu;
  }
  auto report = [&](uint32_t env) -> const EnvReport& {
    for (int r = 0; r < ranks; ++r) {
      RankEnvs re = EnvsOfRank(layout.total, ranks, r);
      if (env < re.first + re.count) return x->all[size_t(r) * layout.perRank + (env - re.first)];
    }
    CHECK(false);
    return x->all[0];
  };
  for (uint32_t env = 0; env < layout.total; ++env) {
    const EnvReport& r = report(env);
    tot.unshot += r.unshot;
    tot.flight += r.flight;
    tot.lost += r.lost;
    tot.shootable += r.shootable;
    tot.emitted += r.emitted;
    tot.shots += r.shots;
    tot.rays += r.rays;
    tot.recordsCreated += r.recordsCreated;
    tot.radiosity += r.radiosity;
    tot.kdArea += r.kdArea;
    tot.area += r.area;
  }
  for (uint32_t env = 0; env < layout.total; ++env) {
    const EnvReport& r = report(env);
    uint64_t outstanding = tot.recordsCreated - r.recordsCreated - r.foreignShots;
    if (outstanding > tot.maxOutstanding) tot.maxOutstanding = outstanding;
  }
  return tot;
}

// Moves the round's packets to their receivers and delivers them: for each
// receiver, senders in environment order and packets in send order.
void Exchange(Span<Environment* const> envs, const RankEnvs& layout, Transport* t,
              ExchangeBuffers* x, double* waited) {
  int ranks = t->size(), me = t->rank();
  if (ranks > 1) {
    for (int r = 0; r < ranks; ++r) {
      RankEnvs re = EnvsOfRank(layout.total, ranks, r);
      uint8_t* block = x->sendBytes.data() + size_t(r) * x->blockBytes;
      size_t used = 0;
      if (r != me) {
        for (Environment* src : envs) {
          for (uint32_t k = 0; k < src->outboxCount(); ++k) {
            const uint8_t* packet = src->OutboxPacket(k);
            uint32_t to = ReadHeader(packet).toEnv;
            if (to < re.first || to >= re.first + re.count) continue;
            CHECK(used + x->packetBytes <= x->blockBytes);
            std::memcpy(block + used, packet, x->packetBytes);
            used += x->packetBytes;
          }
        }
      }
      x->send[r] = Span<const uint8_t>(block, used);
      x->recv[r] = Span<uint8_t>(x->recvBytes.data() + size_t(r) * x->blockBytes, x->blockBytes);
    }
    Timed(waited, [&] { t->AllToAll(x->send.data(), x->recv.data(), x->received.data()); });
  }
  for (Environment* dest : envs) {
    for (int r = 0; r < ranks; ++r) {
      if (r == me) {
        for (Environment* src : envs) {
          for (uint32_t k = 0; k < src->outboxCount(); ++k) {
            const uint8_t* packet = src->OutboxPacket(k);
            if (ReadHeader(packet).toEnv == dest->index()) dest->Deliver(packet);
          }
        }
      } else {
        CHECK(x->received[r] % x->packetBytes == 0);
        for (size_t off = 0; off < x->received[r]; off += x->packetBytes) {
          const uint8_t* packet = x->recv[r].data() + off;
          if (ReadHeader(packet).toEnv == dest->index()) dest->Deliver(packet);
        }
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

}  // namespace

SolveResult Solve(Span<Environment* const> envs, const RankEnvs& layout, Transport* transport,
                  ExchangeBuffers* buffers, const SolveOptions& options, TextWriter* convergence) {
  const uint32_t n = layout.total;
  CHECK(envs.size() == layout.count);
  for (uint32_t i = 0; i < envs.size(); ++i) CHECK(envs[i]->index() == layout.first + i);
  SolveResult result;
  Progress progress(options.quiet || transport->rank() != 0);
  ErrorProbe* probe = options.probe;
  const double start = os::Seconds();
  // The solve's clock leaves out the seconds spent measuring the error.
  auto clock = [&] { return os::Seconds() - start - result.errorSeconds; };
  auto measure = [&] {
    double t0 = os::Seconds();
    result.relativeRmse = probe->Measure();
    ++result.errorMeasurements;
    result.errorSeconds += os::Seconds() - t0;
  };
  uint64_t measuredAt = ~0ull;  // the shot count last measured
  RoundTotals totals = Totals(envs, layout, transport, buffers, 0.0, 0.0, &result.waitSeconds);
  result.unshotFraction = totals.emitted > 0.0 ? totals.unshot / totals.emitted : 0.0;
  result.biasEstimate = BiasEstimate(totals, options.correctUnshot);
  result.lossEstimate = LossEstimate(totals);
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

  bool done = ShouldStop(totals, options, &result);
  uint32_t idle = 0;  // rounds in a row without a shot
  while (!done) {
    double cpu0 = os::CpuSeconds();
    for (uint32_t k = 0; k < n; ++k) {
      uint32_t i = options.order.empty() ? k : options.order[k];
      if (i < layout.first || i >= layout.first + layout.count) continue;
      envs[i - layout.first]->RunRound(
          ShotBudget(i, options.roundShots, result.shots, options.maxShots),
          AdmittedRecords(result.rounds, i, n, options.queueCapacity, totals.maxOutstanding));
    }
    double roundCpu = os::CpuSeconds() - cpu0;
    result.computeSeconds += roundCpu;
    Exchange(envs, layout, transport, buffers, &result.waitSeconds);
    ++result.rounds;
    uint64_t before = result.shots;
    double elapsed = clock();
    totals = Totals(envs, layout, transport, buffers, elapsed, roundCpu, &result.waitSeconds);
    result.waitSecondsMax = totals.waitedMax;
    result.criticalSeconds += totals.roundCpuMax;
    result.shots = totals.shots;
    result.rays = totals.rays;
    result.unshotFraction = totals.emitted > 0.0 ? totals.unshot / totals.emitted : 0.0;
    result.biasEstimate = BiasEstimate(totals, options.correctUnshot);
    result.lossEstimate = LossEstimate(totals);
    // A round without a shot is convergence only when nothing is left to
    // shoot anywhere (--stop-unshot 0 drains every queue). Otherwise the
    // admission held back every environment that had power; its rotation
    // admits each within n rounds, so n such rounds in a row are a stall.
    bool idleRound = result.shots == before;
    if (idleRound && totals.shootable == 0) {
      result.reason = StopReason::kConverged;
      break;
    }
    if (idleRound && options.maxShots > 0 &&
        options.maxShots - result.shots < uint64_t(n) * options.roundShots) {
      result.reason = StopReason::kMaxShots;  // the budget left went to environments with none
      break;
    }
    idle = idleRound ? idle + 1 : 0;
    if (idle >= n) {
      result.reason = StopReason::kStalled;
      break;
    }
    done = ShouldStop(totals, options, &result);
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
  if (probe && measuredAt != result.shots) {
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
  for (const Patch& p : env.patches())
    for (int c = 0; c < 3; ++c) r.kdArea[c] += static_cast<double>(p.kd[c]) * p.area;
  return r;
}

void AmbientTerm(Span<const AmbientReport> reports, double ambient[3]) {
  double area = 0.0, unshot[3] = {0, 0, 0}, kdArea[3] = {0, 0, 0}, emitted[3] = {0, 0, 0},
         radiosity[3] = {0, 0, 0};
  for (const AmbientReport& r : reports) {
    area += r.area;
    for (int c = 0; c < 3; ++c) {
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
  }
}

}  // namespace vismask
