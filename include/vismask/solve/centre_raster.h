// Method B's centre mask by patch rather than by ray. Every pixel's centre
// ray starts at one point, so instead of walking the grid once per pixel,
// each patch is bounded by a cone about the origin, the cone by a range of
// rows and columns of the hemisphere, and only the still-open pixels in that
// range are tested against that patch, with the very IntersectPatch the
// grid's walk calls on the very same ray. A pixel closes iff some patch
// passes that test, which is Grid::Occluded's answer wherever the grid
// agrees with testing every patch (tests/grid_test.cpp): the two give the
// same bits (tests/mask_test.cpp). The ranges are conservative: a cone
// widened for rounding, then one pixel more on every side.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <limits>

#include "vismask/accel/grid.h"
#include "vismask/core/span.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/patch.h"
#include "vismask/solve/sampling.h"

namespace vismask {

// The centre rays, as Environment::CastCentres forms them: from `origin`,
// through the centre of pixel p of `dirs` turned into the world by `frame`,
// over (0, inf).
struct CentreRays {
  glm::vec3 origin;
  Frame frame;
  const MaskDirections* dirs;
  Ray Of(uint32_t pixel) const { return Through(dirs->Centre(pixel)); }
  Ray Of(uint32_t row, uint32_t col) const { return Through(dirs->Centre(row, col)); }
  Ray Through(const glm::vec3& local) const {
    return Ray{origin, frame.ToWorld(local), 0.0f, std::numeric_limits<float>::infinity()};
  }
};

// Closes each open pixel of `mask` whose centre ray hits one of `geom`
// (corners from `patches`), other than the two in `skip`. Returns the
// patch tests made (a deterministic count, the work).
uint64_t RasterCentres(Span<const Patch> patches, Span<const PatchGeom> geom, Skip skip,
                       const CentreRays& rays, MaskBits* mask);

// The same by walking `grid` once per open pixel (with the last occluder
// tried first). Returns the grid's steps.
uint64_t WalkCentres(const Grid& grid, Skip skip, const CentreRays& rays, MaskBits* mask);

// Columns [lo, hi] of one row of the hemisphere, on the unrolled circle:
// they may run past either end (wrap); empty when lo > hi.
struct PixelArc {
  int lo = 1, hi = 0;
};

// Where a convex polygon is seen from the rays' origin. The directions
// through it are those on the inner side of the plane through the origin
// and each of its edges (the cone over it), each plane widened by `margin`
// (a sine). Rows [rowLo, rowHi], and columns [colLo, colHi] for every row,
// bound that cone; within a row, each edge plane leaves an arc of columns.
// With no edge planes (the origin near the polygon's plane), the bounds
// alone.
struct PolygonView {
  int rowLo = 1, rowHi = 0;
  int colLo = 0, colHi = -1;
  int edges = 0;
  // Per edge plane: 1 / |normal.xy|, its angle in columns less half a
  // column, normal.z.
  double invXY[4], psiCols[4], z[4];
  double margin = 0.0;
  double inner = -1.0;  // >= 0: the directions inside every plane by this much
};

// The view of a polygon (a box face) from the rays' origin over the whole
// hemisphere: planes widened by `margin` for the columns that may see it,
// narrowed by `inner` for those that surely do (< 0: none). False when the
// origin is near the polygon's plane: then every pixel must be tested.
bool FaceView(const Patch& face, const CentreRays& rays, double margin, double inner,
              PolygonView* v);
// Row `row` of a view: *may, the columns whose centre directions may pass
// through the polygon (and one more each side), and *sure (with an inner
// margin), those that surely do (and one fewer each side). False when no
// column may.
bool ViewRow(const PolygonView& v, const CentreRays& rays, uint32_t row, PixelArc* may,
             PixelArc* sure);

// Face `side` (0: lo, 1: hi) of `box` across `axis`, as a rectangle whose
// corners run lo-lo, hi-lo, hi-hi, lo-hi over the next two axes, facing
// out of the box.
Patch BoxFace(const Bounds& box, int axis, int side);

// Calls f(col, sure) for each column of `may` (wrapping on a row of `cols`),
// `sure` telling whether the column is also one of `sure`'s (which `may`
// holds, as a row's view gives them).
template <typename F>
void ForArc(const PixelArc& may, const PixelArc& sure, int cols, F&& f) {
  int span = may.hi - may.lo + 1 < cols ? may.hi - may.lo + 1 : cols;
  int sureLo = sure.lo - may.lo, sureHi = sure.hi - may.lo;  // as offsets in may
  if (sure.lo <= sure.hi) {
    int shift = ((sureLo % cols) + cols) % cols - sureLo;
    sureLo += shift;
    sureHi += shift;
  }
  int col = ((may.lo % cols) + cols) % cols;
  for (int k = 0; k < span; ++k, col = col + 1 == cols ? 0 : col + 1)
    f(col, k >= sureLo && k <= sureHi);
}

// Closes each open pixel whose centre direction cannot pass through any of
// `exits` (at most 6 rectangles: the faces of the rays' environment that
// another environment lies beyond), keeping, with a margin, every pixel
// that a direction able to leave through one of them falls in. Returns
// the pixels closed. The origin must be inside the box the faces bound.
uint32_t KeepExits(Span<const Patch> exits, const CentreRays& rays, MaskBits* mask);

}  // namespace vismask
