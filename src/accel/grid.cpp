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

// Of two hits at the same t, whether patch p (side `front`) beats `best`:
// a front side beats a back side, then the lower index wins. A total order
// (so the walk's cell order cannot matter): of two coplanar twins, whose t
// is bit-identical (patch.h, TwinGeom), the ray lands on the one it faces.
// Runs on exact ties only, off the walk's hot path.
inline bool TieWins(uint32_t p, bool front, uint32_t best, bool bestFront) {
  return front != bestFront ? front : p < best;
}

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

template <bool kAnyHit>
bool Grid::TestAll(const Ray& ray, Skip skip, Hit* hit) const {
  const PatchGeom* geom = geom_.data();
  uint32_t n = static_cast<uint32_t>(geom_.size());
  Hit best;
  best.t = ray.tMax;
  for (uint32_t p = 0; p < n; ++p) {
    float t;
    bool front;
    if (p == skip.patch || p == skip.twin || !IntersectPatch(geom[p], ray, &t, &front)) continue;
    if (kAnyHit) {
      if (hit) hit->patch = p;
      return true;
    }
    // The nearest; of equal t, TieWins (patches rise with p).
    if (best.patch == kNoPatch || t < best.t ||
        (t == best.t && TieWins(p, front, best.patch, best.front)))
      best = Hit{p, t, front};
  }
  if (best.patch == kNoPatch) return false;
  *hit = best;
  return true;
}

template <bool kAnyHit>
bool Grid::Walk(const Ray& ray, Skip skip, Hit* hit) const {
  DCHECK(cellStart_.data() != nullptr);  // built
  if (!(ray.tMin < ray.tMax)) return false;
  const float o[3] = {ray.o.x, ray.o.y, ray.o.z};
  const float d[3] = {ray.d.x, ray.d.y, ray.d.z};
  if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f) return false;
  if (!(std::fabs(o[0]) <= farLimit_ && std::fabs(o[1]) <= farLimit_ &&
        std::fabs(o[2]) <= farLimit_))
    return TestAll<kAnyHit>(ray, skip, hit);

  // Clip (tMin, tMax) to the grid box; an axis the ray does not move along
  // must already hold the origin. A direction so small that its inverse
  // overflows has no usable DDA: every patch is tested instead.
  const glm::vec3& lo = plan_.bounds.lo;
  const glm::vec3& hi = plan_.bounds.hi;
  float invD[3];
  float t0 = ray.tMin, t1 = ray.tMax;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0f) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      invD[a] = 0.0f;
      continue;
    }
    invD[a] = 1.0f / d[a];
    if (!(std::fabs(invD[a]) <= std::numeric_limits<float>::max()))
      return TestAll<kAnyHit>(ray, skip, hit);
    float tNear = (lo[a] - o[a]) * invD[a];
    float tFar = (hi[a] - o[a]) * invD[a];
    if (tNear > tFar) std::swap(tNear, tFar);
    if (tNear > t0) t0 = tNear;
    if (tFar < t1) t1 = tFar;
  }
  if (!(t0 <= t1)) return false;

  // Entry cell, and per axis the cell planes ahead: the k-th (k = 0, 1, ...)
  // is crossed at first + k * delta, a product and a sum per step that is
  // never accumulated, so its error stays a few ulps of the scene magnitude,
  // far inside the registration padding. The plane where the ray leaves the
  // grid bounds t1 by the same formula (same bits, and the formula grows with
  // k), so no step can take the walk out of the grid.
  const int* res = plan_.res;
  const int stride[3] = {1, res[0], res[0] * res[1]};
  float first[3], delta[3];
  int move[3];
  int index = 0;
  for (int a = 0; a < 3; ++a) {
    float p = d[a] == 0.0f ? o[a] : o[a] + t0 * d[a];
    float f = (p - lo[a]) * invCellSize_[a];
    int c = f >= 0.0f ? (f < static_cast<float>(res[a]) ? static_cast<int>(f) : res[a] - 1) : 0;
    index += c * stride[a];
    if (d[a] == 0.0f) {
      first[a] = std::numeric_limits<float>::infinity();
      delta[a] = 0.0f;
      move[a] = 0;
      continue;
    }
    bool up = d[a] > 0.0f;
    first[a] = (lo[a] + static_cast<float>(up ? c + 1 : c) * cellSize_[a] - o[a]) * invD[a];
    delta[a] = cellSize_[a] * std::fabs(invD[a]);
    move[a] = up ? stride[a] : -stride[a];
    float exit = first[a] + static_cast<float>(up ? res[a] - 1 - c : c) * delta[a];
    if (exit < t1) t1 = exit;
  }
  // Per axis in registers: the next plane's t, and how many were crossed.
  const float fx = first[0], fy = first[1], fz = first[2];
  const float dx = delta[0], dy = delta[1], dz = delta[2];
  float tx = fx, ty = fy, tz = fz;
  float kx = 0.0f, ky = 0.0f, kz = 0.0f;

  const uint32_t* start = cellStart_.data();
  const uint64_t* occupied = occupied_.data();
  WalkState st;
  st.r = ray;  // tMax shrinks to just past the best hit so far
  st.t1 = t1;
  st.limit = t1;          // no step into a cell beyond this: the ray's end or the best hit
  st.bestT = ray.tMax;    // every hit is nearer than the ray's end
  uint64_t subSteps = 0;  // sub-grid cells entered
  auto done = [&] { steps_ += st.tests + subSteps + static_cast<uint64_t>(kx + ky + kz) + 1; };
  for (;;) {
    // Most cells a ray crosses are empty: one bit in a small bitmap says so,
    // where their offsets (32 times larger, strided by rows and slices) cost
    // a cache miss each in a large grid.
    if (((occupied[static_cast<uint32_t>(index) >> 6] >> (index & 63)) & 1) != 0) {
      const uint32_t b = start[index];
      const uint32_t header = refs_.data()[b];
      // kSubGrid .. kNoPlane - 1: a sub-grid.
      if (__builtin_expect(header - kSubGrid < kNoPlane - kSubGrid, 0)) {
        // Where the ray entered the top cell: the last plane it crossed, by
        // the steps' own formula (t0 if none); and where it leaves it.
        float tEnter = t0;
        if (kx > 0.0f) tEnter = std::max(tEnter, fx + (kx - 1.0f) * dx);
        if (ky > 0.0f) tEnter = std::max(tEnter, fy + (ky - 1.0f) * dy);
        if (kz > 0.0f) tEnter = std::max(tEnter, fz + (kz - 1.0f) * dz);
        const float tLeave = std::min(std::min(tx, ty), tz);
        // A copy goes out of line: the walk's own state never leaves this
        // function, so it stays in registers.
        WalkState sub = st;
        const bool found = WalkSub<kAnyHit>(subs_.data()[header - kSubGrid], invD, tEnter, tLeave,
                                            skip, hit, &sub, &subSteps);
        st = sub;
        if (found) {
          done();
          return true;
        }
      } else if (TestCell<kAnyHit>(b, start[index + 1], skip, hit, &st)) {
        done();
        return true;
      }
    }
    // Step across the plane that comes first (ties: y before x, z before
    // both), unless the ray ends, or its best hit is, before that plane.
    if (tx < ty && tx < tz) {
      if (!(tx < st.limit)) break;
      index += move[0];
      kx += 1.0f;
      tx = fx + kx * dx;
    } else if (ty < tz) {
      if (!(ty < st.limit)) break;
      index += move[1];
      ky += 1.0f;
      ty = fy + ky * dy;
    } else {
      if (!(tz < st.limit)) break;
      index += move[2];
      kz += 1.0f;
      tz = fz + kz * dz;
    }
  }
  done();
  if (st.bestPatch == kNoPatch) return false;
  hit->patch = st.bestPatch;
  hit->t = st.bestT;
  hit->front = st.bestFront;
  return true;
}

template <bool kAnyHit>
inline __attribute__((always_inline)) bool Grid::TestCell(uint32_t b, uint32_t e, Skip skip,
                                                          Hit* hit, WalkState* st) const {
  const uint32_t* refs = refs_.data();
  const PatchGeom* geom = geom_.data();
  const uint32_t header = refs[b];
  uint32_t begin = b + 1, end = e;
  if (header != kNoPlane) {
    // The cell's patches share a plane (CellPlane). Each patch test
    // divides num = d - n.o by denom = n.dir; if num is never of
    // denom's sign over the range of d, every t is <= 0 and, with
    // tMin >= 0, every test below would fail its range check: the
    // cell is passed without reading a patch. The products and sums
    // are IntersectPatch's, on the other sign of the normal for some
    // patches, which negates them exactly; no division is needed.
    const CellPlane& pl = planes_.data()[header];
    const Ray& r = st->r;
    float denom = pl.n.x * r.d.x + pl.n.y * r.d.y + pl.n.z * r.d.z;
    float s = pl.n.x * r.o.x + pl.n.y * r.o.y + pl.n.z * r.o.z;
    float numLo = pl.dLo - s, numHi = pl.dHi - s;
    if (denom == 0.0f || (r.tMin >= 0.0f && (denom > 0.0f ? numHi <= 0.0f : numLo >= 0.0f))) {
      st->tests += end - begin;
      return false;
    }
  }
  // Ask for every patch of the cell at once: their cache misses overlap
  // instead of coming one test at a time.
  for (uint32_t k = begin; k < end; ++k) {
    const char* g = reinterpret_cast<const char*>(geom + refs[k]);
    __builtin_prefetch(g);
    __builtin_prefetch(g + sizeof(PatchGeom) - 1);
  }
  for (uint32_t k = begin; k < end; ++k) {
    uint32_t p = refs[k];
    float t;
    bool front;
    ++st->tests;
    if (p == skip.patch || !IntersectPatch(geom[p], st->r, &t, &front) || p == skip.twin) continue;
    if (kAnyHit) {
      if (hit) hit->patch = p;
      return true;
    }
    // t <= bestT here. On a tie a front side, then the lower index, so
    // that of two coplanar twins the ray lands on the one it faces.
    if (t < st->bestT || TieWins(p, front, st->bestPatch, st->bestFront)) {
      st->bestPatch = p;
      st->bestT = t;
      st->bestFront = front;
      st->r.tMax = std::nextafter(t, std::numeric_limits<float>::infinity());
      st->limit = std::min(st->t1, t);
    }
  }
  return false;
}

// A top cell's sub-grid, from where the ray entered the top cell to where it
// leaves it (or to the best hit): the same DDA on the sub-grid's cells, its
// end bounded by the sub-grid's last planes (the same formula, so no step
// leaves it). The sub-grid's planes and the top cell's differ by rounding
// only, far inside the registration padding. Out of line, with its own copy
// of the walk's state, so that the top walk keeps its own in registers.
template <bool kAnyHit>
__attribute__((noinline)) bool Grid::WalkSub(const SubGrid& sg, const float invD[3], float tEnter,
                                             float tLeave, Skip skip, Hit* hit, WalkState* state,
                                             uint64_t* steps) const {
  WalkState st = *state;
  const float o[3] = {st.r.o.x, st.r.o.y, st.r.o.z};
  const float d[3] = {st.r.d.x, st.r.d.y, st.r.d.z};
  const int32_t* res = sg.res;
  const int32_t stride[3] = {1, res[0], res[0] * res[1]};
  float first[3], delta[3];
  int32_t move[3];
  int32_t index = static_cast<int32_t>(sg.first);
  float tEnd = tLeave;
  for (int a = 0; a < 3; ++a) {
    float p = d[a] == 0.0f ? o[a] : o[a] + tEnter * d[a];
    float f = (p - sg.lo[a]) * sg.invCellSize[a];
    int c = f >= 0.0f ? (f < static_cast<float>(res[a]) ? static_cast<int>(f) : res[a] - 1) : 0;
    index += c * stride[a];
    if (d[a] == 0.0f) {
      first[a] = std::numeric_limits<float>::infinity();
      delta[a] = 0.0f;
      move[a] = 0;
      continue;
    }
    bool up = d[a] > 0.0f;
    first[a] = (sg.lo[a] + static_cast<float>(up ? c + 1 : c) * sg.cellSize[a] - o[a]) * invD[a];
    delta[a] = sg.cellSize[a] * std::fabs(invD[a]);
    move[a] = up ? stride[a] : -stride[a];
    float exit = first[a] + static_cast<float>(up ? res[a] - 1 - c : c) * delta[a];
    if (exit < tEnd) tEnd = exit;
  }
  const float fx = first[0], fy = first[1], fz = first[2];
  const float dx = delta[0], dy = delta[1], dz = delta[2];
  float tx = fx, ty = fy, tz = fz;
  float kx = 0.0f, ky = 0.0f, kz = 0.0f;
  const uint32_t* start = subStart_.data();
  const uint64_t* occupied = subOccupied_.data();
  bool done = false;
  for (;;) {
    const uint32_t u = static_cast<uint32_t>(index);
    if (((occupied[u >> 6] >> (u & 63)) & 1) != 0 &&
        TestCell<kAnyHit>(start[u], start[u + 1], skip, hit, &st)) {
      done = true;
      break;
    }
    const float bound = std::min(tEnd, st.limit);
    if (tx < ty && tx < tz) {
      if (!(tx < bound)) break;
      index += move[0];
      kx += 1.0f;
      tx = fx + kx * dx;
    } else if (ty < tz) {
      if (!(ty < bound)) break;
      index += move[1];
      ky += 1.0f;
      ty = fy + ky * dy;
    } else {
      if (!(tz < bound)) break;
      index += move[2];
      kz += 1.0f;
      tz = fz + kz * dz;
    }
  }
  *steps += static_cast<uint64_t>(kx + ky + kz) + 1;
  *state = st;
  return done;
}

bool Grid::Intersect(const Ray& ray, Skip skip, Hit* hit) const {
  return Walk<false>(ray, skip, hit);
}

bool Grid::Occluded(const Ray& ray, Skip skip) const {
  return Walk<true>(ray, skip, nullptr);
}

bool Grid::Occluded(const Ray& ray, Skip skip, uint32_t* hint) const {
  uint32_t h = *hint;
  float t;
  bool front;
  if (h != kNoPatch && h != skip.patch && h != skip.twin &&
      IntersectPatch(geom_[h], ray, &t, &front))
    return true;
  Hit hit;
  if (!Walk<true>(ray, skip, &hit)) return false;
  *hint = hit.patch;
  return true;
}

}  // namespace vismask
