// Meshing's pieces (internal to src/scene/mesh.cpp and
// src/scene/mesh_strips.cpp): the parts a polygon is cut into before they
// are subdivided, and a convex polygon of many corners cut in strips.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

namespace vismask::meshing {

// A part of a polygon to subdivide: a convex quad into an m x n grid of quads,
// or a triangle into n x n similar triangles (m unused).
struct Piece {
  uint32_t polygon;
  int numCorners;
  glm::dvec3 c[4];
  double m, n;
  // A triangle as a fan of n triangles from c[0] to points from c[1] to
  // c[2] (a strip's end, StripPieces), not n x n similar ones.
  bool fan = false;
};

// A convex polygon with more corners than a quad, as strips: cut across
// its longest extent into slabs whose outline chords are at most `s` long
// and pass every corner they skip within s / 64, each slab a column of
// quads (a fan at a pointed end); their pieces appended to *pieces unless
// null, their patches and lattice vertices added to the counts. False
// when it does not apply.
bool StripPieces(const std::vector<glm::dvec3>& c, glm::dvec3 normal, uint32_t index, double s,
                 std::vector<Piece>* pieces, double* numPatches, double* numVertices);

}  // namespace vismask::meshing
