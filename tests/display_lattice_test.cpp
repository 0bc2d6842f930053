// DisplayLattice's smoothing of the indirect part (Finish with steps): a
// linear field stays exactly as it was, a noisy one loses its noise, and the
// values without smoothing are kept for the leaves inside a patch.
#include "vismask/solve/display_lattice.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "vismask/core/arena.h"

namespace vismask {
namespace {

// An N x N lattice of unit quads in z = 0: vertex (i, j) is i + (N + 1) j.
struct Square {
  static constexpr int kN = 8;
  std::vector<Patch> patches;
  DisplayLattice::Staged staged;
  Arena arena{1 << 20};
  DisplayLattice lattice;

  Square() {
    for (int j = 0; j <= kN; ++j)
      for (int i = 0; i <= kN; ++i) staged.vertices.push_back(glm::vec3(i, j, 0));
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) {
        Patch p{};
        const uint32_t v0 = i + (kN + 1) * j;
        const uint32_t ids[4] = {v0, v0 + 1, v0 + kN + 2, v0 + kN + 1};
        for (int k = 0; k < 4; ++k) {
          p.vertex[k] = ids[k];
          p.corner[k] = staged.vertices[ids[k]];
        }
        p.numCorners = 4;
        p.area = 1.0f;
        p.normal = glm::vec3(0, 0, 1);
        patches.push_back(p);
      }
    lattice.Layout(arena, staged, true);
    lattice.Build(staged, Span<const Patch>(patches.data(), patches.size()));
  }
  // Each patch one leaf showing `value(patch)`, as ComputeVertexRadiosity adds it.
  // `weight(patch)`: its leaf's exposed area (0: buried, nothing sees it).
  template <typename F, typename W>
  void Fill(F value, int steps, W weight) {
    lattice.Clear();
    for (uint32_t i = 0; i < patches.size(); ++i)
      for (int k = 0; k < 4; ++k) lattice.Add(patches[i].vertex[k], weight(i), value(i), 1.0f);
    lattice.Finish(Span<const Patch>(patches.data(), patches.size()), steps);
  }
  template <typename F>
  void Fill(F value, int steps) {
    Fill(value, steps, [](uint32_t) { return 1.0f; });
  }
  glm::vec3 Centre(uint32_t i) const {
    return 0.25f * (patches[i].corner[0] + patches[i].corner[1] + patches[i].corner[2] +
                    patches[i].corner[3]);
  }
};

TEST(DisplayLatticeTest, SmoothingLeavesALinearFieldAsItWas) {
  Square s;
  auto linear = [&](uint32_t i) {
    glm::vec3 c = s.Centre(i);
    return glm::vec3(1.0f + 0.25f * c.x + 0.1f * c.y, 2.0f - 0.05f * c.x, 0.5f + 0.2f * c.y);
  };
  s.Fill(linear, 0);
  std::vector<glm::vec3> plain(s.lattice.radiosity().begin(), s.lattice.radiosity().end());
  EXPECT_FALSE(s.lattice.smoothed());
  s.Fill(linear, 6);
  EXPECT_TRUE(s.lattice.smoothed());
  for (uint32_t v = 0; v < plain.size(); ++v)
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(s.lattice.radiosity()[v][c], plain[v][c], 1e-4f) << "vertex " << v;
      EXPECT_EQ(s.lattice.Unsmoothed(v)[c], plain[v][c]) << "vertex " << v;
    }
}

TEST(DisplayLatticeTest, SmoothingTakesTheNoiseOutAndKeepsTheMean) {
  Square s;
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 0.2f);
  std::vector<float> v(s.patches.size());
  for (float& x : v) x = 1.0f + noise(rng);
  auto field = [&](uint32_t i) { return glm::vec3(v[i]); };
  // The spread about 1 of the vertices two edges or more inside the
  // outline (those smoothed), and their mean.
  auto spread = [&](double* mean) {
    double sum = 0.0, sq = 0.0;
    int n = 0;
    for (int j = 2; j < Square::kN - 1; ++j)
      for (int i = 2; i < Square::kN - 1; ++i) {
        double x = s.lattice.radiosity()[i + (Square::kN + 1) * j].x;
        sum += x, sq += (x - 1.0) * (x - 1.0), ++n;
      }
    *mean = sum / n;
    return std::sqrt(sq / n);
  };
  double mean0, mean6;
  s.Fill(field, 0);
  double before = spread(&mean0);
  s.Fill(field, 6);
  double after = spread(&mean6);
  EXPECT_LT(after, 0.5 * before);
  EXPECT_NEAR(mean6, mean0, 0.05);
}

// A vertex no exposed leaf touches (weight 0: under a lamp that hangs just
// below the ceiling, under a block on the floor) holds no value, so its
// neighbours must not take it in: a uniform field stays uniform around a
// buried block of 2 x 2 patches (it went dark there, a halo around the
// Cornell box's lamp).
TEST(DisplayLatticeTest, SmoothingLeavesBuriedVerticesOut) {
  Square s;
  auto buried = [](uint32_t i) {
    const int x = static_cast<int>(i) % Square::kN, y = static_cast<int>(i) / Square::kN;
    return (x == 3 || x == 4) && (y == 3 || y == 4);
  };
  s.Fill([](uint32_t) { return glm::vec3(1.0f); }, 6,
         [&](uint32_t i) { return buried(i) ? 0.0f : 1.0f; });
  const uint32_t centre = 4 + (Square::kN + 1) * 4;  // touches only buried patches
  EXPECT_EQ(s.lattice.weights()[centre], 0.0f);
  int checked = 0;
  for (uint32_t v = 0; v < s.lattice.radiosity().size(); ++v) {
    if (v == centre) continue;
    EXPECT_NEAR(s.lattice.radiosity()[v].x, 1.0f, 1e-5f) << "vertex " << v;
    ++checked;
  }
  EXPECT_EQ(checked, (Square::kN + 1) * (Square::kN + 1) - 1);
}

}  // namespace
}  // namespace vismask
