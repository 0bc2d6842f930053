// Partition: the scene's bounding box cut into an NX x NY x NZ grid of
// axis-aligned local environments, and every polygon clipped at the
// environment planes so that each piece, and so each patch, belongs to
// exactly one environment.
#pragma once
#include <cstdint>
#include <vector>

#include "vismask/scene.h"
#include "vismask/status.h"

namespace vismask {

struct EnvGrid {
  int n[3] = {1, 1, 1};  // environments along x, y, z
  Bounds box;            // the whole scene's box (the union of the environments)

  int count() const { return n[0] * n[1] * n[2]; }
  // Environment index of cell (ix, iy, iz): x fastest.
  int Index(int ix, int iy, int iz) const { return ix + n[0] * (iy + n[1] * iz); }
  void Cell(int index, int c[3]) const {
    c[0] = index % n[0];
    c[1] = (index / n[0]) % n[1];
    c[2] = index / (n[0] * n[1]);
  }
  // The box of environment `index`. Split planes are at
  // box.lo + (box.hi - box.lo) * k / n, computed the same way everywhere.
  Bounds EnvBox(int index) const;
  // The coordinate of split plane k (0..n) on `axis`.
  float Plane(int axis, int k) const;
};

// Parses "NX", "NXxNY" or "NXxNYxNZ" (each 1..64). False on anything else.
bool ParseEnvGrid(const char* text, int n[3]);

// The scene after partitioning: `scene.polygons` are the clipped pieces
// (material, line and normal kept from the source polygon; the uv of a cut
// piece's corners from the source's affine uv map, texture.h), `env[i]` is the
// environment of piece i, and `source[i]` the index of the polygon it was cut
// from. Pieces are ordered by environment, then by source polygon.
struct Partition {
  EnvGrid grid;
  Scene scene;
  std::vector<uint32_t> env;
  std::vector<uint32_t> source;
};

// Clips every polygon of `scene` at the planes of `grid` (whose box must
// contain the scene). A polygon lying exactly in a split plane goes to the
// environment on its front side (the side its normal points to). Pieces of
// negligible area (touching a plane along an edge) are dropped.
Status PartitionScene(const Scene& scene, const EnvGrid& grid, Partition* out);

}  // namespace vismask
