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

constexpr int kProbes = 5;  // rays a point: the normal and four at 60 degrees to it
// Probes a point needs to reach out for it to be open, the normal counting
// for all. One 60-degree probe is not enough: a ceiling's points above the
// Cornell lamp (0.8 mm below it) within 1.4 mm of its edge see out along
// one, receive next to nothing, and as an open eighth of a leaf their
// weight darkened the vertices beside the lamp.
constexpr int kMinReaching = 2;

}  // namespace

// Every leaf not yet measured, one point a cell (stratified over its
// square); then again, kFineExposure points to a cell's side, the leaves of
// every patch with a buried part or a corner shared with one. One point a
// cell (its centre) missed the strip of the Cornell ceiling above the
// lamp's edge, 13% of a patch at the 0.3 s plan's size: the patch showed
// its power spread over the whole, a dark band beside the lamp. Four a
// cell everywhere took init from 0.78 to 2.2 s on the box at patch size 5;
// this way 0.96 s, with the same images.
void Environment::MeasureExposure() {
  bool any = false;
  for (uint32_t i = 0; i < patches_.size(); ++i) any |= MeasurePatchExposure(i, 1);
  if (!any) return;
  lattice_.ClearMarks();
  for (uint32_t i = 0; i < patches_.size(); ++i)
    if (PartlyBuried(i))
      for (uint32_t k = 0; k < patches_[i].numCorners; ++k) lattice_.Mark(patches_[i].vertex[k]);
  for (uint32_t i = 0; i < patches_.size(); ++i) {
    bool near = false;
    for (uint32_t k = 0; k < patches_[i].numCorners; ++k)
      near |= lattice_.Marked(patches_[i].vertex[k]);
    if (!near) continue;
    ForEachLeaf(elements_.all(), patches_[i].numCorners == 3, i,
                [&](uint32_t e, const glm::vec2*, int) {
                  elements_.SetExposed(e, ElementTree::kUnmeasured, 0);
                });
    MeasurePatchExposure(i, kFineExposure);
  }
}

bool Environment::PartlyBuried(uint32_t i) const {
  bool buried = false;
  ForEachLeaf(elements_.all(), patches_[i].numCorners == 3, i,
              [&](uint32_t e, const glm::vec2*, int) {
                const float share = elements_.exposed(e);
                buried |= share >= 0.0f && share < 1.0f;
              });
  return buried;
}

bool Environment::MeasurePatchExposure(uint32_t i, int fine) {
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
  const int side = fine * ElementTree::kOpenSide;
  bool measured = false;
  ForEachLeaf(elements_.all(), triangle, i, [&](uint32_t e, const glm::vec2* c, int n) {
    if (elements_.exposed(e) != ElementTree::kUnmeasured) return;
    measured = true;
    int open = 0, points = 0;
    // Open points per cell: a cell is open when all of its points are, so
    // that no origin is drawn where a ray would start inside a solid.
    uint8_t cellOpen[ElementTree::kOpenSide * ElementTree::kOpenSide] = {};
    for (int a = 0; a < side; ++a)
      for (int b = 0; b < side; ++b) {
        float u = (a + 0.5f) / side, v = (b + 0.5f) / side;
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
        int reached = 0;
        for (int r = 0; r < kProbes && reached < kMinReaching; ++r) {
          Hit hit;
          const Ray probe{x, dirs[r], eps, std::numeric_limits<float>::infinity()};
          const bool missed = !grid_.Intersect(probe, skip, &hit);
          // The normal alone is enough: a slit's mouth is never straight
          // above. Not when it leaves for a neighbour, though: a block cut
          // by the plane above it has its top there, and from under it only
          // the slanted probes meet its walls from inside.
          const bool whole = r == 0 && !(missed && ExitFace(probe) >= 0);
          reached += missed || hit.front ? (whole ? kMinReaching : 1) : 0;
        }
        const bool reaches = reached >= kMinReaching;
        open += reaches ? 1 : 0;
        if (reaches) ++cellOpen[(a / fine) * ElementTree::kOpenSide + b / fine];
        ++points;
      }
    uint16_t cells = 0;
    for (int k = 0; k < ElementTree::kOpenSide * ElementTree::kOpenSide; ++k)
      if (cellOpen[k] == fine * fine) cells = static_cast<uint16_t>(cells | (1u << k));
    elements_.SetExposed(e, static_cast<float>(open) / static_cast<float>(points), cells);
  });
  return measured;
}

}  // namespace vismask
