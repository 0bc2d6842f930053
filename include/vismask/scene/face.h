// Face: one OBJ face as read, checked and made into the planar simple
// polygons the renderer takes. Strict, a face that is not one already is
// refused (the loader before issue 16); otherwise it is mended: degenerate
// corners removed, a non-planar face triangulated, and what cannot be
// mended dropped. Init-time (heap).
#pragma once
#include <string>
#include <vector>

#include "vismask/scene/scene.h"

namespace vismask {

// What became of a face (the loader counts each kind and warns once).
struct FaceResult {
  enum Fate {
    kKept,              // as read, or with corners removed (removedCorners > 0)
    kTriangulated,      // non-planar: replaced by triangles of its corners
    kDegenerate,        // dropped: zero area, or fewer than 3 distinct non-collinear corners
    kSelfIntersecting,  // dropped: its edges cross or touch (planar or in the best-fit plane)
    kRefused,           // strict only: `error` says why, in the words of the loader before
  };
  Fate fate = kKept;
  size_t removedCorners = 0;    // repeated corners and corners collinear with their neighbours
  size_t droppedTriangles = 0;  // kTriangulated: degenerate triangles left out
  double offPlane = 0.0;        // kTriangulated: the farthest corner from the best-fit plane
  std::string error;            // kRefused
};

// Checks face `face` (corners, with per-corner uv and vn when not empty,
// material, line and smoothing group set) and appends what it becomes to
// *out: nothing, itself with its normal and area set, itself without some
// corners, or triangles (each carrying its corners' uv and vn and the face's
// material, line and smoothing group). Strict, anything but a good face is
// kRefused and nothing is appended. The checks are relative to the face's
// size (its largest corner-to-corner distance): corners closer than 1e-6 of
// it coincide, a corner whose edges turn by less than 1e-5 (|sin|) is
// collinear, a face of area below 1e-6 size^2 has none, and a corner farther
// than 1e-4 of it from the face's plane (Newell's normal through the corners'
// centroid) makes the face non-planar. Mending, in this order: a corner that
// repeats the one before it, or that lies on the line through its
// neighbours (a vertex in the middle of an edge, a spike going out and back)
// is removed, until none is; a face left with fewer than 3 corners or no
// area is kDegenerate; one whose corners repeat further apart, or whose
// edges cross in its plane (or, non-planar, in the projection along its
// normal's main axis), is kSelfIntersecting (a bow tie has no one reading);
// a non-planar quad is split along the diagonal whose two triangles are the
// flatter pair (the larger cosine between their normals; 1-3 only when 0-2
// would fold the face over), a larger one ear-clipped in that projection.
FaceResult ShapeFace(const Polygon& face, bool strict, std::vector<Polygon>* out);

}  // namespace vismask
