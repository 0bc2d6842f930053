// What a grid's references are (internal to src/accel/grid.cpp's
// Grid::MakePlan and Grid::Build): the plane runs, the sub-grids the top
// cells get, every cell's reference count and shared plane, and each block's
// reference width. MakePlan counts from it and Build lays out from it, both
// by this code, so the counted bytes are the built ones.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "grid_cells.h"
#include "vismask/accel/grid.h"

namespace vismask::gridrefs {

constexpr uint32_t kNone = 0xffffffffu;

// +1 or -1: the sign that makes the normal's first non-zero component
// positive; 0 for a zero or non-finite normal (which gets no plane record).
inline float NormalSign(const glm::vec3& n) {
  if (!(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z))) return 0.0f;
  for (int a = 0; a < 3; ++a) {
    if (n[a] > 0.0f) return 1.0f;
    if (n[a] < 0.0f) return -1.0f;
  }
  return 0.0f;
}

// Calls visit(CellPlane) for every run of two or more consecutive patches of
// one surface whose normals agree up to sign, bit for bit (CellPlane).
template <typename Visit>
void ForEachPlaneRun(Span<const Patch> patches, Span<const PatchGeom> geom, Visit visit) {
  const size_t n = patches.size();
  size_t i = 0;
  while (i < n) {
    const float sign = NormalSign(geom[i].n);
    CellPlane run;
    run.n = sign * geom[i].n;
    run.dLo = run.dHi = sign * geom[i].d;
    size_t j = i + 1;
    if (sign != 0.0f && std::isfinite(run.dLo)) {
      for (; j < n && patches[j].surface == patches[i].surface; ++j) {
        const float sj = NormalSign(geom[j].n);
        const glm::vec3 nj = sj * geom[j].n;
        const float dj = sj * geom[j].d;
        if (sj == 0.0f || std::memcmp(&nj, &run.n, sizeof nj) != 0 || !std::isfinite(dj)) break;
        run.dLo = std::min(run.dLo, dj);
        run.dHi = std::max(run.dHi, dj);
      }
    }
    if (j - i >= 2) {
      run.first = static_cast<uint32_t>(i);
      run.count = static_cast<uint32_t>(j - i);
      visit(run);
    }
    i = j;
  }
}

// Whether two records are the same plane and range, bit for bit.
inline bool SamePlane(const CellPlane& a, const CellPlane& b) {
  return std::memcmp(&a.n, &b.n, sizeof a.n) == 0 &&
         std::memcmp(&a.dLo, &b.dLo, sizeof a.dLo) == 0 &&
         std::memcmp(&a.dHi, &b.dHi, sizeof a.dHi) == 0;
}

// The sub-grids of a plan's top cells (Grid::Nest), from the references
// each top cell counts.
struct NestLayout {
  std::vector<uint32_t> count;                // references per top cell
  std::vector<uint32_t> sub;                  // top cell -> its sub-grid, or kNone
  std::vector<uint32_t> top;                  // sub-grid -> its top cell
  std::vector<int> res;                       // sub-grid -> 3 cells per axis
  std::vector<gridcells::CellGeometry> geom;  // sub-grid -> its cells, in double
  std::vector<uint64_t> first;  // sub-grid -> its first cell among all sub-grids' cells
  uint64_t subCells = 0;
};

// A block of cells (the top grid's, or one sub-grid's) and its references:
// 16-bit from base when its patch indices span less than 65536, else wide.
struct Block {
  uint32_t lo = kNone;  // its least and greatest patch
  uint32_t hi = 0;
  uint64_t refs = 0;
  uint32_t base() const { return wide() || lo == kNone ? 0 : lo; }
  bool wide() const { return lo != kNone && hi - lo > 0xffffu; }
  uint64_t units() const { return refs * (wide() ? 2 : 1); }
};

// Every cell's references and header, both levels. A cell's `run` is the
// plane run its patches share (that of its lowest patch, when every other
// patch's run has the same plane and range bit for bit), else kNone.
struct RefLayout {
  gridcells::Scale scale;
  gridcells::CellGeometry topGeom;
  NestLayout nest;
  std::vector<CellPlane> runs;
  std::vector<uint32_t> kept;              // run -> its index among the kept records, or kNone
  std::vector<uint32_t> topCount, topRun;  // per top cell (0, kNone with a sub-grid)
  std::vector<uint32_t> subCount, subRun;  // per sub-grid cell
  Block top;
  std::vector<Block> sub;        // per sub-grid
  std::vector<uint64_t> pairs;   // every (top cell << 32 | patch) registration, in patch order
  std::vector<uint32_t> nested;  // the patches registered in a top cell with a sub-grid
  uint64_t refs = 0, units = 0, occupied = 0, planes = 0;
};
void MakeRefLayout(Span<const Patch> patches, Span<const PatchGeom> geom, const Grid::Plan& plan,
                   RefLayout* out);

// Calls top(i, c) for every top cell c without a sub-grid that patch i is
// registered in, and sub(i, g, s) for every cell s (numbered across all
// sub-grids) of sub-grid g it is registered in; within either, patches in
// ascending order. The top cells' come from rl.pairs; only the patches in
// cells with a sub-grid are shaped again, for the sub-grids' cells.
template <typename Top, typename Sub>
void ForEachRef(Span<const Patch> patches, Span<const PatchGeom> geom, const RefLayout& rl, Top top,
                Sub sub) {
  const NestLayout& nl = rl.nest;
  for (uint64_t pc : rl.pairs) {
    const size_t c = static_cast<size_t>(pc >> 32);
    if (nl.sub[c] == kNone) top(static_cast<size_t>(static_cast<uint32_t>(pc)), c);
  }
  gridcells::Shape shape;
  for (uint32_t i : rl.nested) {
    gridcells::MakeShape(patches[i], geom[i], rl.scale, &shape);
    gridcells::ForEachCell(rl.topGeom, shape, [&](size_t c) {
      const uint32_t g = nl.sub[c];
      if (g == kNone) return;
      const uint64_t first = nl.first[g];
      gridcells::ForEachCell(nl.geom[g], shape, [&](size_t l) { sub(i, g, first + l); });
    });
  }
}

}  // namespace vismask::gridrefs
