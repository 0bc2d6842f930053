// Grid: the SEADS-style grid over one environment's patches: a uniform
// grid whose dense cells hold grids of their own (two levels, Ize et al.'s
// nested grids; Kalojanov et al.'s two-level grids), each walked by the same
// 3D-DDA. Built once at init into flat arrays: per level a bitmap of the
// cells that hold any patch, with the number of occupied cells before each
// of its words (so an occupied cell's rank is that count plus a popcount, and
// an empty cell costs one bit, no offset); per occupied cell of either level
// a record (CellRecord: where its references start, and its header); the
// references themselves, cell by cell, each block of cells (the top grid, or
// one sub-grid) in 16 bits from its least patch index when its indices span
// less than 65536, else in 32 bits; and a small table of planes (CellPlane)
// that lets a ray pass a cell whose patches all lie in one plane without
// reading them. Rays walk it with a 3D-DDA (Amanatides & Woo). Intersect
// finds the closest hit, Occluded stops at the first. The resolution
// follows the patch count and the extent (Cleary et al.: cells per axis = extent * cbrt(density * N
// / volume)); a face of the box that walls lie on is placed just inside an outer layer of cells.
// A top cell that many references fall in (a cluster of small props on a large bare floor) gets a
// sub-grid of its own, its resolution from its own reference count (Nest): its header then names
// the sub-grid (kSubGrid | index), whose cells are laid out like the top ones (their own bitmap,
// records after the top cells', references after theirs). The walk enters it between
// the top cell's entry and exit and steps its cells the same way, so it visits every cell of
// either level that a ray crosses, and the closest hit is the uniform grid's: the hit with the
// least t, ties broken by a total order (TieWins), whatever the order the cells came in.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <memory>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/patch.h"

namespace vismask {

namespace gridrefs {
struct RefLayout;
}

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
// Only the records some cell's header names are kept, in run order.
struct CellPlane {
  glm::vec3 n{0.0f};
  float dLo = 0.0f;
  float dHi = 0.0f;
  uint32_t first = 0;  // the run: patches first .. first + count - 1
  uint32_t count = 0;
};

// A top cell's own grid: its box (the top cell's, in float as the walk
// computes it), resolution, where its cells start among all sub-grids' cells
// (cell x, y, z is first + (z * res[1] + y) * res[0] + x), and how its
// references are stored (base: 16-bit references hold patch - base; wide:
// 32-bit references hold the patch).
struct SubGrid {
  glm::vec3 lo{0.0f};
  glm::vec3 cellSize{1.0f};
  glm::vec3 invCellSize{1.0f};
  int32_t res[3] = {1, 1, 1};
  uint32_t first = 0;
  uint32_t base = 0;
  uint32_t wide = 0;
};

// An occupied cell of either level: where its references start (in 16-bit
// units of the reference stream; they end where the next record's start)
// and its header: a CellPlane index, kNoPlane, or (a top cell) kSubGrid |
// its sub-grid's index.
struct CellRecord {
  uint32_t start = 0;
  uint32_t header = 0;
};

// The patches of one cell, decoded from the reference stream (16-bit
// references plus a base, or 32-bit ones stored as two 16-bit units).
class RefList {
 public:
  RefList() = default;
  RefList(const uint16_t* units, uint32_t count, uint32_t base, bool wide)
      : units_(units), count_(count), base_(base), wide_(wide) {}
  size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  uint32_t operator[](size_t k) const {
    if (!wide_) return base_ + units_[k];
    return static_cast<uint32_t>(units_[2 * k]) | static_cast<uint32_t>(units_[2 * k + 1]) << 16;
  }
  struct Iterator {
    const RefList* list;
    size_t k;
    uint32_t operator*() const { return (*list)[k]; }
    Iterator& operator++() {
      ++k;
      return *this;
    }
    bool operator!=(const Iterator& o) const { return k != o.k; }
    bool operator==(const Iterator& o) const { return k == o.k; }
  };
  Iterator begin() const { return Iterator{this, 0}; }
  Iterator end() const { return Iterator{this, count_}; }

 private:
  const uint16_t* units_ = nullptr;
  uint32_t count_ = 0;
  uint32_t base_ = 0;
  bool wide_ = false;
};

// Which top cells get a sub-grid (Grid::MakePlan): those with at least
// minRefs references (0: none, a uniform grid) that do not all lie on one
// surface's plane (such a cell is passed whole by a ray leaving the plane,
// CellPlane), at about `density` cells per reference, at most maxRes cells
// per axis. Chosen by the instructions a cosine ray takes and by the bench
// (bench/analysis.md has the figures): 32 nests the furnished interiors'
// dense cells, where a lower bound would also nest the building's and the
// large Cornell boxes' evenly filled cells, costing bytes and a slower walk
// for nothing.
struct GridNest {
  uint32_t minRefs = 32;
  float density = 1.0f;
  int maxRes = 32;
};

class Grid {
 public:
  // A cell's header when its patches share no plane record.
  static constexpr uint32_t kNoPlane = 0xffffffffu;
  // A top cell's header with this bit names its sub-grid (the rest of the
  // word is its index); plane records are numbered below it.
  static constexpr uint32_t kSubGrid = 0x80000000u;
  using Nest = GridNest;
  // What the grid needs, decided at init before any arena exists.
  struct Plan {
    int res[3] = {1, 1, 1};
    uint64_t refs = 0;      // total (cell, patch) references, both levels
    uint64_t units = 0;     // 16-bit units they take (a 32-bit reference takes two)
    uint64_t occupied = 0;  // cells holding a reference (a CellRecord each), both levels
    uint64_t planes = 0;    // CellPlane records some cell's header names
    uint64_t subGrids = 0;  // top cells with a grid of their own
    uint64_t subCells = 0;  // the cells of all sub-grids
    uint32_t topBase = 0;   // the top cells' references: 16-bit from topBase,
    bool topWide = false;   // or 32-bit
    Nest nest;              // the rule that chose them
    Bounds bounds;          // padded box the top cells cover
  };
  // What MakePlan works out on the way to its counts: every patch's cells
  // (init-time heap, about 40 bytes a patch). Build takes it instead of
  // shaping every patch again, when it is given the same patches: a
  // fingerprint of their corners and ray-test data says so.
  class Work {
   public:
    Work();
    ~Work();
    Work(Work&&) noexcept;
    Work& operator=(Work&&) noexcept;
    bool empty() const { return layout_ == nullptr; }

   private:
    friend class Grid;
    std::unique_ptr<gridrefs::RefLayout> layout_;
    uint64_t fingerprint_ = 0;
  };
  // Plans the grid for `patches` with about `density` cells per patch.
  static Plan MakePlan(Span<const Patch> patches, float density, Nest nest = Nest());
  // The same, for patches whose ray-test data is `geom` (what Build will
  // be given), rather than MakePatchGeom of each (twins: TwinGeom). With
  // `work`, keeps there what Build can take.
  static Plan MakePlan(Span<const Patch> patches, Span<const PatchGeom> geom, float density,
                       Nest nest = Nest(), Work* work = nullptr);

  // Carves the arrays from `arena` (also from a measuring arena).
  void Layout(Arena& arena, const Plan& plan);
  // Fills the arrays. `geom` must outlive the grid; indices are into it.
  // Fails (CHECK) unless the patches give exactly the plan's counts. With
  // `work` (MakePlan's) from the same patches, takes it (and leaves it
  // empty) rather than working it out again; from other patches it is
  // ignored.
  void Build(Span<const Patch> patches, Span<const PatchGeom> geom, Work* work = nullptr);

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
    return records_.bytes() + refs_.bytes() + occupied_.bytes() + rank_.bytes() + planes_.bytes() +
           subs_.bytes() + subOccupied_.bytes() + subRank_.bytes();
  }
  // The built arrays, read-only (tests, statistics): a top cell's patches in
  // ascending order (empty for an empty cell and for a cell with a
  // sub-grid) and its header (kNoPlane for an empty cell; SubGridOf); the
  // same for sub-grid cells.
  RefList CellRefs(size_t c) const;
  uint32_t CellPlaneOf(size_t c) const;
  Span<const CellPlane> planes() const { return planes_; }
  // The sub-grid of top cell c, or nullptr.
  const SubGrid* SubGridOf(size_t c) const {
    uint32_t h = CellPlaneOf(c);
    return h != kNoPlane && (h & kSubGrid) ? &subs_[h & ~kSubGrid] : nullptr;
  }
  Span<const SubGrid> subGrids() const { return subs_; }
  // Sub-grid cell s (SubGrid::first + its index in the sub-grid).
  RefList SubCellRefs(size_t s) const;
  uint32_t SubCellPlaneOf(size_t s) const;
  // Whether top cell c, sub-grid cell s, holds a reference (a sub-grid
  // counts for its top cell): its bit in the level's bitmap.
  bool CellOccupied(size_t c) const { return (occupied_[c >> 6] >> (c & 63)) & 1; }
  bool SubCellOccupied(size_t s) const { return (subOccupied_[s >> 6] >> (s & 63)) & 1; }
  // The occupied cells' records, top cells' first, then the sub-grids'
  // cells', and one past the last (where the references end).
  Span<const CellRecord> records() const { return records_; }

 private:
  // The record index of cell i of a level (its bitmap, and the records
  // before each of its words), or -1 for an empty cell.
  static int64_t RecordOf(Span<const uint64_t> bits, Span<const uint32_t> rank, size_t i) {
    const uint64_t w = bits[i >> 6];
    if (!((w >> (i & 63)) & 1)) return -1;
    return rank[i >> 6] + __builtin_popcountll(w & ((uint64_t{1} << (i & 63)) - 1));
  }
  RefList RefsOf(int64_t r, uint32_t base, bool wide) const;

  // A walk's state between its levels: the ray's end (tMax: just past the
  // best hit so far; the ray's other parts never change and are not
  // copied), where the walk stops (the ray's end t1 or the best hit), the
  // best hit, and the patches tested.
  struct WalkState {
    float tMax = 0.0f;
    float t1 = 0.0f;
    float limit = 0.0f;
    uint32_t bestPatch = kNoPatch;
    float bestT = 0.0f;
    bool bestFront = false;
    uint64_t tests = 0;
  };
  // The DDA walk behind Intersect (kAnyHit false) and Occluded (true), the
  // top cells' references 32-bit (kWide) or 16-bit.
  template <bool kAnyHit, bool kWide>
  bool Walk(const Ray& ray, Skip skip, Hit* hit) const;
  template <bool kAnyHit>
  bool WalkAny(const Ray& ray, Skip skip, Hit* hit) const;
  // The patches of one cell (record r: its header and references, 32-bit
  // or 16-bit from base) for ray ray up to st->tMax: true when an any-hit
  // walk is done.
  template <bool kAnyHit, bool kWide>
  bool TestCell(const CellRecord* r, uint32_t base, const Ray& ray, Skip skip, Hit* hit,
                WalkState* st) const;
  // A top cell's sub-grid between t = tEnter and tLeave; adds the cells it
  // entered to *steps.
  template <bool kAnyHit, bool kWide>
  bool WalkSub(const SubGrid& sg, const Ray& ray, const float invD[3], float tEnter, float tLeave,
               Skip skip, Hit* hit, WalkState* st, uint64_t* steps) const;
  template <bool kAnyHit>
  bool EnterSub(const SubGrid& sg, const Ray& ray, const float invD[3], float tEnter, float tLeave,
                Skip skip, Hit* hit, WalkState* st, uint64_t* steps) const;
  // Every patch, for rays whose origin is too far away for the grid's padding.
  template <bool kAnyHit>
  bool TestAll(const Ray& ray, Skip skip, Hit* hit) const;

  Plan plan_;
  glm::vec3 cellSize_{1.0f};
  glm::vec3 invCellSize_{1.0f};
  Span<CellRecord> records_;  // occupied cells of both levels, and one past the last
  Span<uint16_t> refs_;       // the references, in 16-bit units
  Span<uint64_t> occupied_;   // bit c: top cell c holds a patch
  Span<uint32_t> rank_;       // records before each word of occupied_
  Span<CellPlane> planes_;
  Span<SubGrid> subs_;
  Span<uint64_t> subOccupied_;  // bit s: sub-grid cell s holds a patch
  Span<uint32_t> subRank_;      // records before each word of subOccupied_

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
