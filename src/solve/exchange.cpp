#include "vismask/solve/exchange.h"

#include <cstring>

#include "vismask/core/check.h"
#include "vismask/core/os.h"
#include "vismask/solve/packet.h"

namespace vismask {

void ExchangeBuffers::Layout(Arena& arena, const RankEnvs& envs, int ranks, uint32_t bytesPerPacket,
                             uint32_t packetsPerEnvRound, uint32_t outboxPackets) {
  packetBytes = bytesPerPacket;
  reportBytes = size_t(envs.perRank) * sizeof(EnvReport);
  blockBytes = reportBytes + size_t(envs.perRank) * packetsPerEnvRound * bytesPerPacket;
  size_t n = static_cast<size_t>(ranks);
  sendBytes = arena.Alloc<uint8_t>(n * blockBytes);
  recvBytes = arena.Alloc<uint8_t>(n * blockBytes);
  send = arena.Alloc<Span<const uint8_t>>(n);
  recv = arena.Alloc<Span<uint8_t>>(n);
  received = arena.Alloc<size_t>(n);
  mine = arena.Alloc<EnvReport>(envs.perRank);
  all = arena.Alloc<EnvReport>(n * envs.perRank);
  envCpu = arena.Alloc<double>(envs.perRank);
  envSteps = arena.Alloc<uint64_t>(envs.perRank);
  envWork = arena.Alloc<uint64_t>(envs.perRank);
  // A rank delivers its own environments' outboxes and a block from each other rank.
  arrived = arena.Alloc<const uint8_t*>(size_t(envs.perRank) * outboxPackets +
                                        (n - 1) * envs.perRank * size_t(packetsPerEnvRound));
  bucket = arena.Alloc<uint32_t>(size_t(envs.perRank) + 1);
}

namespace {

// to.*field += from.*field for each field, in the order given.
template <class T, class... M>
void AddFields(T* to, const T& from, M T::*... field) {
  ((to->*field += from.*field), ...);
}

}  // namespace

void EnvSums::Add(const EnvSums& o) {
  using S = EnvSums;
  AddFields(this, o, &S::unshot, &S::flight, &S::lost, &S::emitted, &S::emission, &S::radiosity,
            &S::kdArea, &S::area, &S::work, &S::steps, &S::shots, &S::foreignShots, &S::paceWork,
            &S::shotWork, &S::rays, &S::forwardsCreated, &S::held, &S::shootable);
}

namespace {

double Sum3(const double v[3]) {
  return v[0] + v[1] + v[2];
}

// Runs a transport collective, adding the time it takes to *waited.
template <class Call>
void Timed(double* waited, Call&& call) {
  double t0 = os::Seconds();
  call();
  *waited += os::Seconds() - t0;
}

// This rank's reports (x->mine): each environment's state now, its outbox
// counted as in flight and queued (FlightPower, shootable).
void FillReports(Span<Environment* const> envs, const RankEnvs& rankEnvs, ExchangeBuffers* x,
                 double elapsed, double roundCpu, double waited) {
  for (uint32_t i = 0; i < rankEnvs.perRank; ++i) x->mine[i] = EnvReport{};
  for (uint32_t i = 0; i < envs.size(); ++i) {
    const Environment* e = envs[i];
    EnvReport& r = x->mine[i];
    double flight[3];
    e->FlightPower(flight);
    const EnergyLedger& l = e->ledger();
    r.flight = Sum3(flight);
    r.unshot = Sum3(l.unshot) + r.flight;
    r.lost = Sum3(l.emitted) - Sum3(l.absorbed) - Sum3(l.escaped) - r.unshot;
    // What --sky and --sun lost at once never lit the scene: the stop rules
    // count without it (EnergyLedger::outsideLost; 0 without them).
    r.emitted = Sum3(l.emitted) - Sum3(l.outsideLost);
    double emission[3];
    e->EmissionLeft(emission);
    r.emission = Sum3(emission);
    const uint32_t queued = e->exchange().queue().count(), out = e->exchange().outbox().count();
    r.held = uint64_t(queued) + out;
    r.shootable = queued + out + e->HasLocalUnshot();
    r.shots = e->stats().shots + e->stats().foreignShots;
    r.rays = e->stats().rays;
    r.forwardsCreated = e->stats().forwardsCreated;
    r.foreignShots = e->stats().foreignShots;
    r.paceWork = e->paceWork();
    r.shotWork = e->shotWork();
    r.radiosity = Sum3(e->ledger().radiosity) - Sum3(l.outsideLost);
    r.area = e->totalArea();
    r.kdArea = e->kdArea();
    r.envCpu = i < x->envCpu.size() ? x->envCpu[i] : 0.0;
    r.roundSteps = i < x->envSteps.size() ? x->envSteps[i] : 0;
    r.steps = e->stats().gridSteps;
    r.roundWork = i < x->envWork.size() ? x->envWork[i] : 0;
    r.work = e->workSteps();
  }
  x->mine[0].elapsed = elapsed;
  x->mine[0].waited = waited;
  x->mine[0].roundCpu = roundCpu;
  x->mine[0].interrupt = static_cast<uint64_t>(os::PendingInterrupt());
}

// The totals of the gathered reports (x->all), summed in environment order.
RoundTotals SumTotals(const RankEnvs& rankEnvs, int ranks, const ExchangeBuffers* x) {
  // Rank r's block holds its environments first; the rest is padding.
  RoundTotals tot;
  tot.elapsed = x->all[0].elapsed;
  for (int r = 0; r < ranks; ++r) {
    const EnvReport& first = x->all[size_t(r) * rankEnvs.perRank];
    if (first.waited > tot.waitedMax) tot.waitedMax = first.waited;
    if (first.roundCpu > tot.roundCpuMax) tot.roundCpuMax = first.roundCpu;
    tot.roundCpuSum += first.roundCpu;
    if (first.interrupt > tot.interrupt) tot.interrupt = first.interrupt;
    RankEnvs re = EnvsOfRank(rankEnvs.total, ranks, r);
    uint64_t rankSteps = 0, rankWork = 0;
    for (uint32_t k = 0; k < re.count; ++k) {
      rankSteps += x->all[size_t(r) * rankEnvs.perRank + k].roundSteps;
      rankWork += x->all[size_t(r) * rankEnvs.perRank + k].roundWork;
    }
    if (rankSteps > tot.rankStepsMax) tot.rankStepsMax = rankSteps;
    if (rankWork > tot.rankWorkMax) tot.rankWorkMax = rankWork;
  }
  auto report = [&](uint32_t env) -> const EnvReport& {
    int r = RankOfEnv(env, rankEnvs.total, ranks);
    RankEnvs re = EnvsOfRank(rankEnvs.total, ranks, r);
    return x->all[size_t(r) * rankEnvs.perRank + (env - re.first)];
  };
  for (uint32_t env = 0; env < rankEnvs.total; ++env) {
    const EnvReport& r = report(env);
    tot.Add(r);
    if (r.envCpu > tot.envCpuMax) tot.envCpuMax = r.envCpu;
    if (r.roundSteps > tot.envStepsMax) tot.envStepsMax = r.roundSteps;
    if (r.roundWork > tot.envWorkMax) tot.envWorkMax = r.roundWork;
  }
  for (uint32_t env = 0; env < rankEnvs.total; ++env) {
    const EnvReport& r = report(env);
    uint64_t outstanding = tot.forwardsCreated - r.forwardsCreated - r.foreignShots;
    if (outstanding > tot.maxOutstanding) tot.maxOutstanding = outstanding;
  }
  return tot;
}

}  // namespace

RoundTotals GatherTotals(Span<Environment* const> envs, const RankEnvs& rankEnvs, Transport* t,
                         ExchangeBuffers* x, double elapsed, double roundCpu, double* waited) {
  FillReports(envs, rankEnvs, x, elapsed, roundCpu, *waited);
  Timed(waited, [&] { t->AllGather(x->mine.data(), x->mine.bytes(), x->all.data()); });
  return SumTotals(rankEnvs, t->size(), x);
}

RoundTotals ExchangeRound(Span<Environment* const> envs, const RankEnvs& rankEnvs, Transport* t,
                          ExchangeBuffers* x, double elapsed, double roundCpu, double* waited) {
  FillReports(envs, rankEnvs, x, elapsed, roundCpu, *waited);
  int ranks = t->size(), me = t->rank();
  std::memcpy(x->all.data() + size_t(me) * rankEnvs.perRank, x->mine.data(), x->reportBytes);
  if (ranks > 1) {
    // Each block: this rank's reports, then its packets for that rank.
    for (int r = 0; r < ranks; ++r) {
      RankEnvs re = EnvsOfRank(rankEnvs.total, ranks, r);
      uint8_t* block = x->sendBytes.data() + size_t(r) * x->blockBytes;
      size_t used = 0;
      if (r != me) {
        std::memcpy(block, x->mine.data(), x->reportBytes);
        used = x->reportBytes;
        for (Environment* src : envs) {
          const Outbox& outbox = src->exchange().outbox();
          for (uint32_t k = 0; k < outbox.count(); ++k) {
            const uint8_t* packet = outbox.Packet(k);
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
    for (int r = 0; r < ranks; ++r) {
      if (r == me) continue;
      CHECK(x->received[r] >= x->reportBytes &&
            (x->received[r] - x->reportBytes) % x->packetBytes == 0);
      std::memcpy(x->all.data() + size_t(r) * rankEnvs.perRank, x->recv[r].data(), x->reportBytes);
    }
  }
  // Every packet for this rank's environments in sender order (ranks hold
  // contiguous blocks of environments, so rank order then the packets'
  // order), counted by receiver, then placed: a counting sort, so each
  // receiver gets its packets in the order a pass over them all would.
  const uint32_t first = rankEnvs.first, local = static_cast<uint32_t>(envs.size());
  for (uint32_t d = 0; d <= local; ++d) x->bucket[d] = 0;
  auto visit = [&](auto&& take) {
    for (int r = 0; r < ranks; ++r) {
      if (r == me) {
        for (Environment* src : envs) {
          const Outbox& outbox = src->exchange().outbox();
          for (uint32_t k = 0; k < outbox.count(); ++k) take(outbox.Packet(k));
        }
      } else {
        for (size_t off = x->reportBytes; off < x->received[r]; off += x->packetBytes)
          take(x->recv[r].data() + off);
      }
    }
  };
  auto receiver = [&](const uint8_t* packet) {
    const uint32_t to = ReadHeader(packet).toEnv;
    return to >= first && to < first + local ? to - first : local;  // local: not ours
  };
  visit([&](const uint8_t* packet) {
    const uint32_t d = receiver(packet);
    if (d < local) ++x->bucket[d + 1];
  });
  for (uint32_t d = 0; d < local; ++d) x->bucket[d + 1] += x->bucket[d];
  CHECK(x->bucket[local] <= x->arrived.size());
  visit([&](const uint8_t* packet) {
    const uint32_t d = receiver(packet);
    if (d < local) x->arrived[x->bucket[d]++] = packet;
  });
  // bucket[d] is now the end of d's packets, which start at bucket[d - 1].
  for (uint32_t d = 0; d < local; ++d)
    for (uint32_t k = d == 0 ? 0 : x->bucket[d - 1]; k < x->bucket[d]; ++k)
      envs[d]->Deliver(x->arrived[k]);
  for (Environment* e : envs) e->ClearOutbox();
  return SumTotals(rankEnvs, ranks, x);
}

}  // namespace vismask
