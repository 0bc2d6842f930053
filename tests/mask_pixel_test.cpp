// MaskDirections::Pixel, the tables' MaskPixel (Methods A and C mark a pixel
// per form-factor ray): the same pixel as MaskPixel for every direction.
// CosinePixel, the pixel of a form-factor ray from its sample: the same
// pixel as MaskPixel for every sample.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <random>
#include <vector>

#include "mask_test_util.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/sampling.h"

namespace vismask {
namespace {

constexpr double kHalfPi = 1.5707963267948966, kTwoPi = 6.283185307179586;
const uint32_t kResolutions[] = {1, 2, 7, 50, 100, 250, 4096};

// Fails the test at the first direction whose pixels differ.
void ExpectSame(const MaskDirections& dirs, const glm::vec3& d) {
  uint32_t fast = dirs.Pixel(d), slow = MaskPixel(d, dirs.res());
  ASSERT_EQ(fast, slow) << "res " << dirs.res() << " d " << std::hexfloat << d.x << " " << d.y
                        << " " << d.z;
}

// x moved k ulps (k may be negative).
float Ulps(float x, int k) {
  for (; k > 0; --k) x = std::nextafter(x, 2.0f * std::fabs(x) + 1.0f);
  for (; k < 0; ++k) x = std::nextafter(x, -2.0f * std::fabs(x) - 1.0f);
  return x;
}

// A million random directions a resolution: the sampler's own (cosine,
// CosineDirection) and uniform ones, unit and not.
TEST(MaskPixelTest, RandomDirectionsGiveMaskPixel) {
  std::mt19937 rng(19);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), signed_(-1.0f, 1.0f);
  for (uint32_t res : kResolutions) {
    test::MaskTables t(res);
    for (int k = 0; k < 500000; ++k) {
      ExpectSame(t.dirs, CosineDirection(unit(rng), unit(rng)));
      glm::vec3 d(signed_(rng), signed_(rng), unit(rng));
      ExpectSame(t.dirs, d);
      if (glm::length(d) > 0.0f) ExpectSame(t.dirs, glm::normalize(d));
      if (HasFatalFailure()) return;
    }
  }
}

// Directions on and a few ulps either side of every row edge (z = cos of
// the edge angle) and every column edge (x, y at the edge angle, and u2 at
// the edge through CosineDirection), the diagonals and the axes.
TEST(MaskPixelTest, EdgesGiveMaskPixel) {
  uint64_t checked = 0;
  for (uint32_t res : kResolutions) {
    test::MaskTables t(res);
    auto check = [&](const glm::vec3& d) {
      ExpectSame(t.dirs, d);
      ++checked;
    };
    for (uint32_t k = 0; k <= res; ++k) {
      double theta = k * kHalfPi / res;
      float z = static_cast<float>(std::cos(theta)), s = static_cast<float>(std::sin(theta));
      float u1 = static_cast<float>(std::sin(theta) * std::sin(theta));
      for (int n = -4; n <= 4; ++n) {
        float zn = Ulps(z, n);
        check(glm::vec3(0.6f * s, 0.8f * s, zn));
        check(glm::vec3(-0.28f * s, -0.96f * s, zn));
        check(glm::vec3(1e-3f, -2e-3f, zn));
        if (Ulps(u1, n) >= 0.0f) check(CosineDirection(Ulps(u1, n), 0.3f));
      }
      if (HasFatalFailure()) return;
    }
    for (uint32_t j = 0; j <= 4 * res; ++j) {
      double phi = j * kTwoPi / (4 * res);
      float c = static_cast<float>(std::cos(phi)), s = static_cast<float>(std::sin(phi));
      float u2 = static_cast<float>(static_cast<double>(j) / (4 * res));
      for (int n = -4; n <= 4; ++n)
        for (float r : {1.0f, 0.5f, 1e-3f, 1e-20f}) {
          float z = std::sqrt(std::fmax(0.0f, 1.0f - r * r));
          check(glm::vec3(r * Ulps(c, n), r * s, z));
          check(glm::vec3(r * c, r * Ulps(s, n), z));
          check(glm::vec3(r * Ulps(c, n), r * Ulps(s, -n), z));
          check(CosineDirection(r, Ulps(u2, n)));
        }
      if (HasFatalFailure()) return;
    }
    // Diagonals (x = +-y), axes and signed zeros, poles and horizon.
    for (float a : {1.0f, 0.7071068f, 1e-3f, 1e-30f, 0.0f, -0.0f})
      for (float b : {1.0f, -1.0f, 0.0f, -0.0f})
        for (float z : {0.0f, 1e-30f, 0.5f, 1.0f, 1.5f, -0.5f}) {
          check(glm::vec3(a, b * a, z));
          check(glm::vec3(b * a, a, z));
          check(glm::vec3(-a, b * a, z));
          check(glm::vec3(b * a, -a, z));
        }
    if (HasFatalFailure()) return;
  }
  EXPECT_GT(checked, 2000000u);
}

// CosinePixel(u2, CosineDirection(u1, u2)) against MaskPixel: random
// samples, and u1 and u2 on and a few ulps either side of every row and
// column edge (where 2 pi u2 and the direction's angle fall on either side
// of an edge if the margin is too small), u1 = 0 (the normal) and tiny.
TEST(MaskPixelTest, CosinePixelGivesMaskPixel) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  uint64_t checked = 0;
  for (uint32_t res : kResolutions) {
    test::MaskTables t(res);
    auto check = [&](float u1, float u2) {
      glm::vec3 d = CosineDirection(u1, u2);
      uint32_t fast = t.dirs.CosinePixel(u2, d), slow = MaskPixel(d, res);
      ASSERT_EQ(fast, slow) << "res " << res << " u1 " << std::hexfloat << u1 << " u2 " << u2;
      ++checked;
    };
    for (int k = 0; k < 300000; ++k) check(unit(rng), unit(rng));
    if (HasFatalFailure()) return;
    for (uint32_t j = 0; j <= 4 * res; ++j) {
      float u2 = static_cast<float>(static_cast<double>(j) / (4 * res));
      for (int n = -6; n <= 6; ++n) {
        float v = Ulps(u2, n);
        if (!(v >= 0.0f && v < 1.0f)) continue;
        for (float u1 : {0.0f, 1e-30f, 1e-12f, 1e-6f, 0.3f, 0.9999f, unit(rng)}) check(u1, v);
        // Further out, near the margin: 1e-6 and 3e-5 of a column.
        for (double off : {-3e-5, -1e-6, 1e-6, 3e-5}) {
          float w = static_cast<float>((j + off) / (4 * res));
          if (w >= 0.0f && w < 1.0f) check(unit(rng), w);
        }
      }
      if (HasFatalFailure()) return;
    }
    for (uint32_t k = 0; k <= res; ++k) {
      double theta = k * kHalfPi / res;
      float u1 = static_cast<float>(std::sin(theta) * std::sin(theta));
      for (int n = -6; n <= 6; ++n) {
        float v = Ulps(u1, n);
        if (v >= 0.0f && v <= 1.0f) check(v, unit(rng));
      }
      if (HasFatalFailure()) return;
    }
  }
  EXPECT_GT(checked, 2000000u);
}

}  // namespace
}  // namespace vismask
