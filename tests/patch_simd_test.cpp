// OutsideEdges (SSE2 on x86-64, NEON on aarch64) against the portable
// scalar form: the same answer for every input, so the grid's hits, and so
// every output byte, do not depend on which one the build uses.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "test_util.h"
#include "vismask/patch.h"

namespace vismask {
namespace {

using test::FloatFromBits;

// Values where a 4-wide form could part from the scalar one: signed zeros,
// subnormals, the largest and smallest normals, infinities, NaN, and
// numbers whose products round.
float Special(std::mt19937& rng) {
  static const float kValues[] = {0.0f,
                                  -0.0f,
                                  1.0f,
                                  -1.0f,
                                  FloatFromBits(1),  // the least subnormal
                                  -FloatFromBits(1),
                                  FloatFromBits(0x007fffff),  // the largest subnormal
                                  std::numeric_limits<float>::min(),
                                  std::numeric_limits<float>::max(),
                                  -std::numeric_limits<float>::max(),
                                  std::numeric_limits<float>::infinity(),
                                  -std::numeric_limits<float>::infinity(),
                                  std::numeric_limits<float>::quiet_NaN(),
                                  1.0f + std::numeric_limits<float>::epsilon(),
                                  0.1f,
                                  1e-20f,
                                  1e20f};
  return kValues[rng() % (sizeof kValues / sizeof kValues[0])];
}

TEST(PatchSimdTest, OutsideEdgesIsTheScalarTestOnEveryInput) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uni(-2.0f, 2.0f);
  std::uniform_int_distribution<uint32_t> bits;
  uint64_t outside = 0, inside = 0;
  for (int i = 0; i < 400000; ++i) {
    PatchGeom g{};
    glm::vec3 x;
    const int kind = i % 4;  // plain numbers, special values, random bits, a near tie
    auto value = [&]() {
      if (kind == 1 && rng() % 3 == 0) return Special(rng);
      if (kind == 2) return FloatFromBits(bits(rng));
      return uni(rng);
    };
    for (int e = 0; e < 4; ++e) {
      g.ex[e] = value();
      g.ey[e] = value();
      g.ez[e] = value();
      g.ew[e] = value();
    }
    x = glm::vec3(value(), value(), value());
    if (kind == 3) {
      // The offset at the scalar sum itself, or an ulp either side: where
      // the two forms part if one rounded a sum differently.
      const int e = static_cast<int>(rng() % 4);
      const float s = g.ex[e] * x.x + g.ey[e] * x.y + g.ez[e] * x.z;
      const int step = static_cast<int>(rng() % 3) - 1;
      g.ew[e] = step == 0 ? s : std::nextafter(s, step > 0 ? HUGE_VALF : -HUGE_VALF);
    }
    const bool scalar = OutsideEdgesScalar(g, x);
    ASSERT_EQ(OutsideEdges(g, x), scalar) << "case " << i;
    ++(scalar ? outside : inside);
  }
  // Both answers are exercised.
  EXPECT_GT(outside, 10000u);
  EXPECT_GT(inside, 10000u);
}

// A quad's own edge planes: its centre is inside, a point past an edge is
// outside, and a triangle's missing fourth edge never fails.
TEST(PatchSimdTest, OutsideEdgesOfAPatch) {
  Patch p{};
  p.corner[0] = glm::vec3(0, 0, 0);
  p.corner[1] = glm::vec3(2, 0, 0);
  p.corner[2] = glm::vec3(2, 1, 0);
  p.corner[3] = glm::vec3(0, 1, 0);
  p.normal = glm::vec3(0, 0, 1);
  p.numCorners = 4;
  PatchGeom g = MakePatchGeom(p);
  EXPECT_FALSE(OutsideEdges(g, glm::vec3(1.0f, 0.5f, 0.0f)));
  EXPECT_TRUE(OutsideEdges(g, glm::vec3(2.5f, 0.5f, 0.0f)));
  EXPECT_TRUE(OutsideEdges(g, glm::vec3(1.0f, -0.5f, 0.0f)));
  p.corner[3] = p.corner[2];
  p.numCorners = 3;
  g = MakePatchGeom(p);
  EXPECT_TRUE(std::isinf(g.ew[3]) && g.ew[3] < 0.0f);
  EXPECT_FALSE(OutsideEdges(g, glm::vec3(1.5f, 0.25f, 0.0f)));
  EXPECT_TRUE(OutsideEdges(g, glm::vec3(0.5f, 0.75f, 0.0f)));  // past the hypotenuse
}

}  // namespace
}  // namespace vismask
