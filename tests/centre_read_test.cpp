// Method B's --centre-rays: a shot that decides only the pixels its rays
// read downstream (read) lands, in every environment downstream, the light
// that deciding every open pixel (all) lands, bit for bit; and auto's
// choice between them is the source's, which every environment follows.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <utility>
#include <vector>

#include "env_test_util.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/packet.h"
#include "vismask/solve/partition.h"

namespace vismask {
namespace {

// rayQuantum > 0: power allocation (EnvOptions), up to `rays` a shot.
void MakeEnvs(const EnvGrid& grid, CentreChoice choice, uint32_t rays, double rayQuantum,
              test::TestEnvs* out) {
  EnvOptions eo;
  eo.rays = rays;
  eo.rayQuantum = rayQuantum;
  eo.maskMethod = MaskMethod::kB;
  eo.maskRes = 30;
  eo.centreRays = choice;
  eo.roundShots = 1;
  test::MakeTestEnvs("scenes/cornell.obj", grid, 60.0f, eo, out);
}

struct Shots {
  std::vector<std::vector<PatchEnergy>> landed;  // per foreign shot, its environment's energy
  std::vector<uint32_t> open;                    // per packet, its mask's open pixels
  uint64_t centreRays = 0;
  uint32_t readShots = 0;  // packets flagged kReadsOnly
};

// Environment `source`'s first `shots` shots, each followed down every
// other environment, nearest first (upstream comes before downstream):
// each is reset to its emission, gets the shot's packets from upstream and
// makes the one foreign shot, with no local shot allowed.
Shots Follow(const EnvGrid& grid, int source, CentreChoice choice, int shots, uint32_t rays = 512,
             double rayQuantum = 0.0) {
  test::TestEnvs envs;
  MakeEnvs(grid, choice, rays, rayQuantum, &envs);
  const int count = grid.count();
  int from[3];
  grid.Cell(source, from);
  std::vector<std::pair<int, int>> order;  // (distance, environment)
  for (int i = 0; i < count; ++i) {
    int c[3];
    grid.Cell(i, c);
    const int d = std::abs(c[0] - from[0]) + std::abs(c[1] - from[1]) + std::abs(c[2] - from[2]);
    if (i != source) order.emplace_back(d, i);
  }
  std::sort(order.begin(), order.end());
  Shots out;
  for (int s = 0; s < shots; ++s) {
    std::vector<std::vector<uint8_t>> pending;
    auto take = [&](Environment* e) {
      const Outbox& outbox = e->exchange().outbox();
      for (uint32_t k = 0; k < outbox.count(); ++k) {
        const uint8_t* p = outbox.Packet(k);
        pending.emplace_back(p, p + e->packetBytes());
        const PacketHeader h = ReadHeader(p);
        out.readShots += (h.flags & kReadsOnly) != 0;
        uint32_t open = 0;
        for (uint32_t b = sizeof(PacketHeader); b < e->packetBytes(); ++b)
          open += static_cast<uint32_t>(__builtin_popcount(p[b]));
        out.open.push_back(open);
      }
      e->ClearOutbox();
    };
    envs.ptrs[static_cast<size_t>(source)]->RunRound(1, 1);
    EXPECT_EQ(envs.ptrs[static_cast<size_t>(source)]->stats().shots, static_cast<uint64_t>(s) + 1);
    take(envs.ptrs[static_cast<size_t>(source)]);
    for (const auto& [distance, i] : order) {
      Environment* e = envs.ptrs[static_cast<size_t>(i)];
      e->Reset();
      for (const std::vector<uint8_t>& p : pending)
        if (ReadHeader(p.data()).toEnv == static_cast<uint32_t>(i)) e->Deliver(p.data());
      e->RunRound(1, 0);
      EXPECT_EQ(e->stats().foreignShots, 1u) << "environment " << i;  // since Reset
      out.centreRays += e->stats().maskRays;
      out.landed.emplace_back(e->energy().begin(), e->energy().end());
      take(e);
    }
  }
  out.centreRays += envs.ptrs[static_cast<size_t>(source)]->stats().maskRays;
  return out;
}

bool SameEnergy(const std::vector<PatchEnergy>& a, const std::vector<PatchEnergy>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof a[0]) == 0;
}

// In a column of environments, the light in the top one (a foreign shooter
// passed on from the middle one), and in a 2x2 square, the light in all
// four (one receiving the AND of two upstream masks).
TEST(CentreReadTest, ReadShotsLandTheLightOfFullMasks) {
  EnvGrid column, square;
  column.n[1] = 3;
  square.n[0] = 2;
  square.n[2] = 2;
  for (const auto& [grid, source] : {std::pair(column, 2), std::pair(square, 0)}) {
    const int shots = 10;
    const Shots all = Follow(grid, source, CentreChoice::kAll, shots);
    const Shots read = Follow(grid, source, CentreChoice::kRead, shots);
    ASSERT_EQ(all.landed.size(), read.landed.size());
    ASSERT_EQ(all.landed.size(), static_cast<size_t>(shots * (grid.count() - 1)));
    int differ = 0;
    for (size_t k = 0; k < all.landed.size(); ++k)
      differ += !SameEnergy(all.landed[k], read.landed[k]);
    EXPECT_EQ(differ, 0) << "of " << all.landed.size() << " foreign shots, in " << grid.count()
                         << " environments";
    // What read leaves undecided stays open, and it casts far fewer rays.
    ASSERT_EQ(all.open.size(), read.open.size());
    uint64_t openAll = 0, openRead = 0;
    for (size_t k = 0; k < all.open.size(); ++k) {
      EXPECT_LE(all.open[k], read.open[k]) << "packet " << k;
      openAll += all.open[k];
      openRead += read.open[k];
    }
    EXPECT_GT(openRead, openAll);
    EXPECT_LT(read.centreRays * 2, all.centreRays);
    EXPECT_EQ(all.readShots, 0u);
    EXPECT_EQ(read.readShots, read.open.size());
  }
}

// auto: the source's choice, per shot, is in the packets' flags, and the
// environments downstream follow it: each foreign shot lands what the
// same shot lands under all, and the shots go both ways. With power
// allocation the light's shots carry the most rays (2 048, partial
// shots), which reading costs more for, and the walls' few.
TEST(CentreReadTest, AutoChoosesPerShotAndEveryEnvironmentFollows) {
  EnvGrid column;
  column.n[1] = 3;
  double emitted = 0.0;
  {
    test::TestEnvs envs;
    MakeEnvs(column, CentreChoice::kAll, 2048, 0.0, &envs);
    for (Environment* e : envs.ptrs)
      for (const PatchEnergy& p : e->energy()) emitted += UnshotKey(p);
  }
  ASSERT_GT(emitted, 0.0);
  const double quantum = emitted / 4000.0;
  const int shots = 30;
  const Shots all = Follow(column, 2, CentreChoice::kAll, shots, 2048, quantum);
  const Shots mixed = Follow(column, 2, CentreChoice::kAuto, shots, 2048, quantum);
  ASSERT_EQ(all.landed.size(), mixed.landed.size());
  int differ = 0;
  for (size_t k = 0; k < all.landed.size(); ++k)
    differ += !SameEnergy(all.landed[k], mixed.landed[k]);
  EXPECT_EQ(differ, 0);
  EXPECT_GT(mixed.readShots, 0u);
  EXPECT_LT(mixed.readShots, mixed.open.size());
}

}  // namespace
}  // namespace vismask
