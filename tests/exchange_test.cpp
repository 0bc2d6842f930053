// The exchange between rounds (exchange.h): one collective a round carries
// the packets and the reports, and the reports, made before delivery, give
// the totals a gather after the delivery would.
#include "vismask/solve/exchange.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "env_test_util.h"
#include "test_util.h"
#include "vismask/parallel/transport.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/packet.h"
#include "vismask/solve/partition.h"
#include "vismask/solve/solver.h"

namespace vismask {
namespace {

// The Cornell box in 2x1x2 environments, as init makes them (one process).
void MakeEnvs(MaskMethod method, uint32_t queue, test::TestEnvs* out) {
  EnvGrid grid;
  grid.n[0] = 2;
  grid.n[2] = 2;
  EnvOptions eo;
  eo.rays = 256;
  eo.maskMethod = method;
  eo.maskRes = 12;
  eo.queueCapacity = queue;
  eo.roundShots = 8;  // the outbox holds 6 packets a shot of a round
  test::MakeTestEnvs("scenes/cornell.obj", grid, 90.0f, eo, out);
}

void ExpectNearRel(double a, double b, const char* what, int round) {
  EXPECT_NEAR(a, b, 1e-12 * std::fmax(std::fabs(a), std::fabs(b))) << what << " in round " << round;
}

// Rounds driven by hand, as Solve drives them: after each, the totals
// ExchangeRound returns (reports made before the delivery, the outbox's
// packets counted in flight with the share their sender worked out for the
// receiver) against a gather of the same environments just after it.
TEST(ExchangeTest, RoundTotalsAreThoseAfterDelivery) {
  for (MaskMethod method :
       {MaskMethod::kNone, MaskMethod::kA, MaskMethod::kB, MaskMethod::kC, MaskMethod::kR}) {
    SCOPED_TRACE(MaskMethodName(method));
    const uint32_t queue = 64;
    test::TestEnvs envs;
    MakeEnvs(method, queue, &envs);
    if (HasFatalFailure()) return;
    Status error;
    std::unique_ptr<Transport> loop = MakeTransport(TransportRequest{"loop", 1}, &error);
    ASSERT_TRUE(loop) << error.ToString();
    RankEnvs rankEnvs = EnvsOfRank(4, 1, 0);
    Arena arena(1 << 20);
    ExchangeBuffers x;
    x.Layout(arena, rankEnvs, 1, envs.ptrs[0]->packetBytes(), 6 * 8, 6 * 8);
    Span<Environment* const> span = envs.span();
    double waited = 0.0;
    RoundTotals totals = GatherTotals(span, rankEnvs, loop.get(), &x, 0.0, 0.0, &waited);
    double mostFlight = 0.0;
    uint64_t sent = 0, shares = 0;
    for (int round = 0; round < 12; ++round) {
      for (uint32_t i = 0; i < 4; ++i)
        envs.ptrs[i]->RunRound(8, AdmittedForwards(round, i, 4, queue, totals.maxOutstanding), 0);
      for (Environment* e : envs.ptrs) {
        const Outbox& outbox = e->exchange().outbox();
        sent += outbox.count();
        // The share the sender put in each packet is the receiver's own.
        for (uint32_t k = 0; k < outbox.count(); ++k) {
          const uint8_t* packet = outbox.Packet(k);
          PacketHeader h = ReadHeader(packet);
          float own = method == MaskMethod::kR
                          ? 0.0f
                          : static_cast<float>(envs.ptrs[h.toEnv]->FlightShareAt(packet));
          EXPECT_EQ(test::Bits(h.flightShare), test::Bits(own))
              << "packet " << k << " from " << h.fromEnv << " to " << h.toEnv;
          shares += h.flightShare > 0.0f;
        }
      }
      RoundTotals before = ExchangeRound(span, rankEnvs, loop.get(), &x, 0.0, 0.0, &waited);
      RoundTotals after = GatherTotals(span, rankEnvs, loop.get(), &x, 0.0, 0.0, &waited);
      ExpectNearRel(before.flight, after.flight, "power in flight", round);
      ExpectNearRel(before.unshot, after.unshot, "unshot power", round);
      ExpectNearRel(before.lost, after.lost, "lost power", round);
      EXPECT_EQ(before.shootable == 0, after.shootable == 0) << "round " << round;
      EXPECT_GE(before.shootable, after.shootable) << "round " << round;
      EXPECT_EQ(before.shots, after.shots);
      EXPECT_EQ(before.maxOutstanding, after.maxOutstanding);
      EXPECT_EQ(before.emitted, after.emitted);
      EXPECT_EQ(before.radiosity, after.radiosity);
      mostFlight = std::fmax(mostFlight, after.flight);
      totals = before;
    }
    EXPECT_GT(sent, 0u) << "no packet crossed: the test tests nothing";
    EXPECT_GT(mostFlight, 0.0) << "no power was ever in flight";
    if (method != MaskMethod::kR) {
      EXPECT_GT(shares, 0u) << "no packet had a share in flight";
    }
    loop->Finish(0);
  }
}

}  // namespace
}  // namespace vismask
