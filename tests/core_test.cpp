// Unit tests of the building blocks: arena, checks, MaxTree, RNG, sampling.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "test_util.h"
#include "vismask/core/arena.h"
#include "vismask/core/check.h"
#include "vismask/core/fminmax.h"
#include "vismask/solve/max_tree.h"
#include "vismask/solve/patch.h"
#include "vismask/solve/rng.h"
#include "vismask/solve/sampling.h"
#include "vismask/solve/slot_index.h"

namespace vismask {
namespace {

using test::Bits;

// FMax and FMin: x when x > y (x < y), else y, so of two equal values (two
// zeros of either sign) the second; of a NaN and a number, the number. On
// x86-64 that is glibc's fmaxf and fminf, bit for bit, which the outputs
// had before.
TEST(FMinMaxTest, FollowTheRuleAndGlibcOnX86) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> v = {0.0f, -0.0f, 1.0f, -1.0f, 1e-30f, -1e-30f, 1e-45f, inf, -inf, nan, 3.5f};
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> any(-10.0f, 10.0f);
  for (int k = 0; k < 200; ++k) v.push_back(any(rng));
  // libm's own functions, through pointers the compiler cannot see
  // through: once it has proven neither operand a NaN (the isnan tests
  // below), GCC may fold std::fmax into a bare maxss whose order, and so
  // whose sign of two zeros, it picks itself (the SAN build did).
  [[maybe_unused]] float (*volatile libmMax)(float, float) = ::fmaxf;
  [[maybe_unused]] float (*volatile libmMin)(float, float) = ::fminf;
  int checked = 0;
  for (float x : v)
    for (float y : v) {
      const float mx = FMax(x, y), mn = FMin(x, y);
      const float wantMax = std::isnan(y) ? x : std::isnan(x) ? y : (x > y ? x : y);
      const float wantMin = std::isnan(y) ? x : std::isnan(x) ? y : (x < y ? x : y);
      ASSERT_EQ(Bits(mx), Bits(wantMax)) << x << " " << y;
      ASSERT_EQ(Bits(mn), Bits(wantMin)) << x << " " << y;
#if defined(__x86_64__)
      ASSERT_EQ(Bits(mx), Bits(libmMax(x, y))) << x << " " << y;
      ASSERT_EQ(Bits(mn), Bits(libmMin(x, y))) << x << " " << y;
#endif
      ++checked;
    }
  EXPECT_EQ(checked, static_cast<int>(v.size() * v.size()));
  // The order of two zeros decides the sign: the second.
  EXPECT_TRUE(std::signbit(FMax(0.0f, -0.0f)));
  EXPECT_FALSE(std::signbit(FMax(-0.0f, 0.0f)));
}

TEST(ArenaTest, MeasuredLayoutFitsExactly) {
  auto layout = [](Arena& a) {
    a.Alloc<char>(3);
    a.Alloc<double>(10);
    a.Alloc<glm::vec3>(7);
    a.AllocBytes(100, 64);
  };
  Arena measure = Arena::Measure();
  layout(measure);
  EXPECT_TRUE(measure.measuring());
  Arena real(measure.used());
  layout(real);
  EXPECT_EQ(real.used(), measure.used());
  EXPECT_LE(real.used(), real.capacity());
  EXPECT_LT(real.capacity() - real.used(), Arena::kAlign);
}

TEST(ArenaTest, AllocationsAreAlignedZeroedAndDisjoint) {
  Arena a(4096);
  Span<uint8_t> s1 = a.Alloc<uint8_t>(5);
  Span<double> s2 = a.Alloc<double>(4);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(s2.data()) % 16, 0u);
  EXPECT_GE(reinterpret_cast<uint8_t*>(s2.data()), s1.data() + 5);
  for (double d : s2) EXPECT_EQ(d, 0.0);
}

TEST(ArenaDeathTest, OverflowIsCaught) {
  EXPECT_DEATH(
      {
        Arena a(64);
        a.Alloc<char>(65);
      },
      "arena overflow");
}

// CHECK_EQ and the like print both operands (issue 18: a bare CHECK says
// only which comparison failed).
TEST(CheckDeathTest, ComparisonsPrintBothOperands) {
  EXPECT_DEATH(CHECK_EQ(2 + 2, 5), "CHECK\\(2 \\+ 2 == 5\\) failed: 4 against 5");
  EXPECT_DEATH(CHECK_LT(0.5, -1.25), "CHECK\\(0.5 < -1.25\\) failed: 0.5 against -1.25");
  size_t big = 7;
  EXPECT_DEATH(CHECK_LE(big, 3u), "failed: 7 against 3");
  CHECK_GE(big, 7u);  // holds: nothing happens
}

TEST(MaxTreeTest, AgreesWithLinearScan) {
  for (uint32_t n : {1u, 2u, 3u, 7u, 64u, 1000u}) {
    Arena measure = Arena::Measure();
    MaxTree probe;
    probe.Layout(measure, n);
    Arena arena(measure.used());
    MaxTree t;
    t.Layout(arena, n);
    t.Clear();
    std::vector<double> keys(n, 0.0);
    std::mt19937 rng(n);
    for (int step = 0; step < 5000; ++step) {
      uint32_t i = rng() % n;
      double k = (rng() % 4 == 0) ? 0.0 : static_cast<double>(rng() % 50);  // many ties
      if (step % 2 == 0 && k >= keys[i]) {
        t.Increase(i, k);
      } else {
        t.Set(i, k);
      }
      keys[i] = k;
      uint32_t best = 0;
      for (uint32_t j = 1; j < n; ++j)
        if (keys[j] > keys[best]) best = j;
      ASSERT_EQ(t.Top(), best) << "n=" << n << " step=" << step;
    }
  }
}

// With ties, equal keys go to the lower tie value, then the lower index:
// the foreign queue's order (largest key, then lower shooter id and shot).
TEST(MaxTreeTest, TiesGoToTheLowerTieValue) {
  const uint32_t n = 37;
  Arena measure = Arena::Measure();
  MaxTree probe;
  probe.Layout(measure, n, true);
  Arena arena(measure.used());
  MaxTree t;
  t.Layout(arena, n, true);
  const double none = -std::numeric_limits<double>::infinity();
  t.Clear(none);
  std::vector<double> keys(n, none);
  std::vector<uint64_t> ties(n, 0);
  std::mt19937 rng(5);
  for (int step = 0; step < 20000; ++step) {
    uint32_t i = rng() % n;
    int kind = static_cast<int>(rng() % 8);
    double k = kind == 0   ? none
               : kind == 1 ? std::numeric_limits<double>::infinity()
                           : static_cast<double>(rng() % 4);  // many ties
    uint64_t tie = rng() % 6;
    t.Set(i, k, tie);
    keys[i] = k;
    ties[i] = tie;
    uint32_t best = 0;
    for (uint32_t j = 1; j < n; ++j)
      if (keys[j] > keys[best] || (keys[j] == keys[best] && ties[j] < ties[best])) best = j;
    ASSERT_EQ(t.Top(), best) << "step=" << step;
  }
}

// SlotIndex against a map: Find, Take (the lowest free slot) and Release
// in random order, the table kept full to its capacity at times.
TEST(SlotIndexTest, AgreesWithAMap) {
  for (uint32_t slots : {1u, 5u, 64u, 576u}) {
    Arena measure = Arena::Measure();
    SlotIndex probe;
    probe.Layout(measure, slots);
    Arena arena(measure.used());
    SlotIndex index;
    index.Layout(arena, slots);
    index.Clear();
    std::map<std::pair<uint32_t, uint32_t>, int> held;
    std::vector<bool> taken(slots, false);
    std::mt19937 rng(slots);
    for (int step = 0; step < 30000; ++step) {
      // Few shooters and shots, so keys collide and probe runs form.
      uint32_t shooter = rng() % (2 * slots + 3), shot = rng() % 3;
      auto key = std::make_pair(shooter, shot);
      auto it = held.find(key);
      ASSERT_EQ(index.Find(shooter, shot), it == held.end() ? -1 : it->second) << step;
      if (it != held.end() && rng() % 2) {
        index.Release(it->second, shooter, shot);
        taken[it->second] = false;
        held.erase(it);
      } else if (it == held.end()) {
        int lowest = -1;
        for (uint32_t s = 0; s < slots && lowest < 0; ++s)
          if (!taken[s]) lowest = static_cast<int>(s);
        int s = index.Take(shooter, shot);
        ASSERT_EQ(s, lowest) << step;
        if (s >= 0) {
          taken[s] = true;
          held[key] = s;
        }
      }
    }
  }
}

TEST(RngTest, StreamsAreReproducibleAndDistinct) {
  Rng a = ShotRng(ShotKey(1, 5, 0)), b = ShotRng(ShotKey(1, 5, 0)), c = ShotRng(ShotKey(1, 5, 1));
  int same = 0;
  for (int i = 0; i < 100; ++i) {
    uint32_t x = a.NextU32();
    EXPECT_EQ(x, b.NextU32());
    same += x == c.NextU32();
  }
  EXPECT_LT(same, 3);
  double sum = 0.0;
  Rng d(42, 7);
  for (int i = 0; i < 100000; ++i) {
    float u = d.NextFloat();
    ASSERT_GE(u, 0.0f);
    ASSERT_LT(u, 1.0f);
    sum += u;
  }
  EXPECT_NEAR(sum / 100000, 0.5, 0.005);
}

Patch MakeQuad(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
  Patch p{};
  p.corner[0] = a, p.corner[1] = b, p.corner[2] = c, p.corner[3] = d;
  p.numCorners = 4;
  p.normal = glm::normalize(glm::cross(b - a, c - a));
  p.area = 0.5f * (glm::length(glm::cross(b - a, c - a)) + glm::length(glm::cross(c - a, d - a)));
  return p;
}

TEST(SamplingTest, PointsAreUniformOnATrapezoid) {
  // Trapezoid with bases 4 (y = 0) and 2 (y = 1): the area below y = 0.5 is
  // (4 + 3) / 2 * 0.5 = 1.75 of 3.
  Patch p = MakeQuad({0, 0, 0}, {4, 0, 0}, {3, 1, 0}, {1, 1, 0});
  PatchSampler s = MakePatchSampler(p);
  PatchGeom g = MakePatchGeom(p);
  Rng rng(3, 3);
  int below = 0, n = 200000;
  for (int i = 0; i < n; ++i) {
    glm::vec3 x = s.Point(rng.NextFloat(), rng.NextFloat(), rng.NextFloat());
    ASSERT_NEAR(x.z, 0.0f, 1e-6f);
    ASSERT_FALSE(OutsideEdges(g, x.x, x.y));
    below += x.y < 0.5f;
  }
  EXPECT_NEAR(static_cast<double>(below) / n, 1.75 / 3.0, 0.005);
}

TEST(SamplingTest, DirectionsAreCosineDistributed) {
  // E[cos theta] = 2/3 and E[cos^2 theta] = 1/2 under pdf cos(theta)/pi.
  Rng rng(9, 1);
  double m1 = 0, m2 = 0, mx = 0;
  int n = 200000;
  for (int i = 0; i < n; ++i) {
    glm::vec3 d = CosineDirection(rng.NextFloat(), rng.NextFloat());
    ASSERT_NEAR(glm::length(d), 1.0f, 1e-5f);
    ASSERT_GE(d.z, 0.0f);
    m1 += d.z;
    m2 += d.z * d.z;
    mx += d.x;
  }
  EXPECT_NEAR(m1 / n, 2.0 / 3.0, 0.003);
  EXPECT_NEAR(m2 / n, 0.5, 0.003);
  EXPECT_NEAR(mx / n, 0.0, 0.005);
}

TEST(PatchTest, SharedEdgeLeavesNoCrack) {
  // Two quads sharing the edge x = 1; rays aimed exactly at the edge hit one.
  Patch a = MakeQuad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
  Patch b = MakeQuad({1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0});
  PatchGeom ga = MakePatchGeom(a), gb = MakePatchGeom(b);
  for (int i = 0; i <= 100; ++i) {
    Ray ray{{1.0f, i / 100.0f, 1.0f}, {0.0f, 0.0f, -1.0f}, 0.0f, 10.0f};
    float t;
    bool front;
    bool hit = IntersectPatch(ga, ray, &t, &front) || IntersectPatch(gb, ray, &t, &front);
    EXPECT_TRUE(hit) << i;
  }
}

}  // namespace
}  // namespace vismask
