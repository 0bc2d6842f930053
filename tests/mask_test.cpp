// Visibility masks and packets (the admission rule and shot budget: solver_test.cpp).
#include "vismask/solve/mask.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>
#include <random>
#include <vector>

#include "vismask/scene/mesh.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/packet.h"
#include "vismask/solve/rng.h"
#include "vismask/solve/sampling.h"

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

// PopCount counts bits as a loop over them does: empty, full, single and
// random words (with the builtin where the target has an instruction).
TEST(MaskTest, PopCountCountsEveryBit) {
  auto slow = [](uint64_t w) {
    uint32_t n = 0;
    for (int b = 0; b < 64; ++b) n += (w >> b) & 1;
    return n;
  };
  EXPECT_EQ(PopCount(0), 0u);
  EXPECT_EQ(PopCount(~uint64_t{0}), 64u);
  for (int b = 0; b < 64; ++b) {
    ASSERT_EQ(PopCount(uint64_t{1} << b), 1u) << b;
    ASSERT_EQ(PopCount(~(uint64_t{1} << b)), 63u) << b;
  }
  std::mt19937_64 rng(17);
  for (int i = 0; i < 100000; ++i) {
    uint64_t w = rng() & rng();  // sparser words too
    if (i % 2) w = rng();
    ASSERT_EQ(PopCount(w), slow(w)) << w;
  }
}

TEST(MaskTest, CountOpenOverARangeCountsItsBits) {
  const uint32_t res = 7;  // 196 pixels: rows of 28 bits straddle words
  std::vector<uint64_t> words(MaskShape{res}.words());
  MaskBits m(Span<uint64_t>(words.data(), words.size()), res);
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    m.SetAllClosed();
    for (uint32_t p = 0; p < m.bits(); ++p)
      if (rng() % 3 == 0) m.Open(p);
    for (uint32_t begin = 0; begin <= m.bits(); begin += 1 + rng() % 9)
      for (uint32_t end = begin; end <= m.bits(); end += 1 + rng() % 23) {
        uint32_t want = 0;
        for (uint32_t p = begin; p < end; ++p) want += m.IsOpen(p);
        ASSERT_EQ(m.CountOpen(begin, end), want) << begin << ".." << end;
      }
  }
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
  for (int i = 0; i < n; ++i)
    open += m.IsOpen(MaskPixel(CosineDirection(rng.NextFloat(), rng.NextFloat()), res));
  EXPECT_NEAR(static_cast<double>(open) / n, m.OpenFraction(), 0.004);
}

TEST(MaskTest, PackUnpackAndAnd) {
  const uint32_t res = 13;  // 676 pixels: not a multiple of 8 or 64
  MaskShape shape{res};
  EXPECT_EQ(shape.bytes(), 85u);
  std::vector<uint64_t> wa(shape.words()), wb(shape.words());
  MaskBits a(Span<uint64_t>(wa.data(), wa.size()), res),
      b(Span<uint64_t>(wb.data(), wb.size()), res);
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
  EXPECT_EQ(MaskShape{50}.bytes(), 1250u);                             // ceil(4*50^2/8)
  EXPECT_EQ(PacketBytes(MaskShape{50}), sizeof(PacketHeader) + 1256);  // padded to 8
  EXPECT_EQ(PacketBytes(MaskShape{13}), sizeof(PacketHeader) + 88);    // 85 padded to 8
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

TEST(PacketTest, MethodRCarriesOneBitPerRay) {
  // N rays: ceil(N / 8) bytes padded to 8, whatever --mask-res says.
  EXPECT_EQ(MaskShapeOf(MaskMethod::kR, 250, 1000).bytes(), 125u);
  EXPECT_EQ(PacketBytes(MaskShapeOf(MaskMethod::kR, 250, 1000)), sizeof(PacketHeader) + 128);
  EXPECT_EQ(PacketBytes(MaskShapeOf(MaskMethod::kR, 50, 8192)), sizeof(PacketHeader) + 1024);
  EXPECT_EQ(PacketBytes(MaskShapeOf(MaskMethod::kC, 50, 8192)), PacketBytes(MaskShape{50}));
  EXPECT_EQ(PacketBytes(MaskShapeOf(MaskMethod::kNone, 50, 8192)), sizeof(PacketHeader));
  // 100 bits: not a multiple of 8 or 64; the open share is the share of rays.
  MaskShape shape = MaskShapeOf(MaskMethod::kR, 7, 100);
  std::vector<uint64_t> wa(shape.words()), wb(shape.words());
  MaskBits a = MaskBits::PerRay(Span<uint64_t>(wa.data(), wa.size()), 100);
  MaskBits b = MaskBits::PerRay(Span<uint64_t>(wb.data(), wb.size()), 100);
  a.SetAllOpen();
  EXPECT_EQ(a.CountOpen(), 100u);
  EXPECT_DOUBLE_EQ(a.OpenFraction(), 1.0);
  for (uint32_t r = 0; r < 100; r += 3) a.Close(r);
  EXPECT_EQ(a.CountOpen(), 66u);
  EXPECT_DOUBLE_EQ(a.OpenFraction(), 0.66);
  std::vector<uint8_t> bytes(shape.bytes());
  a.Pack(bytes.data());
  b.Unpack(bytes.data());
  for (uint32_t r = 0; r < 100; ++r) ASSERT_EQ(a.IsOpen(r), r % 3 != 0) << r;
  for (uint32_t r = 0; r < 100; ++r) ASSERT_EQ(b.IsOpen(r), a.IsOpen(r)) << r;
  b.SetAllClosed();
  b.Open(5);
  EXPECT_EQ(b.CountOpen(), 1u);
}

// Method R needs every environment to regenerate the source's rays bit for
// bit from the packet: the header's patch must give the same sampler, and
// the shot's stream the same floats.
TEST(PacketTest, ForeignEnvironmentsRegenerateTheSourcesRaysExactly) {
  Scene scene;
  ASSERT_TRUE(LoadScene("scenes/cornell.obj", &scene).ok());
  std::vector<uint32_t> all(scene.polygons.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  Mesh mesh;
  ASSERT_TRUE(MeshScene(scene, all, 45.0f, 1u << 20, &mesh).ok());
  ASSERT_GT(mesh.patches.size(), 100u);
  bool sawTriangle = false;
  for (Patch p : mesh.patches) {
    sawTriangle |= p.numCorners == 3;
    p.openCells = static_cast<uint16_t>(0x0f0f ^ p.globalId);  // any bits travel
    double power[3] = {1.0, 2.0, 3.0};
    uint64_t key = ShotKey(17, p.globalId, 3);
    uint8_t packet[sizeof(PacketHeader)];
    WriteHeader(packet, ShotHeader(p, power, key, 3, 1, 4096));
    PacketHeader h = ReadHeader(packet);
    Patch q = PatchFromHeader(h);
    EXPECT_EQ(h.shotKey, key);
    EXPECT_EQ(q.globalId, p.globalId);
    EXPECT_EQ(q.openCells, p.openCells);
    PatchSampler a = MakePatchSampler(p), b = MakePatchSampler(q);
    ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "patch " << p.globalId;
    Rng ra = ShotRng(key), rb = ShotRng(h.shotKey);
    for (int r = 0; r < 64; ++r) {
      float u[5], v[5];
      for (int k = 0; k < 5; ++k) {
        u[k] = ra.NextFloat();
        v[k] = rb.NextFloat();
      }
      glm::vec3 oa = a.Point(u[0], u[1], u[2]), ob = b.Point(v[0], v[1], v[2]);
      glm::vec3 da = a.frame.ToWorld(CosineDirection(u[3], u[4]));
      glm::vec3 db = b.frame.ToWorld(CosineDirection(v[3], v[4]));
      ASSERT_EQ(std::memcmp(&oa, &ob, sizeof oa), 0);
      ASSERT_EQ(std::memcmp(&da, &db, sizeof da), 0);
    }
  }
  EXPECT_TRUE(sawTriangle) << "the Cornell box's blocks mesh into quads only?";
}

// Methods B and C take their centre rays from the tables (issue 19: the
// per-pixel sin/cos were a fifth of a Method B run): the same floats, bit
// for bit, as MaskPixelCentre, so images do not change.
TEST(MaskTest, DirectionTablesGiveTheCentresBitForBit) {
  for (uint32_t res : {1u, 3u, 20u, 100u, 257u}) {
    Arena measure = Arena::Measure();
    MaskDirections d;
    d.Layout(measure, res);
    Arena arena(measure.used());
    d.Layout(arena, res);
    d.Fill();
    for (uint32_t p = 0; p < 4 * res * res; ++p) {
      glm::vec3 a = d.Centre(p), b = MaskPixelCentre(p, res);
      ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "res " << res << " pixel " << p;
    }
  }
}

// MaskPixel takes its angles from FastAcos and FastAtan2 and falls back on
// libm near a row or column edge: the pixel must be libm's everywhere,
// including directions on and beside the edges and the axes.
TEST(MaskTest, PixelIsLibmsPixel) {
  auto reference = [](const glm::vec3& d, uint32_t res) {
    constexpr double kHalf = 1.5707963267948966, kTwo = 6.283185307179586;
    float z = d.z < 0.0f ? 0.0f : (d.z > 1.0f ? 1.0f : d.z);
    double theta = std::acos(static_cast<double>(z));
    double phi = std::atan2(static_cast<double>(d.y), static_cast<double>(d.x));
    if (phi < 0.0) phi += kTwo;
    uint32_t row = std::min(static_cast<uint32_t>(theta / kHalf * res), res - 1);
    uint32_t col = std::min(static_cast<uint32_t>(phi / kTwo * (4 * res)), 4 * res - 1);
    return row * 4 * res + col;
  };
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  uint64_t checked = 0;
  for (uint32_t res : {1u, 7u, 100u, 250u, 4096u}) {
    std::vector<glm::vec3> dirs;
    for (int k = 0; k < 20000; ++k) {
      glm::vec3 d(unit(rng), unit(rng), std::fabs(unit(rng)));
      if (glm::length(d) > 0.0f) dirs.push_back(glm::normalize(d));
    }
    // On and beside the row and column edges, and along the axes.
    for (uint32_t e = 0; e <= 4 * res && e < 2000; ++e) {
      double a = e * 1.5707963267948966 / res, b = e * 6.283185307179586 / (4 * res);
      for (float s : {-1.0f, 0.0f, 1.0f}) {
        float th = std::nextafter(static_cast<float>(a), s * 10.0f);
        float ph = std::nextafter(static_cast<float>(b), s * 10.0f);
        dirs.push_back(glm::vec3(std::sin(th), 0.0f, std::cos(th)));
        dirs.push_back(glm::vec3(0.6f * std::cos(ph), 0.6f * std::sin(ph), 0.8f));
        dirs.push_back(glm::vec3(std::cos(ph), std::sin(ph), 0.0f));
      }
    }
    for (const glm::vec3& d :
         {glm::vec3(0, 0, 1), glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0), glm::vec3(0, -1, 0),
          glm::vec3(1, -0.0f, 0), glm::vec3(-1, -0.0f, 0)})
      dirs.push_back(d);
    for (const glm::vec3& d : dirs) {
      ASSERT_EQ(MaskPixel(d, res), reference(d, res))
          << "res " << res << " d " << d.x << " " << d.y << " " << d.z;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100000u);
}

}  // namespace
}  // namespace vismask
