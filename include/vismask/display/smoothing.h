// Smoothing: which display vertices of different polygons show one value, so
// that a tessellated curved surface is shaded smoothly across its polygons
// while a hard edge stays sharp. Only the display changes, not the solve.
//
// Candidates are the display-lattice vertices on the outline of a polygon that
// has a smoothing group ('s N', N != 0) or vertex normals ('vn'); a polygon
// with neither is never smoothed. Two candidates of different polygons at the
// same point share their values (the display takes the weighted mean of
// both, display.h) when SmoothTogether says so. Lattice points of two
// polygons along a shared edge coincide only where the two are subdivided
// alike; elsewhere on the edge each side interpolates its own shared ends.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "vismask/scene/mesh.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/partition.h"

namespace vismask {

// Appends to mesh->smooth (sorted by vertex) the lattice vertices of `mesh`
// that lie, within `tolerance`, on an outline edge of their source polygon
// when that polygon has a smoothing group or vertex normals. `mesh` was meshed
// from `part.scene` (Patch::surface indexes its pieces) and `source` is the
// scene as loaded; a piece's vertices on the environment planes that cut it
// are not on its source's outline unless they are on an original edge too.
// `sourceIds`, when given, is each source polygon's index in the whole scene
// (the streaming init keeps only the polygons its environments cut from):
// the id a vertex is never shared with itself by.
void MarkSmoothVertices(const Scene& source, const Partition& part, float tolerance, Mesh* mesh,
                        const std::vector<uint32_t>* sourceIds = nullptr);

// Whether two polygon corners at one point share their display value, given
// each polygon's geometric normal n, its vertex normal vn there (0: none),
// its smoothing group g, and cos(crease angle). With vertex normals on both:
// when they differ by at most the crease angle and each faces the front of
// the other's polygon (so a polygon and its reversed twin never share). Else
// when both are in one smoothing group and their geometric normals differ by
// at most the crease angle (so a box given one group keeps its corners).
bool SmoothTogether(const glm::vec3& na, const glm::vec3& vna, uint32_t ga, const glm::vec3& nb,
                    const glm::vec3& vnb, uint32_t gb, float cosCrease);

}  // namespace vismask
