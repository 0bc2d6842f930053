#include "vismask/accel/grid.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>
#include <limits>
#include <vector>

#include "grid_cells.h"

namespace vismask {

namespace {

using gridcells::CellGeometry;
using gridcells::CellGeometryOf;
using gridcells::ForEachCell;
using gridcells::MakeShape;
using gridcells::Scale;
using gridcells::ScaleOf;
using gridcells::Shape;

constexpr int kMaxRes = 1024;        // cells per axis
constexpr double kBoundsRel = 1e-3;  // grid margin, relative to the largest extent
constexpr double kWallReach = 0.25;  // a wall lies within this many cells of its face
constexpr double kWallCos = 0.9;     // and faces along the axis (within ~25 degrees)
constexpr size_t kWallShare = 64;    // a face is a wall's when 1/64 of the patches are on it
constexpr double kWallPast = 8.0;    // pads between a wall and the next cell plane

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

constexpr uint32_t kNoSub = 0xffffffffu;

// The sub-grids a plan's top cells get (Grid::Nest), decided from the
// references each top cell counts: MakePlan and Build both run this, so
// they lay out the same cells.
struct NestLayout {
  std::vector<uint32_t> count;     // references per top cell
  std::vector<uint32_t> sub;       // top cell -> its sub-grid, or kNoSub
  std::vector<uint32_t> top;       // sub-grid -> its top cell
  std::vector<int> res;            // sub-grid -> 3 cells per axis
  std::vector<CellGeometry> geom;  // sub-grid -> its cells, in double
  std::vector<uint64_t> first;     // sub-grid -> its first cell among all sub-grids' cells
  uint64_t subCells = 0;
};

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

void PlanNest(Span<const Patch> patches, Span<const PatchGeom> geom, const Scale& scale,
              const CellGeometry& top, const Grid::Nest& nest, NestLayout* out) {
  const size_t cells = static_cast<size_t>(top.res[0]) * top.res[1] * top.res[2];
  out->count.assign(cells, 0);
  out->sub.assign(cells, kNoSub);
  // Each patch's plane run (ForEachPlaneRun), and each cell's: the run all
  // its patches belong to, kNoSub for none yet, kMixed for several or none.
  constexpr uint32_t kMixed = kNoSub - 1;
  std::vector<uint32_t> runOf(nest.minRefs ? patches.size() : 0, kMixed), cellRun;
  if (nest.minRefs) {
    uint32_t runs = 0;
    ForEachPlaneRun(patches, geom, [&](const CellPlane& run) {
      for (uint32_t k = 0; k < run.count; ++k) runOf[run.first + k] = runs;
      ++runs;
    });
    cellRun.assign(cells, kNoSub);
  }
  Shape shape;
  for (size_t i = 0; i < patches.size(); ++i) {
    MakeShape(patches[i], geom[i], scale, &shape);
    ForEachCell(top, shape, [&](size_t c) {
      ++out->count[c];
      if (nest.minRefs) {
        uint32_t& r = cellRun[c];
        r = r == kNoSub || r == runOf[i] ? runOf[i] : kMixed;
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

// Calls top(i, c) for every top cell c without a sub-grid that patch i is
// registered in, and sub(i, s) for every sub-grid cell s (numbered across
// all sub-grids) it is registered in; patches in ascending order.
template <typename Top, typename Sub>
void ForEachRef(Span<const Patch> patches, Span<const PatchGeom> geom, const Scale& scale,
                const CellGeometry& topGeom, const NestLayout& nl, Top top, Sub sub) {
  Shape shape;
  for (size_t i = 0; i < patches.size(); ++i) {
    MakeShape(patches[i], geom[i], scale, &shape);
    ForEachCell(topGeom, shape, [&](size_t c) {
      const uint32_t s = nl.sub[c];
      if (s == kNoSub) {
        top(i, c);
        return;
      }
      const uint64_t first = nl.first[s];
      ForEachCell(nl.geom[s], shape, [&](size_t l) { sub(i, first + l); });
    });
  }
}

}  // namespace

Grid::Plan Grid::MakePlan(Span<const Patch> patches, float density, Nest nest) {
  std::vector<PatchGeom> geom(patches.size());
  for (size_t i = 0; i < patches.size(); ++i) geom[i] = MakePatchGeom(patches[i]);
  return MakePlan(patches, Span<const PatchGeom>(geom.data(), geom.size()), density, nest);
}

Grid::Plan Grid::MakePlan(Span<const Patch> patches, Span<const PatchGeom> geom, float density,
                          Nest nest) {
  CHECK(patches.size() == geom.size());
  CHECK_MSG(density > 0.0f && std::isfinite(density), "grid density must be positive");
  CHECK_MSG(nest.minRefs == 0 || (nest.density > 0.0f && std::isfinite(nest.density) &&
                                  nest.maxRes >= 1 && nest.maxRes <= kMaxRes),
            "sub-grid density must be positive");
  Plan plan;
  plan.nest = nest;
  size_t n = patches.size();
  if (n == 0) {
    plan.bounds.hi = glm::vec3(1.0f);
    return plan;
  }
  Scale scale = ScaleOf(patches);

  // Bounds: every patch's registration box, plus a margin on every side so a
  // flat scene gets some thickness.
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo.x);
  Shape shape;
  for (size_t i = 0; i < n; ++i) {
    MakeShape(patches[i], geom[i], scale, &shape);
    lo = glm::min(lo, shape.lo);
    hi = glm::max(hi, shape.hi);
  }
  glm::dvec3 extent = hi - lo;
  double maxExtent = std::max({extent.x, extent.y, extent.z});
  if (!(maxExtent > 0.0)) maxExtent = 1.0;
  double margin = kBoundsRel * maxExtent;
  for (int a = 0; a < 3; ++a) {
    plan.bounds.lo[a] = std::nextafter(static_cast<float>(lo[a] - margin), -HUGE_VALF);
    plan.bounds.hi[a] = std::nextafter(static_cast<float>(hi[a] + margin), HUGE_VALF);
    extent[a] = static_cast<double>(plan.bounds.hi[a]) - plan.bounds.lo[a];
  }

  // Resolution (Cleary): cells per axis = extent * cbrt(density * N / volume).
  double volume = extent.x * extent.y * extent.z;
  double k = std::cbrt(density * static_cast<double>(n) / volume);
  for (int a = 0; a < 3; ++a)
    plan.res[a] = static_cast<int>(std::clamp(std::round(extent[a] * k), 1.0, double{kMaxRes}));
  double limit = 8.0 * static_cast<double>(n) + 64.0;
  for (;;) {
    double cells = static_cast<double>(plan.res[0]) * plan.res[1] * plan.res[2];
    if (cells <= limit) break;
    double shrink = std::cbrt(limit / cells);
    for (int a = 0; a < 3; ++a)
      plan.res[a] = std::max(1, static_cast<int>(std::floor(plan.res[a] * shrink)));
  }

  // Walls on the box: a face of the box that many patches lie on (a floor,
  // a wall, not necessarily flat) is put just inside an outer layer of cells,
  // keeping the number of cells, so that those patches are registered in that
  // layer only and a ray leaving or reaching one of them crosses a sliver of
  // it, instead of a whole layer of cells each holding several of the wall's
  // patches. Only speed depends on this: registration is conservative
  // whatever the bounds.
  for (int a = 0; a < 3; ++a) {
    double reach = kWallReach * (hi[a] - lo[a]) / plan.res[a];
    size_t onLo = 0, onHi = 0;
    double deepLo = lo[a], deepHi = hi[a];  // how far in those patches reach
    for (const Patch& p : patches) {
      if (!(std::fabs(p.normal[a]) >= kWallCos)) continue;
      float cLo = p.corner[0][a], cHi = cLo;
      for (uint32_t k = 1; k < p.numCorners && k < 4; ++k) {
        cLo = std::min(cLo, p.corner[k][a]);
        cHi = std::max(cHi, p.corner[k][a]);
      }
      if (cHi <= lo[a] + reach) {
        ++onLo;
        deepLo = std::max(deepLo, double{cHi});
      }
      if (cLo >= hi[a] - reach) {
        ++onHi;
        deepHi = std::min(deepHi, double{cLo});
      }
    }
    int wallLo = onLo * kWallShare >= n, wallHi = onHi * kWallShare >= n;
    if (wallLo + wallHi == 0 || plan.res[a] <= wallLo + wallHi) continue;
    // The interior cells start just past the walls' registration (a few
    // pads and the margin); each wall's layer is one more cell beyond.
    double past = kWallPast * scale.pad + margin;
    double inLo = wallLo ? deepLo + past : lo[a] - margin;
    double inHi = wallHi ? deepHi - past : hi[a] + margin;
    double size = (inHi - inLo) / (plan.res[a] - wallLo - wallHi);
    if (!(size > 2.0 * past)) continue;
    plan.bounds.lo[a] = std::nextafter(static_cast<float>(inLo - wallLo * size), -HUGE_VALF);
    plan.bounds.hi[a] = std::nextafter(static_cast<float>(inHi + wallHi * size), HUGE_VALF);
  }

  // Exact reference and occupied-cell counts, by the same rule Build uses:
  // the top cells' references, the sub-grids they decide, then the
  // references in those.
  CellGeometry cellGeom = CellGeometryOf(plan);
  NestLayout nl;
  PlanNest(patches, geom, scale, cellGeom, nest, &nl);
  std::vector<uint32_t> subCount(static_cast<size_t>(nl.subCells), 0);
  uint64_t refs = 0, occupied = 0;
  ForEachRef(
      patches, geom, scale, cellGeom, nl, [&](size_t, size_t) { ++refs; },
      [&](size_t, uint64_t c) { ++subCount[c]; });
  for (uint32_t count : nl.count) occupied += count > 0;
  for (uint32_t count : subCount) {
    refs += count;
    occupied += count > 0;
  }
  plan.subGrids = nl.top.size();
  plan.subCells = nl.subCells;
  plan.refs = refs;
  plan.occupied = occupied;
  ForEachPlaneRun(patches, geom, [&plan](const CellPlane&) { ++plan.planes; });
  return plan;
}

void Grid::Layout(Arena& arena, const Plan& plan) {
  plan_ = plan;
  size_t cells = cellCount();
  CHECK_MSG(cells < 0xffffffffu && plan.subCells < 0x7fffffffu &&
                plan.refs + plan.occupied < 0xffffffffu && plan.planes < kSubGrid &&
                plan.subGrids < kNoPlane - kSubGrid,
            "grid too large for 32-bit offsets");
  cellStart_ = arena.Alloc<uint32_t>(cells + 1);
  refs_ = arena.Alloc<uint32_t>(static_cast<size_t>(plan.refs + plan.occupied));
  occupied_ = arena.Alloc<uint64_t>((cells + 63) / 64);
  planes_ = arena.Alloc<CellPlane>(static_cast<size_t>(plan.planes));
  // A uniform grid (no sub-grid) takes no more than it took before nesting.
  if (plan.subGrids > 0) {
    subs_ = arena.Alloc<SubGrid>(static_cast<size_t>(plan.subGrids));
    subStart_ = arena.Alloc<uint32_t>(static_cast<size_t>(plan.subCells) + 1);
    subOccupied_ = arena.Alloc<uint64_t>(static_cast<size_t>((plan.subCells + 63) / 64));
  } else {
    subs_ = Span<SubGrid>();
    subStart_ = Span<uint32_t>();
    subOccupied_ = Span<uint64_t>();
  }
  for (int a = 0; a < 3; ++a) {
    float extent = plan.bounds.hi[a] - plan.bounds.lo[a];
    cellSize_[a] = extent / static_cast<float>(plan.res[a]);
    invCellSize_[a] = static_cast<float>(plan.res[a]) / extent;
  }
}

void Grid::Build(Span<const Patch> patches, Span<const PatchGeom> geom) {
  CHECK(patches.size() == geom.size());
  CHECK_MSG(cellStart_.data() != nullptr, "Grid::Build needs a real arena");
  geom_ = geom;
  Scale scale = ScaleOf(patches);
  farLimit_ = scale.farLimit;
  CellGeometry cellGeom = CellGeometryOf(plan_);
  size_t cells = cellCount();
  uint32_t* start = cellStart_.data();

  // The plane records, in patch order.
  size_t numPlanes = 0;
  ForEachPlaneRun(patches, geom, [&](const CellPlane& run) {
    CHECK(numPlanes < planes_.size());
    planes_[numPlanes++] = run;
  });
  CHECK_MSG(numPlanes == planes_.size(), "grid plan does not match the patches it is built from");

  // The sub-grids, as MakePlan decided them.
  NestLayout nl;
  PlanNest(patches, geom, scale, cellGeom, plan_.nest, &nl);
  CHECK_MSG(nl.top.size() == plan_.subGrids && nl.subCells == plan_.subCells,
            "grid plan does not match the patches it is built from");
  for (size_t g = 0; g < nl.top.size(); ++g) {
    SubGrid& sg = subs_[g];
    for (int a = 0; a < 3; ++a) {
      sg.lo[a] = static_cast<float>(nl.geom[g].lo[a]);
      sg.cellSize[a] = static_cast<float>(nl.geom[g].size[a]);
      sg.invCellSize[a] = static_cast<float>(nl.geom[g].inv[a]);
      sg.res[a] = nl.res[3 * g + a];
    }
    sg.first = static_cast<uint32_t>(nl.first[g]);
  }

  // Counting sort, level by level: the top cells' words (a header before an
  // occupied cell's patches; a cell with a sub-grid has its header only),
  // then the sub-grids' cells', each cell filled in patch order.
  const size_t subCells = static_cast<size_t>(nl.subCells);
  std::vector<uint32_t> subCount(subCells, 0);
  uint64_t total = 0;
  ForEachRef(
      patches, geom, scale, cellGeom, nl, [&](size_t, size_t) { ++total; },
      [&](size_t, uint64_t c) {
        ++subCount[c];
        ++total;
      });
  CHECK_MSG(total == plan_.refs, "grid plan does not match the patches it is built from");
  uint32_t* refs = refs_.data();
  std::vector<uint32_t> fillTop(cells), fillSub(subCells);
  uint32_t sum = 0;
  for (size_t c = 0; c < cells; ++c) {
    start[c] = sum;
    fillTop[c] = sum + 1;
    if (nl.sub[c] != kNoSub)
      sum += 1;
    else if (nl.count[c] > 0)
      sum += 1 + nl.count[c];
  }
  start[cells] = sum;
  for (size_t c = 0; c < subCells; ++c) {
    subStart_[c] = sum;
    fillSub[c] = sum + 1;
    if (subCount[c] > 0) sum += 1 + subCount[c];
  }
  if (subCells) subStart_[subCells] = sum;
  CHECK_MSG(sum == plan_.refs + plan_.occupied,
            "grid plan does not match the patches it is built from");
  ForEachRef(
      patches, geom, scale, cellGeom, nl,
      [&](size_t i, size_t c) { refs[fillTop[c]++] = static_cast<uint32_t>(i); },
      [&](size_t i, uint64_t c) { refs[fillSub[c]++] = static_cast<uint32_t>(i); });

  // Each occupied cell's header: the plane record all its patches share, if
  // any; a top cell's sub-grid.
  const CellPlane* planes = planes_.data();
  auto recordOf = [&](uint32_t p) -> const CellPlane* {
    const CellPlane* r = std::upper_bound(
        planes, planes + numPlanes, p, [](uint32_t q, const CellPlane& c) { return q < c.first; });
    if (r == planes) return nullptr;
    --r;
    return p - r->first < r->count ? r : nullptr;
  };
  auto header = [&](uint32_t b, uint32_t e) {
    const CellPlane* shared = recordOf(refs[b + 1]);
    for (uint32_t k = b + 2; k < e && shared; ++k) {
      const CellPlane* r = recordOf(refs[k]);
      if (!r || !SamePlane(*r, *shared)) shared = nullptr;
    }
    refs[b] = shared ? static_cast<uint32_t>(shared - planes) : kNoPlane;
  };
  uint64_t* occupied = occupied_.data();
  for (size_t w = 0; w < occupied_.size(); ++w) occupied[w] = 0;
  for (size_t c = 0; c < cells; ++c) {
    if (start[c + 1] == start[c]) continue;
    occupied[c >> 6] |= uint64_t{1} << (c & 63);
    if (nl.sub[c] != kNoSub)
      refs[start[c]] = kSubGrid | nl.sub[c];
    else
      header(start[c], start[c + 1]);
  }
  uint64_t* subOccupied = subOccupied_.data();
  for (size_t w = 0; w < subOccupied_.size(); ++w) subOccupied[w] = 0;
  for (size_t c = 0; c < subCells; ++c) {
    if (subStart_[c + 1] == subStart_[c]) continue;
    subOccupied[c >> 6] |= uint64_t{1} << (c & 63);
    header(subStart_[c], subStart_[c + 1]);
  }
}

}  // namespace vismask
