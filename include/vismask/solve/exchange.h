// The exchange between rounds, one collective a round: the round's packets
// moved to the ranks of their receivers and delivered in a fixed order, and
// every environment's report, which travels with them, summed in
// environment order (so every rank takes the same decisions whatever the
// grouping). The buffers are carved from the rank's arena at init; nothing
// here allocates.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/parallel/ranks.h"
#include "vismask/parallel/transport.h"
#include "vismask/solve/environment.h"

namespace vismask {

// What adds up across environments: each environment's share in its
// EnvReport, their sums, taken in environment order, in RoundTotals.
struct EnvSums {
  double unshot = 0.0;  // local unshot power plus the power in flight booked here
  double flight = 0.0;  // the latter (Environment::FlightPower), channels summed
  double lost = 0.0;    // emitted - absorbed - escaped - unshot (both parts): the loss
  double emitted = 0.0;
  // The emission not yet shot (Environment::EmissionLeft), channels summed.
  double emission = 0.0;
  double radiosity = 0.0;  // sum of b * area, channels summed
  double kdArea = 0.0;     // sum of kd * area, channels averaged (constant)
  double area = 0.0;       // (constant)
  uint64_t work = 0;       // work so far (Environment::workSteps)
  uint64_t steps = 0;      // grid steps so far (EnvStats::gridSteps)
  uint64_t shots = 0;      // local and foreign
  uint64_t foreignShots = 0;
  // The pacer's work, and the shots' part of it beside their rays
  // (Environment::paceWork, shotWork).
  uint64_t paceWork = 0;
  uint64_t shotWork = 0;
  uint64_t rays = 0;  // form-factor rays traced
  uint64_t forwardsCreated = 0;
  // Queued shooters and outbox packets: a bound on the shots whose rays
  // are still on their way (Method R, SolveOptions::routed).
  uint64_t held = 0;
  // Local patches with unshot power (0 or 1: any), queued shooters and
  // packets in the outbox.
  uint64_t shootable = 0;
  void Add(const EnvSums& other);  // field by field
};

// What every environment reports between rounds, gathered from all ranks and
// summed in environment order, so every rank takes the same decisions
// whatever the grouping.
struct EnvReport : EnvSums {
  double elapsed;       // seconds since the solve began, on this rank's clock
  double waited;        // this rank's SolveResult::waitSeconds so far (first entry of a rank)
  double roundCpu;      // CPU seconds of this rank's shots in the last round (first entry)
  uint64_t interrupt;   // a signal this rank caught, to end at this round (first entry; 0: none)
  double envCpu;        // CPU seconds of this environment's shots in the last round
  uint64_t roundSteps;  // grid steps of this environment's shots in the last round
  uint64_t roundWork;   // their work (Environment::workSteps), what rounds are sized by
};

struct RoundTotals : EnvSums {
  double elapsed = 0.0;      // rank 0's clock
  double waitedMax = 0.0;    // the most any rank has waited
  double roundCpuMax = 0.0;  // the most CPU any rank used for the last round's shots
  double roundCpuSum = 0.0;  // the CPU all ranks used for them together
  // A signal some rank caught (SIGINT, SIGTERM or SIGHUP, the largest
  // number; 0: none) while checkpointing defers them (os::DeferInterrupts):
  // every rank learns it at the same round, writes a checkpoint and ends.
  uint64_t interrupt = 0;
  double envCpuMax = 0.0;     // the most CPU any environment used for them
  uint64_t envStepsMax = 0;   // the most grid steps any environment did in the last round
  uint64_t rankStepsMax = 0;  // the most any rank's environments did in it, together
  uint64_t envWorkMax = 0;    // the same two in work (Environment::workSteps)
  uint64_t rankWorkMax = 0;
  uint64_t maxOutstanding = 0;  // the most foreign shooters any env may still receive
};

// A rank's exchange buffers, carved from its arena at init: one send and one
// receive block per rank, each large enough for a rank's reports and every
// packet its environments can send another rank in a round
// (`packetsPerEnvRound` per environment), and the gathered reports.
struct ExchangeBuffers {
  // packetsPerEnvRound: the most packets an environment sends another
  // rank's environments in a round; outboxPackets: the most one's outbox
  // holds (delivered in this rank).
  void Layout(Arena& arena, const RankEnvs& envs, int ranks, uint32_t packetBytes,
              uint32_t packetsPerEnvRound, uint32_t outboxPackets);
  Span<uint8_t> sendBytes;  // ranks blocks of `blockBytes`
  Span<uint8_t> recvBytes;
  Span<Span<const uint8_t>> send;
  Span<Span<uint8_t>> recv;
  Span<size_t> received;
  size_t reportBytes = 0;   // a rank's reports (perRank entries), at the start of each block
  Span<EnvReport> mine;     // perRank entries
  Span<EnvReport> all;      // ranks * perRank entries
  Span<double> envCpu;      // perRank: the solver's CPU seconds of each environment's round
  Span<uint64_t> envSteps;  // perRank: the grid steps of each environment's round
  Span<uint64_t> envWork;   // perRank: the work of each environment's round
  // Delivery: the round's packets for this rank's environments, bucketed by
  // receiver in one pass (each bucket in sender and send order).
  Span<const uint8_t*> arrived;  // every packet this rank can get in a round
  Span<uint32_t> bucket;         // perRank + 1 starts into `arrived`
  size_t blockBytes = 0;
  uint32_t packetBytes = 0;
};

// Gathers every environment's report (those of `envs` from this rank) and
// sums them in environment order; the seconds spent in the collective are
// added to *waited. The solve's first totals, before any round.
RoundTotals GatherTotals(Span<Environment* const> envs, const RankEnvs& rankEnvs, Transport* t,
                         ExchangeBuffers* x, double elapsed, double roundCpu, double* waited);

// The exchange at the end of a round, in one collective: every rank sends
// every other rank its environments' reports and the packets for that
// rank's environments (one AllToAll), then delivers the packets it got (for
// each receiver, senders in environment order and packets in send order)
// and sums the reports in environment order. A report is made before its
// packets are delivered: the outbox's packets count as in flight with the
// receiver's share their sender worked out (Environment::FlightPower) and
// as queued shooters, so the totals are those after the delivery, up to the
// rounding of the sums (and `shootable` is 0 exactly when it would be 0
// after it). The collective's seconds are added to *waited.
RoundTotals ExchangeRound(Span<Environment* const> envs, const RankEnvs& rankEnvs, Transport* t,
                          ExchangeBuffers* x, double elapsed, double roundCpu, double* waited);

}  // namespace vismask
