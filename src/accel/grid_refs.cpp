#include "grid_refs.h"

namespace vismask::gridrefs {

using gridcells::CellGeometry;
using gridcells::ForEachCell;
using gridcells::MakeShape;
using gridcells::Scale;
using gridcells::Shape;

namespace {

// The cells of top cell c split res[0] x res[1] x res[2].
CellGeometry SubGeometry(const CellGeometry& top, size_t c, const int res[3]) {
  const size_t at[3] = {c % top.res[0], (c / top.res[0]) % top.res[1],
                        c / (static_cast<size_t>(top.res[0]) * top.res[1])};
  CellGeometry g;
  for (int a = 0; a < 3; ++a) {
    g.lo[a] = top.lo[a] + static_cast<double>(at[a]) * top.size[a];
    g.res[a] = res[a];
    g.size[a] = top.size[a] / res[a];
    g.inv[a] = res[a] / top.size[a];
  }
  return g;
}

// The top cells' reference counts and the sub-grids they decide; each
// (top cell, patch) registration into *pairs (cell << 32 | patch), in patch
// order, so that no later pass shapes a patch again for its top cells.
void PlanNest(Span<const Patch> patches, Span<const PatchGeom> geom, const Scale& scale,
              const CellGeometry& top, const Grid::Nest& nest, NestLayout* out,
              std::vector<uint64_t>* pairs) {
  const size_t cells = static_cast<size_t>(top.res[0]) * top.res[1] * top.res[2];
  out->count.assign(cells, 0);
  out->sub.assign(cells, kNone);
  // Each patch's plane run (ForEachPlaneRun), and each cell's: the run all
  // its patches belong to, kNone for none yet, kMixed for several or none.
  constexpr uint32_t kMixed = kNone - 1;
  std::vector<uint32_t> runOf(nest.minRefs ? patches.size() : 0, kMixed), cellRun;
  if (nest.minRefs) {
    uint32_t runs = 0;
    ForEachPlaneRun(patches, geom, [&](const CellPlane& run) {
      for (uint32_t k = 0; k < run.count; ++k) runOf[run.first + k] = runs;
      ++runs;
    });
    cellRun.assign(cells, kNone);
  }
  Shape shape;
  for (size_t i = 0; i < patches.size(); ++i) {
    MakeShape(patches[i], geom[i], scale, &shape);
    ForEachCell(top, shape, [&](size_t c) {
      ++out->count[c];
      pairs->push_back(static_cast<uint64_t>(c) << 32 | i);
      if (nest.minRefs) {
        uint32_t& r = cellRun[c];
        r = r == kNone || r == runOf[i] ? runOf[i] : kMixed;
      }
    });
  }
  if (nest.minRefs == 0) return;
  // Cleary's rule again, inside the cell: about nest.density cells per
  // reference, shaped like the cell.
  const double volume = top.size.x * top.size.y * top.size.z;
  for (size_t c = 0; c < cells; ++c) {
    // A cell of one surface's plane is passed whole by a ray leaving it
    // (CellPlane): it keeps its patches.
    if (out->count[c] < nest.minRefs || cellRun[c] != kMixed) continue;
    double k = std::cbrt(nest.density * static_cast<double>(out->count[c]) / volume);
    int res[3];
    for (int a = 0; a < 3; ++a)
      res[a] = static_cast<int>(
          std::clamp(std::round(top.size[a] * k), 1.0, static_cast<double>(nest.maxRes)));
    const uint64_t n = static_cast<uint64_t>(res[0]) * res[1] * res[2];
    if (n == 1) continue;
    out->sub[c] = static_cast<uint32_t>(out->top.size());
    out->top.push_back(static_cast<uint32_t>(c));
    out->res.insert(out->res.end(), res, res + 3);
    out->geom.push_back(SubGeometry(top, c, res));
    out->first.push_back(out->subCells);
    out->subCells += n;
  }
}

// A cell's shared run after patch i (run q, or kNone) joins it: the first
// patch's run while every later one has the same plane and range.
constexpr uint32_t kUnseen = kNone - 1;
inline void JoinRun(const std::vector<CellPlane>& runs, uint32_t q, uint32_t* cell) {
  if (*cell == kUnseen)
    *cell = q;
  else if (*cell != kNone && (q == kNone || (q != *cell && !SamePlane(runs[q], runs[*cell]))))
    *cell = kNone;
}

inline void Add(Block* b, uint32_t p) {
  b->lo = std::min(b->lo, p);
  b->hi = std::max(b->hi, p);
  ++b->refs;
}

}  // namespace

void MakeRefLayout(Span<const Patch> patches, Span<const PatchGeom> geom, const Grid::Plan& plan,
                   RefLayout* out) {
  out->scale = gridcells::ScaleOf(patches);
  out->topGeom = gridcells::CellGeometryOf(plan);
  out->pairs.clear();
  PlanNest(patches, geom, out->scale, out->topGeom, plan.nest, &out->nest, &out->pairs);
  const NestLayout& nl = out->nest;
  // The patches registered in a cell with a sub-grid, which ForEachRef
  // shapes again for its cells.
  out->nested.clear();
  for (uint64_t pc : out->pairs) {
    const uint32_t i = static_cast<uint32_t>(pc);
    if (nl.sub[pc >> 32] != kNone && (out->nested.empty() || out->nested.back() != i))
      out->nested.push_back(i);
  }
  // The plane runs, and each patch's.
  std::vector<uint32_t> runOf(patches.size(), kNone);
  out->runs.clear();
  ForEachPlaneRun(patches, geom, [&](const CellPlane& run) {
    for (uint32_t k = 0; k < run.count; ++k)
      runOf[run.first + k] = static_cast<uint32_t>(out->runs.size());
    out->runs.push_back(run);
  });
  const size_t cells = nl.count.size(), subCells = static_cast<size_t>(nl.subCells);
  out->topCount.assign(cells, 0);
  out->topRun.assign(cells, kUnseen);
  out->subCount.assign(subCells, 0);
  out->subRun.assign(subCells, kUnseen);
  out->top = Block();
  out->sub.assign(nl.top.size(), Block());
  ForEachRef(
      patches, geom, *out,
      [&](size_t i, size_t c) {
        ++out->topCount[c];
        JoinRun(out->runs, runOf[i], &out->topRun[c]);
        Add(&out->top, static_cast<uint32_t>(i));
      },
      [&](size_t i, uint32_t g, uint64_t s) {
        ++out->subCount[s];
        JoinRun(out->runs, runOf[i], &out->subRun[s]);
        Add(&out->sub[g], static_cast<uint32_t>(i));
      });
  // The records some occupied cell names, in run order.
  std::vector<char> used(out->runs.size(), 0);
  out->occupied = 0;
  for (size_t c = 0; c < cells; ++c) {
    uint32_t& r = out->topRun[c];
    if (r == kUnseen) r = kNone;
    if (r != kNone) used[r] = 1;
    out->occupied += out->topCount[c] > 0 || nl.sub[c] != kNone;
  }
  for (size_t c = 0; c < subCells; ++c) {
    uint32_t& r = out->subRun[c];
    if (r == kUnseen) r = kNone;
    if (r != kNone) used[r] = 1;
    out->occupied += out->subCount[c] > 0;
  }
  out->kept.assign(out->runs.size(), kNone);
  out->planes = 0;
  for (size_t r = 0; r < used.size(); ++r)
    if (used[r]) out->kept[r] = static_cast<uint32_t>(out->planes++);
  out->refs = out->top.refs;
  out->units = out->top.units();
  for (const Block& b : out->sub) {
    out->refs += b.refs;
    out->units += b.units();
  }
}

}  // namespace vismask::gridrefs
