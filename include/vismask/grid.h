// Grid: the SEADS-style uniform grid over one environment's patches.
// Two flat arrays built once at init: cellStart (numCells + 1 offsets) and
// refs (cell by cell: a header word, then the patch indices), a bitmap of
// the cells that hold any patch (so the walk reads an empty cell's bit, not
// its offsets), and a small table of planes (CellPlane) that lets a ray
// pass a cell whose patches all lie in one plane without reading them. Rays walk it with a 3D-DDA
// (Amanatides & Woo). Intersect finds the closest hit, Occluded stops at the first. The resolution
// follows the patch count and the extent (Cleary et al.: cells per axis = extent * cbrt(density * N
// / volume)); a face of the box that walls lie on is placed just inside an outer layer of cells.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>

#include "vismask/arena.h"
#include "vismask/patch.h"
#include "vismask/scene.h"
#include "vismask/span.h"

namespace vismask {

// The patches a ray ignores: the one it was shot from and, in a two-sided
// mesh, that patch's twin (coplanar, behind the origin: mesh.h). Either may
// be kNoPatch; a plain index converts.
struct Skip {
  uint32_t patch = kNoPatch;
  uint32_t twin = kNoPatch;
  Skip(uint32_t p = kNoPatch, uint32_t t = kNoPatch) : patch(p), twin(t) {}  // NOLINT: implicit
};

// A plane shared by a run of patches: consecutive in index order, of one
// source surface, with the same normal up to its sign (a twin's is
// negated, TwinGeom). `n` is the normal with its first non-zero component
// positive, [dLo, dHi] the range of the patches' plane offsets (PatchGeom::d)
// on that side. A cell whose patches all belong to runs with the same
// record keeps its index in its header word. A ray that meets the plane
// behind its origin, for every offset in the range, meets every patch of
// the cell at t <= 0 (float subtraction is monotonic, and IntersectPatch's
// sign of t is that of d - n.o over n.dir), so with tMin >= 0 the walk
// passes the cell without reading its patches, and finds what testing them
// would have found. A ray leaving a wall, or running beside one, does.
struct CellPlane {
  glm::vec3 n{0.0f};
  float dLo = 0.0f;
  float dHi = 0.0f;
  uint32_t first = 0;  // the run: patches first .. first + count - 1
  uint32_t count = 0;
};

class Grid {
 public:
  // A cell's header word when its patches share no plane record.
  static constexpr uint32_t kNoPlane = 0xffffffffu;
  // What the grid needs, decided at init before any arena exists.
  struct Plan {
    int res[3] = {1, 1, 1};
    uint64_t refs = 0;      // total (cell, patch) references
    uint64_t occupied = 0;  // cells holding a reference (a header word each)
    uint64_t planes = 0;    // CellPlane records: runs of two or more patches
    Bounds bounds;          // padded box the cells cover
  };
  // Plans the grid for `patches` with about `density` cells per patch.
  static Plan MakePlan(Span<const Patch> patches, float density);
  // The same, for patches whose ray-test data is `geom` (what Build will
  // be given), rather than MakePatchGeom of each (twins: TwinGeom).
  static Plan MakePlan(Span<const Patch> patches, Span<const PatchGeom> geom, float density);

  // Carves cellStart, refs and the planes from `arena` (also from a measuring arena).
  void Layout(Arena& arena, const Plan& plan);
  // Fills the arrays. `geom` must outlive the grid; indices are into it.
  void Build(Span<const Patch> patches, Span<const PatchGeom> geom);

  // Closest hit in (ray.tMin, ray.tMax), ignoring the patches in `skip`.
  // Front and back sides both count. Of hits at the same t, a front side
  // wins, then the lower index: of two coplanar twins (TwinGeom) the one
  // the ray faces.
  bool Intersect(const Ray& ray, Skip skip, Hit* hit) const;
  // True if anything is hit in (ray.tMin, ray.tMax), ignoring `skip`.
  bool Occluded(const Ray& ray, Skip skip) const;
  // The same, for coherent rays (Method B's centre rays, all from one
  // point): patch *hint (kNoPatch: none) is tried before the walk, and the
  // patch that occluded the ray is left in *hint for the next one. The
  // answer is Occluded's wherever the walk agrees with testing every patch
  // (tests/grid_test.cpp), because a hit on any patch is a hit.
  bool Occluded(const Ray& ray, Skip skip, uint32_t* hint) const;

  const Plan& plan() const { return plan_; }
  size_t cellCount() const {
    return static_cast<size_t>(plan_.res[0]) * plan_.res[1] * plan_.res[2];
  }
  size_t bytes() const {
    return cellStart_.bytes() + refs_.bytes() + occupied_.bytes() + planes_.bytes();
  }
  // The built arrays, read-only (tests, statistics): a cell that holds
  // patches takes words cellStart()[c] .. cellStart()[c + 1] - 1 of the
  // references: its header (CellPlaneOf), then its patches in ascending
  // order (CellRefs); an empty cell takes none.
  Span<const uint32_t> cellStart() const { return cellStart_; }
  Span<const uint32_t> CellRefs(size_t c) const {
    uint32_t b = cellStart_[c], e = cellStart_[c + 1];
    return b == e ? Span<const uint32_t>() : Span<const uint32_t>(refs_.data() + b + 1, e - b - 1);
  }
  uint32_t CellPlaneOf(size_t c) const {
    return cellStart_[c] == cellStart_[c + 1] ? kNoPlane : refs_[cellStart_[c]];
  }
  Span<const CellPlane> planes() const { return planes_; }
  // Bit c of word c / 64: cell c holds at least one reference.
  Span<const uint64_t> occupied() const { return occupied_; }

 private:
  // The DDA walk behind Intersect (kAnyHit false) and Occluded (true).
  template <bool kAnyHit>
  bool Walk(const Ray& ray, Skip skip, Hit* hit) const;
  // Every patch, for rays whose origin is too far away for the grid's padding.
  template <bool kAnyHit>
  bool TestAll(const Ray& ray, Skip skip, Hit* hit) const;

  Plan plan_;
  glm::vec3 cellSize_{1.0f};
  glm::vec3 invCellSize_{1.0f};
  Span<uint32_t> cellStart_;
  Span<uint32_t> refs_;
  Span<uint64_t> occupied_;  // bit c: cell c holds a patch
  Span<CellPlane> planes_;

 public:
  // Work done by the walks so far: cells entered plus patches tested or
  // ruled out by their cell's plane (a deterministic count, the same on
  // every machine).
  uint64_t steps() const { return steps_; }
  // Resume (checkpoint.h): the count a checkpoint saved.
  void SetSteps(uint64_t steps) { steps_ = steps; }

 private:
  mutable uint64_t steps_ = 0;
  Span<const PatchGeom> geom_;
  float farLimit_ = 0.0f;  // origins with a coordinate beyond this skip the grid
};

}  // namespace vismask
