// Helpers shared by the partition tests: polygons and scenes built from
// corners, environment grids, and the invariants every partition keeps.
#pragma once
#include <gtest/gtest.h>

#include <glm/vec3.hpp>
#include <vector>

#include "vismask/scene/scene.h"
#include "vismask/solve/partition.h"

namespace vismask::parttest {

// Newell's area vector of a polygon's corners, in double.
glm::dvec3 AreaVector(const std::vector<glm::vec3>& corners);

// A polygon with the normal and area the loader would give its corners.
Polygon MakePolygon(const std::vector<glm::vec3>& corners, int line);

// A one-material scene of `polygons`, its bounds those of their corners.
Scene MakeScene(const std::vector<Polygon>& polygons);

// The grid `text` (as --envs gives it) over `box`.
EnvGrid MakeGrid(const char* text, const Bounds& box);

Scene LoadCornell();

// Checks the invariants of a partition of `scene` by `grid`: order, kept
// attributes, pieces inside their boxes, convex and planar where cut, and
// areas conserved per source polygon and in total (so nothing is duplicated).
void CheckPartition(const Scene& scene, const EnvGrid& grid, const Partition& part);

}  // namespace vismask::parttest
