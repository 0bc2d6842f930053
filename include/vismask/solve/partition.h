// Partition: the scene's bounding box cut into an NX x NY x NZ grid of
// axis-aligned local environments, and every polygon clipped at the
// environment planes so that each piece, and so each patch, belongs to
// exactly one environment.
//
// The split planes are uniform (--envs NXxNYxNZ) or balanced (--envs
// auto[:N]): each axis's planes at the quantiles of the scene's work along
// that axis, so every slab holds about the same share. Either way the
// environments form a rectilinear grid (plane k of an axis is shared by
// every cell), which the masks' upstream/downstream rule needs
// (docs/DESIGN.md, Propagation).
//
// Balanced planes come from a WorkSplitter, an accumulator fed one polygon
// at a time, in fixed memory (kBins weights per axis, reserved when it is
// made; nothing grows per polygon), so a loader that streams the OBJ can
// feed it polygon by polygon in its first pass without holding the scene:
//
//   WorkSplitter splitter;                      // or splitter(patchSize)
//   for each polygon P (in file order):
//     splitter.Add(P.corners, n, P.area, EstimatedPatches(P.corners, n, patchSize));
//   EnvGrid grid; grid.n = ...; grid.box = the scene's bounds;
//   splitter.Planes(&grid);                     // grid now holds the planes
//
// The result depends only on the polygons and their order (not on how many
// ranks feed or read it): the whole-scene path (PrepareScene) feeds it
// every loaded polygon in file order.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "vismask/core/status.h"
#include "vismask/scene/scene.h"

namespace vismask {

constexpr int kMaxEnvsPerAxis = 64;
constexpr int kMaxAutoEnvs = 4096;  // --envs auto:N

struct EnvGrid {
  int n[3] = {1, 1, 1};  // environments along x, y, z
  Bounds box;            // the whole scene's box (the union of the environments)
  // Balanced grids: the internal planes (1..n-1) of each axis, strictly
  // increasing inside the box (WorkSplitter::Planes); uniform otherwise.
  bool balanced = false;
  float cut[3][kMaxEnvsPerAxis + 1] = {};

  int count() const { return n[0] * n[1] * n[2]; }
  // Environment index of cell (ix, iy, iz): x fastest.
  int Index(int ix, int iy, int iz) const { return ix + n[0] * (iy + n[1] * iz); }
  void Cell(int index, int c[3]) const {
    c[0] = index % n[0];
    c[1] = (index / n[0]) % n[1];
    c[2] = index / (n[0] * n[1]);
  }
  // The box of environment `index`. Uniform split planes are at
  // box.lo + (box.hi - box.lo) * k / n, computed the same way everywhere;
  // balanced ones are `cut`.
  Bounds EnvBox(int index) const;
  // The coordinate of split plane k (0..n) on `axis`.
  float Plane(int axis, int k) const;
};

// Parses "NX", "NXxNY" or "NXxNYxNZ" (each 1..64). False on anything else.
bool ParseEnvGrid(const char* text, int n[3]);

// The grid shape for `count` environments in a box of `extent`: the
// factorisation nx * ny * nz = count (each <= 64, none > 1 on an axis of no
// extent) whose cut planes have the least area (the faces masks cross);
// ties to the first in (nx, ny) ascending order. False when none exists.
bool ChooseEnvShape(int count, const glm::vec3& extent, int n[3]);

// About how many patches the mesher makes of a polygon of `n` corners at
// patch size `patchSize` (mesh.h: triangles n x n, quads m x n, others
// triangulated; exactly, for a convex polygon cut in strips): the weight a
// WorkSplitter balances.
double EstimatedPatches(const glm::vec3* corners, int n, float patchSize);

// Balanced split planes from polygons fed one at a time (see the top of
// this file). Fixed memory: kBins doubles per axis over a range that
// starts at the first polygon and doubles (merging bins pairwise) to cover
// each new one, so its resolution stays within 1/(kBins/4) of the extent
// seen. Deterministic: the same polygons in the same order give the same
// planes.
class WorkSplitter {
 public:
  static constexpr int kBins = 4096;
  WorkSplitter();
  // Adds one polygon: its `n` corners, its area (> 0) and the work it brings
  // (e.g. EstimatedPatches), spread along each axis evenly over the
  // polygon's extent there (a polygon flat on an axis is a point mass on it).
  void Add(const glm::vec3* corners, int n, double area, double weight);
  // Fills grid->cut for grid->n and grid->box: plane k of an axis at the bin
  // edge where the weight below it is nearest k/n of the total (the middle
  // of a run of equally near edges), strictly increasing and strictly inside
  // the box; an axis where that cannot be (no extent, all the weight at one
  // point) keeps uniform planes. Sets grid->balanced.
  void Planes(EnvGrid* grid) const;
  double totalWeight() const { return total_; }
  uint64_t polygons() const { return count_; }

 private:
  struct Axis {
    double lo = 0.0;     // the first bin's lower edge
    double width = 0.0;  // of one bin; 0 until the first polygon
    std::vector<double> bins;
  };
  void Cover(Axis* a, double lo, double hi, double scale);
  std::vector<double> PlanesOf(int axis, int n, float boxLo, float boxHi) const;
  Axis axis_[3];
  double total_ = 0.0;
  uint64_t count_ = 0;
};

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
