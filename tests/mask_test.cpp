// Visibility masks, packets and the exchange's admission rule.
#include <cmath>
#include <random>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "vismask/mask.h"
#include "vismask/packet.h"
#include "vismask/rng.h"
#include "vismask/sampling.h"
#include "vismask/solver.h"

namespace vismask {
namespace {

TEST(MaskTest, PixelCentresMapBackToTheirPixel) {
  for (uint32_t res : {1u, 2u, 7u, 50u, 250u}) {
    for (uint32_t p = 0; p < 4 * res * res; p += 1 + res / 3) {
      glm::vec3 d = MaskPixelCentre(p, res);
      ASSERT_NEAR(glm::length(d), 1.0f, 1e-5f);
      ASSERT_EQ(MaskPixel(d, res), p) << "res " << res;
    }
  }
}

TEST(MaskTest, RowsRunFromTheNormalAndColumnsFromTheTangent) {
  EXPECT_EQ(MaskPixel(glm::vec3(0, 0, 1), 10), 0u);
  EXPECT_EQ(MaskPixel(glm::normalize(glm::vec3(1, 0.001f, 0.001f)), 10) / 40, 9u);  // horizon row
  EXPECT_EQ(MaskPixel(glm::normalize(glm::vec3(-1, 0.001f, 0.2f)), 10) % 40, 19u);  // phi ~ pi
}

TEST(MaskTest, OpenFractionIsCosineWeighted) {
  const uint32_t res = 20;
  std::vector<uint64_t> words(MaskShape{res}.words());
  MaskBits m(Span<uint64_t>(words.data(), words.size()), res);
  m.SetAllOpen();
  EXPECT_NEAR(m.OpenFraction(), 1.0, 1e-12);
  EXPECT_EQ(m.CountOpen(), 4 * res * res);
  // Close every pixel hit by a sample of a closed half (phi in [0, pi)):
  // the open share must be the fraction of cosine-distributed rays that
  // still land on open pixels.
  for (uint32_t p = 0; p < 4 * res * res; ++p)
    if ((p % (4 * res)) < 2 * res) m.Close(p);
  EXPECT_NEAR(m.OpenFraction(), 0.5, 1e-12);
  // Close the first theta row: its cosine-weighted share is sin^2(pi/40).
  for (uint32_t p = 0; p < 4 * res; ++p) m.Close(p);
  double s = std::sin(3.14159265358979 / 40);
  EXPECT_NEAR(m.OpenFraction(), 0.5 - 0.5 * s * s, 1e-12);
  Rng rng(1, 2);
  int open = 0, n = 400000;
  for (int i = 0; i < n; ++i) open += m.IsOpen(MaskPixel(CosineDirection(rng.NextFloat(), rng.NextFloat()), res));
  EXPECT_NEAR(static_cast<double>(open) / n, m.OpenFraction(), 0.004);
}

TEST(MaskTest, PackUnpackAndAnd) {
  const uint32_t res = 13;  // 676 pixels: not a multiple of 8 or 64
  MaskShape shape{res};
  EXPECT_EQ(shape.bytes(), 85u);
  std::vector<uint64_t> wa(shape.words()), wb(shape.words());
  MaskBits a(Span<uint64_t>(wa.data(), wa.size()), res), b(Span<uint64_t>(wb.data(), wb.size()), res);
  a.SetAllOpen();
  std::mt19937 rng(5);
  for (int i = 0; i < 300; ++i) a.Close(rng() % shape.pixels());
  std::vector<uint8_t> bytes(shape.bytes());
  a.Pack(bytes.data());
  b.Unpack(bytes.data());
  for (uint32_t p = 0; p < shape.pixels(); ++p) ASSERT_EQ(a.IsOpen(p), b.IsOpen(p)) << p;
  EXPECT_EQ(a.CountOpen(), b.CountOpen());
  b.SetAllOpen();
  b.Close(3);
  b.And(a);
  EXPECT_FALSE(b.IsOpen(3));
  EXPECT_EQ(b.CountOpen(), a.CountOpen() - (a.IsOpen(3) ? 1 : 0));
}

TEST(PacketTest, SizeIsFixedByTheMaskResolution) {
  EXPECT_EQ(PacketBytes(MaskShape{0}), sizeof(PacketHeader));
  EXPECT_EQ(MaskShape{50}.bytes(), 1250u);  // ceil(4*50^2/8)
  EXPECT_EQ(PacketBytes(MaskShape{50}), sizeof(PacketHeader) + 1256);  // padded to 8
  EXPECT_EQ(PacketBytes(MaskShape{13}), sizeof(PacketHeader) + 88);   // 85 padded to 8
  PacketHeader h{};
  h.shotKey = 0x0123456789abcdefull;
  h.power[1] = 2.5;
  h.corner[3][2] = -7.0f;
  h.shooterId = 42;
  std::vector<uint8_t> buf(PacketBytes(MaskShape{13}));
  WriteHeader(buf.data(), h);
  PacketHeader g = ReadHeader(buf.data());
  EXPECT_EQ(g.shotKey, h.shotKey);
  EXPECT_EQ(g.power[1], 2.5);
  EXPECT_EQ(g.corner[3][2], -7.0f);
  EXPECT_EQ(g.shooterId, 42u);
}

TEST(SolverTest, AdmissionNeverOverfillsAQueue) {
  // Simulate: envs create what they are admitted; each env drains at most
  // one record a round. No env may ever have more than `capacity` records
  // still to receive.
  const uint32_t n = 5;
  const uint64_t capacity = 7;
  std::vector<uint64_t> created(n, 0), processed(n, 0);
  std::mt19937 rng(3);
  for (uint64_t round = 0; round < 500; ++round) {
    uint64_t total = 0;
    for (uint64_t c : created) total += c;
    uint64_t maxOut = 0;
    for (uint32_t e = 0; e < n; ++e) maxOut = std::max(maxOut, total - created[e] - processed[e]);
    ASSERT_LE(maxOut, capacity);
    uint64_t admitted = 0;
    for (uint32_t e = 0; e < n; ++e) {
      uint32_t a = AdmittedRecords(round, e, n, capacity, maxOut);
      admitted += a;
      created[e] += rng() % (a + 1);
    }
    EXPECT_EQ(admitted, capacity - maxOut);
    total = 0;
    for (uint64_t c : created) total += c;
    for (uint32_t e = 0; e < n; ++e)
      if (total - created[e] > processed[e] && rng() % 3) ++processed[e];
  }
}

TEST(SolverTest, ShotBudgetHonoursMaxShots) {
  EXPECT_EQ(ShotBudget(3, 5, 0, 0), 5u);
  uint64_t sum = 0;
  for (uint32_t e = 0; e < 4; ++e) sum += ShotBudget(e, 5, 93, 100);
  EXPECT_EQ(sum, 7u);
  EXPECT_EQ(ShotBudget(0, 5, 93, 100), 5u);
  EXPECT_EQ(ShotBudget(1, 5, 93, 100), 2u);
  EXPECT_EQ(ShotBudget(2, 5, 93, 100), 0u);
}

}  // namespace
}  // namespace vismask
