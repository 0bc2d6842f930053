#include "vismask/accel/grid.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>
#include <limits>
#include <vector>

#include "grid_cells.h"
#include "grid_refs.h"

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

// What Grid::Work's layout depends on: the patches' corners and ray-test
// data, as 64-bit words of their float bits (so identical copies agree),
// mixed in four independent lanes (a multiply-xorshift chain each) so the
// multiplies overlap.
uint64_t Fingerprint(Span<const Patch> patches, Span<const PatchGeom> geom) {
  constexpr size_t kWords = (4 * sizeof(glm::vec3) + sizeof(PatchGeom)) / 8;
  static_assert((4 * sizeof(glm::vec3)) % 8 == 0 && sizeof(PatchGeom) % 8 == 0, "whole words");
  uint64_t lane[4] = {0x9e3779b97f4a7c15ull ^ patches.size(), 1, 2, 3};
  for (size_t i = 0; i < patches.size(); ++i) {
    uint64_t w[kWords + 1];
    std::memcpy(w, &patches[i].corner[0], 4 * sizeof(glm::vec3));
    std::memcpy(w + 4 * sizeof(glm::vec3) / 8, &geom[i], sizeof(PatchGeom));
    w[kWords] = patches[i].numCorners;
    for (size_t k = 0; k <= kWords; ++k) {
      uint64_t& h = lane[k & 3];
      h = (h ^ w[k]) * 0xff51afd7ed558ccdull;
      h ^= h >> 29;
    }
  }
  return (lane[0] * 3 + lane[1]) * 5 + (lane[2] * 7 + lane[3]);
}

// Whether two plans' top cells are the same, bit for bit.
bool SameCells(const CellGeometry& a, const CellGeometry& b) {
  for (int k = 0; k < 3; ++k)
    if (a.res[k] != b.res[k] || std::memcmp(&a.lo[k], &b.lo[k], sizeof(double)) != 0 ||
        std::memcmp(&a.size[k], &b.size[k], sizeof(double)) != 0)
      return false;
  return true;
}

}  // namespace

Grid::Work::Work() = default;
Grid::Work::~Work() = default;
Grid::Work::Work(Work&&) noexcept = default;
Grid::Work& Grid::Work::operator=(Work&&) noexcept = default;

Grid::Plan Grid::MakePlan(Span<const Patch> patches, float density, Nest nest) {
  std::vector<PatchGeom> geom(patches.size());
  for (size_t i = 0; i < patches.size(); ++i) geom[i] = MakePatchGeom(patches[i]);
  return MakePlan(patches, Span<const PatchGeom>(geom.data(), geom.size()), density, nest);
}

Grid::Plan Grid::MakePlan(Span<const Patch> patches, Span<const PatchGeom> geom, float density,
                          Nest nest, Work* work) {
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
    MakeShape(patches[i], geom[i], scale, &shape, /*boxOnly=*/true);
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

  // Exact counts, by the same code Build lays the references out with: the
  // top cells' references, the sub-grids they decide, the references in
  // those, each block's width, and the plane records the cells name.
  auto kept = std::make_unique<gridrefs::RefLayout>();
  gridrefs::RefLayout& rl = *kept;
  gridrefs::MakeRefLayout(patches, geom, plan, &rl);
  plan.subGrids = rl.nest.top.size();
  plan.subCells = rl.nest.subCells;
  plan.refs = rl.refs;
  plan.units = rl.units;
  plan.occupied = rl.occupied;
  plan.planes = rl.planes;
  plan.topBase = rl.top.base();
  plan.topWide = rl.top.wide();
  if (work) {
    work->layout_ = std::move(kept);
    work->fingerprint_ = Fingerprint(patches, geom);
  }
  return plan;
}

void Grid::Layout(Arena& arena, const Plan& plan) {
  plan_ = plan;
  size_t cells = cellCount();
  CHECK_MSG(cells < 0xffffffffu && plan.subCells < 0xffffffffu && plan.occupied < 0xffffffffu &&
                plan.units < 0xffffffffu && plan.planes < kSubGrid &&
                plan.subGrids < kNoPlane - kSubGrid,
            "grid too large for 32-bit offsets");
  records_ = arena.Alloc<CellRecord>(static_cast<size_t>(plan.occupied) + 1);
  refs_ = arena.Alloc<uint16_t>(static_cast<size_t>(plan.units));
  occupied_ = arena.Alloc<uint64_t>((cells + 63) / 64);
  rank_ = arena.Alloc<uint32_t>((cells + 63) / 64);
  planes_ = arena.Alloc<CellPlane>(static_cast<size_t>(plan.planes));
  // A uniform grid (no sub-grid) takes nothing for them.
  const size_t subWords = static_cast<size_t>((plan.subCells + 63) / 64);
  subs_ =
      plan.subGrids ? arena.Alloc<SubGrid>(static_cast<size_t>(plan.subGrids)) : Span<SubGrid>();
  subOccupied_ = subWords ? arena.Alloc<uint64_t>(subWords) : Span<uint64_t>();
  subRank_ = subWords ? arena.Alloc<uint32_t>(subWords) : Span<uint32_t>();
  for (int a = 0; a < 3; ++a) {
    float extent = plan.bounds.hi[a] - plan.bounds.lo[a];
    cellSize_[a] = extent / static_cast<float>(plan.res[a]);
    invCellSize_[a] = static_cast<float>(plan.res[a]) / extent;
  }
}

namespace {

// Marks the occupied cells of one level in its bitmap and counts, before
// each word, the records that come before it (from `first`).
void Occupancy(const std::vector<uint32_t>& count, const std::vector<uint32_t>* sub, uint32_t first,
               Span<uint64_t> bits, Span<uint32_t> rank) {
  uint32_t r = first;
  for (size_t c = 0; c < count.size(); ++c) {
    if (c % 64 == 0) {
      bits[c / 64] = 0;
      rank[c / 64] = r;
    }
    if (count[c] == 0 && !(sub && (*sub)[c] != gridrefs::kNone)) continue;
    bits[c >> 6] |= uint64_t{1} << (c & 63);
    ++r;
  }
}

}  // namespace

void Grid::Build(Span<const Patch> patches, Span<const PatchGeom> geom, Work* work) {
  CHECK(patches.size() == geom.size());
  CHECK_MSG(records_.data() != nullptr, "Grid::Build needs a real arena");
  geom_ = geom;
  constexpr const char* kMismatch = "grid plan does not match the patches it is built from";
  // MakePlan's layout when it came from these patches (its counts are then
  // the plan's unless the plan came from elsewhere: checked below).
  std::unique_ptr<gridrefs::RefLayout> taken;
  if (work && !work->empty() && work->fingerprint_ == Fingerprint(patches, geom) &&
      SameCells(work->layout_->topGeom, gridcells::CellGeometryOf(plan_)))
    taken = std::move(work->layout_);
  if (work) *work = Work();
  if (!taken) {
    taken = std::make_unique<gridrefs::RefLayout>();
    gridrefs::MakeRefLayout(patches, geom, plan_, taken.get());
  }
  const gridrefs::RefLayout& rl = *taken;
  farLimit_ = rl.scale.farLimit;  // ScaleOf(patches), as MakeRefLayout worked it out
  const gridrefs::NestLayout& nl = rl.nest;
  CHECK_MSG(nl.top.size() == plan_.subGrids && nl.subCells == plan_.subCells &&
                rl.refs == plan_.refs && rl.units == plan_.units && rl.occupied == plan_.occupied &&
                rl.planes == plan_.planes && rl.top.base() == plan_.topBase &&
                rl.top.wide() == plan_.topWide,
            kMismatch);

  // The plane records the cells name, in run order.
  for (size_t r = 0; r < rl.runs.size(); ++r)
    if (rl.kept[r] != gridrefs::kNone) planes_[rl.kept[r]] = rl.runs[r];

  // The sub-grids, as MakePlan decided them.
  for (size_t g = 0; g < nl.top.size(); ++g) {
    SubGrid& sg = subs_[g];
    for (int a = 0; a < 3; ++a) {
      sg.lo[a] = static_cast<float>(nl.geom[g].lo[a]);
      sg.cellSize[a] = static_cast<float>(nl.geom[g].size[a]);
      sg.invCellSize[a] = static_cast<float>(nl.geom[g].inv[a]);
      sg.res[a] = nl.res[3 * g + a];
    }
    sg.first = static_cast<uint32_t>(nl.first[g]);
    sg.base = rl.sub[g].base();
    sg.wide = rl.sub[g].wide();
  }

  // The records, level by level (a top cell with a sub-grid has its header
  // only), each cell's references after the last's, at its block's width.
  const size_t cells = cellCount(), subCells = static_cast<size_t>(nl.subCells);
  std::vector<uint32_t> fillTop(cells), fillSub(subCells);
  auto header = [&](uint32_t run) { return run == gridrefs::kNone ? kNoPlane : rl.kept[run]; };
  uint32_t units = 0, r = 0;
  for (size_t c = 0; c < cells; ++c) {
    fillTop[c] = units;
    if (nl.sub[c] != gridrefs::kNone) {
      records_[r++] = CellRecord{units, kSubGrid | nl.sub[c]};
    } else if (rl.topCount[c] > 0) {
      records_[r++] = CellRecord{units, header(rl.topRun[c])};
      units += rl.topCount[c] * (plan_.topWide ? 2 : 1);
    }
  }
  const uint32_t topRecords = r;
  for (size_t g = 0; g < nl.top.size(); ++g) {
    const uint64_t end = g + 1 < nl.top.size() ? nl.first[g + 1] : nl.subCells;
    for (size_t c = static_cast<size_t>(nl.first[g]); c < end; ++c) {
      fillSub[c] = units;
      if (rl.subCount[c] == 0) continue;
      records_[r++] = CellRecord{units, header(rl.subRun[c])};
      units += rl.subCount[c] * (subs_[g].wide ? 2 : 1);
    }
  }
  CHECK_MSG(r == plan_.occupied && units == plan_.units, kMismatch);
  records_[r] = CellRecord{units, kNoPlane};
  Occupancy(rl.topCount, &nl.sub, 0, occupied_, rank_);
  Occupancy(rl.subCount, nullptr, topRecords, subOccupied_, subRank_);

  uint16_t* refs = refs_.data();
  auto put = [refs](uint32_t* at, uint32_t p, uint32_t base, bool wide) {
    if (wide) {
      refs[(*at)++] = static_cast<uint16_t>(p & 0xffffu);
      refs[(*at)++] = static_cast<uint16_t>(p >> 16);
    } else {
      refs[(*at)++] = static_cast<uint16_t>(p - base);
    }
  };
  gridrefs::ForEachRef(
      patches, geom, rl,
      [&](size_t i, size_t c) {
        put(&fillTop[c], static_cast<uint32_t>(i), plan_.topBase, plan_.topWide);
      },
      [&](size_t i, uint32_t g, uint64_t s) {
        put(&fillSub[s], static_cast<uint32_t>(i), subs_[g].base, subs_[g].wide != 0);
      });
}

RefList Grid::RefsOf(int64_t r, uint32_t base, bool wide) const {
  if (r < 0) return RefList();
  const CellRecord& rec = records_[static_cast<size_t>(r)];
  const uint32_t units = records_[static_cast<size_t>(r) + 1].start - rec.start;
  return RefList(refs_.data() + rec.start, wide ? units / 2 : units, base, wide);
}

RefList Grid::CellRefs(size_t c) const {
  return RefsOf(RecordOf(occupied_, rank_, c), plan_.topBase, plan_.topWide);
}

uint32_t Grid::CellPlaneOf(size_t c) const {
  const int64_t r = RecordOf(occupied_, rank_, c);
  return r < 0 ? kNoPlane : records_[static_cast<size_t>(r)].header;
}

RefList Grid::SubCellRefs(size_t s) const {
  const int64_t r = RecordOf(subOccupied_, subRank_, s);
  if (r < 0) return RefList();
  // The sub-grid that holds cell s: the last whose first cell is not after it.
  const SubGrid* g = std::upper_bound(subs_.begin(), subs_.end(), s,
                                      [](size_t x, const SubGrid& sg) { return x < sg.first; });
  --g;
  return RefsOf(r, g->base, g->wide != 0);
}

uint32_t Grid::SubCellPlaneOf(size_t s) const {
  const int64_t r = RecordOf(subOccupied_, subRank_, s);
  return r < 0 ? kNoPlane : records_[static_cast<size_t>(r)].header;
}

}  // namespace vismask
