// Environment::MeasureExposure (environment.h): the share of each leaf that
// is not buried inside a closed solid. A floor runs on under a block that
// stands on it; the part beneath receives nothing, so a patch or leaf that
// straddles the block's foot shows its received power spread over an area
// half dark, and its vertices' means carry the dark part out beside the
// block (a shadow leak). With the buried share known, a leaf shows its
// power over its exposed area and weighs that much in its vertices.
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <limits>

#include "vismask/accel/grid.h"
#include "vismask/solve/element.h"
#include "vismask/solve/environment.h"

namespace vismask {

namespace {

constexpr int kExposureSide = ElementTree::kOpenSide;  // points a leaf: its square, stratified
constexpr int kProbes = 5;  // rays a point: the normal and four at 60 degrees to it

}  // namespace

void Environment::MeasureExposure() {
  for (uint32_t i = 0; i < patches_.size(); ++i) MeasurePatchExposure(i);
}

void Environment::MeasurePatchExposure(uint32_t i) {
  const float eps = options_.rayEpsilon;
  const Patch& p = patches_[i];
  const bool triangle = p.numCorners == 3;
  // The probes' directions in the patch's frame (fixed: the same bytes
  // whatever the run).
  const glm::vec3 t1 = glm::normalize(p.corner[1] - p.corner[0]);
  const glm::vec3 t2 = glm::cross(p.normal, t1);
  const float c60 = 0.5f, s60 = 0.866025404f;
  const glm::vec3 dirs[kProbes] = {p.normal, c60 * p.normal + s60 * t1, c60 * p.normal - s60 * t1,
                                   c60 * p.normal + s60 * t2, c60 * p.normal - s60 * t2};
  const Skip skip(i, twinOf(i));
  ForEachLeaf(elements_.all(), triangle, i, [&](uint32_t e, const glm::vec2* c, int n) {
    if (elements_.exposed(e) != ElementTree::kUnmeasured) return;
    int open = 0, points = 0;
    uint16_t cells = 0;
    for (int a = 0; a < kExposureSide; ++a)
      for (int b = 0; b < kExposureSide; ++b) {
        float u = (a + 0.5f) / kExposureSide, v = (b + 0.5f) / kExposureSide;
        glm::vec2 st;
        if (n == 3) {
          // Folded into the triangle: (u, v) beyond the diagonal mirrored.
          if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
          st = c[0] + u * (c[1] - c[0]) + v * (c[2] - c[0]);
        } else {
          st = (1.0f - u) * (1.0f - v) * c[0] + u * (1.0f - v) * c[1] + u * v * c[2] +
               (1.0f - u) * v * c[3];
        }
        const glm::vec3 x = PatchPoint(p, st);
        bool reaches = false;
        for (int r = 0; r < kProbes && !reaches; ++r) {
          Hit hit;
          reaches = !grid_.Intersect(Ray{x, dirs[r], eps, std::numeric_limits<float>::infinity()},
                                     skip, &hit) ||
                    hit.front;
        }
        open += reaches ? 1 : 0;
        if (reaches) cells = static_cast<uint16_t>(cells | (1u << (a * kExposureSide + b)));
        ++points;
      }
    elements_.SetExposed(e, static_cast<float>(open) / static_cast<float>(points), cells);
  });
}

}  // namespace vismask
