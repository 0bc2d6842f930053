// OutsideEdges (SSE2 on x86-64, NEON on aarch64) against the portable
// scalar form: the same answer for every input, so the grid's hits, and so
// every output byte, do not depend on which one the build uses.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <limits>
#include <random>
#include <utility>

#include "test_util.h"
#include "vismask/solve/patch.h"

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
    const int kind = i % 4;  // plain numbers, special values, random bits, a near tie
    auto value = [&]() {
      if (kind == 1 && rng() % 3 == 0) return Special(rng);
      if (kind == 2) return FloatFromBits(bits(rng));
      return uni(rng);
    };
    for (int m = 0; m < 4; ++m) {
      g.u[m] = value();
      g.v[m] = value();
    }
    float x = value(), y = value();
    if (kind == 3) {
      // The point at a corner, or an ulp either side of it on each axis:
      // where the edge function is 0 or about to change sign, and the two
      // forms part if one rounded a difference or product differently.
      const int m = static_cast<int>(rng() % 4);
      const int sx = static_cast<int>(rng() % 3) - 1, sy = static_cast<int>(rng() % 3) - 1;
      x = sx == 0 ? g.u[m] : std::nextafter(g.u[m], sx > 0 ? HUGE_VALF : -HUGE_VALF);
      y = sy == 0 ? g.v[m] : std::nextafter(g.v[m], sy > 0 ? HUGE_VALF : -HUGE_VALF);
    }
    const bool scalar = OutsideEdgesScalar(g, x, y);
    ASSERT_EQ(OutsideEdges(g, x, y), scalar) << "case " << i;
    ++(scalar ? outside : inside);
  }
  // Both answers are exercised.
  EXPECT_GT(outside, 10000u);
  EXPECT_GT(inside, 10000u);
}

// A quad's own edges: its centre is inside, a point past an edge is
// outside, and a triangle's repeated corner (an edge of length 0) never
// fails. The normal along -z stores the corners in the other order.
TEST(PatchSimdTest, OutsideEdgesOfAPatch) {
  Patch p{};
  p.corner[0] = glm::vec3(0, 0, 0);
  p.corner[1] = glm::vec3(2, 0, 0);
  p.corner[2] = glm::vec3(2, 1, 0);
  p.corner[3] = glm::vec3(0, 1, 0);
  p.normal = glm::vec3(0, 0, 1);
  p.numCorners = 4;
  PatchGeom g = MakePatchGeom(p);
  EXPECT_EQ(PlaneAxis(g.n), 2);
  EXPECT_FALSE(OutsideEdges(g, 1.0f, 0.5f));
  EXPECT_FALSE(OutsideEdges(g, 2.0f, 1.0f));  // a corner, inside by the tolerance
  EXPECT_TRUE(OutsideEdges(g, 2.5f, 0.5f));
  EXPECT_TRUE(OutsideEdges(g, 1.0f, -0.5f));
  EXPECT_TRUE(OutsideEdges(g, 1.0f, -1e-3f));
  p.corner[3] = p.corner[2];
  p.numCorners = 3;
  g = MakePatchGeom(p);
  EXPECT_EQ(g.u[3], g.u[2]);
  EXPECT_EQ(g.v[3], g.v[2]);
  EXPECT_FALSE(OutsideEdges(g, 1.5f, 0.25f));
  EXPECT_TRUE(OutsideEdges(g, 0.5f, 0.75f));  // past the hypotenuse
  std::swap(p.corner[0], p.corner[2]);        // clockwise seen from +z: facing -z
  p.corner[3] = p.corner[2];
  p.normal = glm::vec3(0, 0, -1);
  g = MakePatchGeom(p);
  EXPECT_EQ(g.n, glm::vec3(0, 0, -1));
  EXPECT_FALSE(OutsideEdges(g, 1.5f, 0.25f));
  EXPECT_TRUE(OutsideEdges(g, 0.5f, 0.75f));
}

// The plane is scaled so that its largest component is +-1 exactly, and
// PlaneAxis finds it, also when two components are equally large.
TEST(PatchSimdTest, PlaneAxisIsTheLargestComponent) {
  Patch p{};
  p.corner[0] = glm::vec3(0, 0, 0);
  p.corner[1] = glm::vec3(1, -1, 0);
  p.corner[2] = glm::vec3(1, -1, 1);
  p.corner[3] = glm::vec3(0, 0, 1);
  p.normal = glm::normalize(glm::vec3(-1, -1, 0));
  p.numCorners = 4;
  PatchGeom g = MakePatchGeom(p);
  EXPECT_EQ(PlaneAxis(g.n), 0);
  EXPECT_EQ(g.n.x, -1.0f);
  EXPECT_EQ(g.n.y, -1.0f);
  EXPECT_FALSE(OutsideEdges(g, -0.5f, 0.5f));  // (y, z) of the middle
  EXPECT_TRUE(OutsideEdges(g, -0.5f, 1.5f));
  EXPECT_TRUE(OutsideEdges(g, 0.5f, 0.5f));
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> uni(-1.0f, 1.0f);
  for (int i = 0; i < 10000; ++i) {
    p.normal = glm::normalize(glm::vec3(uni(rng), uni(rng), uni(rng)));
    g = MakePatchGeom(p);
    int k = 0;
    for (int a = 1; a < 3; ++a)
      if (std::fabs(p.normal[a]) > std::fabs(p.normal[k])) k = a;
    ASSERT_EQ(PlaneAxis(g.n), k) << i;
    ASSERT_EQ(std::fabs(g.n[k]), 1.0f) << i;
  }
}

}  // namespace
}  // namespace vismask
