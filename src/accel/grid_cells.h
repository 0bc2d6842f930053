// Grid cell registration (internal to src/accel/grid.cpp's Grid::MakePlan and
// Grid::Build): the conservative region where a patch's ray test can report
// a hit (its Shape: a box and separating axes, padded for float rounding),
// and the cells of a plan that region may overlap. Both use exactly this
// code, so the planned and the built reference counts agree.
#pragma once
#include <cmath>
#include <cstddef>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "vismask/accel/grid.h"
#include "vismask/core/span.h"
#include "vismask/solve/patch.h"

namespace vismask::gridcells {

constexpr int kMaxPolyVerts = 8;  // a square clipped by four half-planes
constexpr int kMaxAxes = 1 + 4 * kMaxPolyVerts + 3;

// Padding and far limit, from the corners' extent and distance from the origin.
struct Scale {
  float edgePad = 0.0f;
  float pad = 0.0f;
  float farLimit = 0.0f;
};
Scale ScaleOf(Span<const Patch> patches);

// The region where IntersectPatch can report a hit on one patch, widened by
// the padding: a prism over the patch's (widened) polygon. Kept as a box plus
// separating axes with the prism's projection on each.
struct Shape {
  glm::dvec3 lo;
  glm::dvec3 hi;
  int numAxes = 0;
  glm::dvec3 axis[kMaxAxes];
  double pMin[kMaxAxes];
  double pMax[kMaxAxes];
};

// Builds the shape of patch `p` with ray-test data `g` (depends on nothing
// else, so MakePlan and Build register the same cells). boxOnly: its box
// alone, by the same arithmetic (the same bits), without the separating
// axes that are most of the cost (MakePlan's bounds need only the box).
// allAxes: also the axes that repeat others exactly (tests: the cells must
// be the same).
void MakeShape(const Patch& p, const PatchGeom& g, const Scale& scale, Shape* s,
               bool boxOnly = false, bool allAxes = false);

// Cell geometry of a plan, in double for registration.
struct CellGeometry {
  glm::dvec3 lo;
  glm::dvec3 size;
  glm::dvec3 inv;
  int res[3];
};
CellGeometry CellGeometryOf(const Grid::Plan& plan);

inline int ClampCell(double x, int res) {
  if (!(x >= 0.0)) return 0;  // also NaN
  if (x >= res - 1) return res - 1;
  return static_cast<int>(x);
}

// Calls visit(cellIndex) for every cell the shape may overlap, in index order.
template <class Visit>
void ForEachCell(const CellGeometry& f, const Shape& s, Visit&& visit) {
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = ClampCell(std::floor((s.lo[a] - f.lo[a]) * f.inv[a]), f.res[a]);
    hi[a] = ClampCell(std::floor((s.hi[a] - f.lo[a]) * f.inv[a]), f.res[a]);
  }
  glm::dvec3 half = 0.5 * f.size;
  for (int z = lo[2]; z <= hi[2]; ++z) {
    for (int y = lo[1]; y <= hi[1]; ++y) {
      for (int x = lo[0]; x <= hi[0]; ++x) {
        glm::dvec3 centre = f.lo + (glm::dvec3(x, y, z) + 0.5) * f.size;
        bool apart = false;
        for (int i = 0; i < s.numAxes && !apart; ++i) {
          const glm::dvec3& ax = s.axis[i];
          double c = glm::dot(ax, centre);
          double r = std::fabs(ax.x) * half.x + std::fabs(ax.y) * half.y + std::fabs(ax.z) * half.z;
          apart = c + r < s.pMin[i] || c - r > s.pMax[i];
        }
        if (!apart) visit((static_cast<size_t>(z) * f.res[1] + y) * f.res[0] + x);
      }
    }
  }
}

}  // namespace vismask::gridcells
