#include "vismask/grid.h"

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

}  // namespace

Grid::Plan Grid::MakePlan(Span<const Patch> patches, float density) {
  std::vector<PatchGeom> geom(patches.size());
  for (size_t i = 0; i < patches.size(); ++i) geom[i] = MakePatchGeom(patches[i]);
  return MakePlan(patches, Span<const PatchGeom>(geom.data(), geom.size()), density);
}

Grid::Plan Grid::MakePlan(Span<const Patch> patches, Span<const PatchGeom> geom, float density) {
  CHECK(patches.size() == geom.size());
  CHECK_MSG(density > 0.0f && std::isfinite(density), "grid density must be positive");
  Plan plan;
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

  // Exact reference and occupied-cell counts, by the same rule Build uses.
  CellGeometry cellGeom = CellGeometryOf(plan);
  const size_t cells = static_cast<size_t>(plan.res[0]) * plan.res[1] * plan.res[2];
  std::vector<uint64_t> touched((cells + 63) / 64, 0);
  uint64_t refs = 0, occupied = 0;
  for (size_t i = 0; i < n; ++i) {
    MakeShape(patches[i], geom[i], scale, &shape);
    ForEachCell(cellGeom, shape, [&](size_t c) {
      ++refs;
      uint64_t bit = uint64_t{1} << (c & 63);
      occupied += (touched[c >> 6] & bit) == 0;
      touched[c >> 6] |= bit;
    });
  }
  plan.refs = refs;
  plan.occupied = occupied;
  ForEachPlaneRun(patches, geom, [&plan](const CellPlane&) { ++plan.planes; });
  return plan;
}

void Grid::Layout(Arena& arena, const Plan& plan) {
  plan_ = plan;
  size_t cells = cellCount();
  CHECK_MSG(cells < 0xffffffffu && plan.refs + plan.occupied < 0xffffffffu,
            "grid too large for 32-bit offsets");
  cellStart_ = arena.Alloc<uint32_t>(cells + 1);
  refs_ = arena.Alloc<uint32_t>(static_cast<size_t>(plan.refs + plan.occupied));
  occupied_ = arena.Alloc<uint64_t>((cells + 63) / 64);
  planes_ = arena.Alloc<CellPlane>(static_cast<size_t>(plan.planes));
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

  // Counting sort: count per cell, exclusive prefix sum (a header word
  // before each occupied cell's patches), fill advancing each cell's start
  // to its end, then shift the starts back by one cell.
  for (size_t c = 0; c <= cells; ++c) start[c] = 0;
  Shape shape;
  uint64_t total = 0;
  for (size_t i = 0; i < patches.size(); ++i) {
    MakeShape(patches[i], geom[i], scale, &shape);
    ForEachCell(cellGeom, shape, [&](size_t c) {
      ++start[c];
      ++total;
    });
  }
  CHECK_MSG(total == plan_.refs, "grid plan does not match the patches it is built from");
  uint32_t sum = 0;
  for (size_t c = 0; c < cells; ++c) {
    uint32_t count = start[c];
    uint32_t header = count > 0;
    start[c] = sum + header;
    sum += count + header;
  }
  CHECK_MSG(sum == plan_.refs + plan_.occupied,
            "grid plan does not match the patches it is built from");
  start[cells] = sum;
  uint32_t* refs = refs_.data();
  for (size_t i = 0; i < patches.size(); ++i) {
    MakeShape(patches[i], geom[i], scale, &shape);
    uint32_t index = static_cast<uint32_t>(i);
    ForEachCell(cellGeom, shape, [&](size_t c) { refs[start[c]++] = index; });
  }
  for (size_t c = cells; c > 0; --c) start[c] = start[c - 1];
  start[0] = 0;
  uint64_t* occupied = occupied_.data();
  for (size_t w = 0; w < occupied_.size(); ++w) occupied[w] = 0;
  // Each occupied cell's header: the plane record all its patches share, if any.
  const CellPlane* planes = planes_.data();
  auto recordOf = [&](uint32_t p) -> const CellPlane* {
    const CellPlane* r = std::upper_bound(
        planes, planes + numPlanes, p, [](uint32_t q, const CellPlane& c) { return q < c.first; });
    if (r == planes) return nullptr;
    --r;
    return p - r->first < r->count ? r : nullptr;
  };
  for (size_t c = 0; c < cells; ++c) {
    if (start[c + 1] == start[c]) continue;
    occupied[c >> 6] |= uint64_t{1} << (c & 63);
    const CellPlane* shared = recordOf(refs[start[c] + 1]);
    for (uint32_t k = start[c] + 2; k < start[c + 1] && shared; ++k) {
      const CellPlane* r = recordOf(refs[k]);
      if (!r || !SamePlane(*r, *shared)) shared = nullptr;
    }
    refs[start[c]] = shared ? static_cast<uint32_t>(shared - planes) : kNoPlane;
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
  const uint32_t* refs = refs_.data();
  const PatchGeom* geom = geom_.data();
  const CellPlane* planes = planes_.data();
  Ray r = ray;       // tMax shrinks to just past the best hit so far
  float limit = t1;  // no step into a cell beyond this: the ray's end or the best hit
  uint32_t bestPatch = kNoPatch;
  float bestT = r.tMax;  // every hit is nearer than the ray's end
  bool bestFront = false;
  const uint64_t* occupied = occupied_.data();
  uint64_t tests = 0;
  for (;;) {
    // Most cells a ray crosses are empty: one bit in a small bitmap says so,
    // where their offsets (32 times larger, strided by rows and slices) cost
    // a cache miss each in a large grid.
    if (((occupied[static_cast<uint32_t>(index) >> 6] >> (index & 63)) & 1) != 0) {
      uint32_t begin = start[index] + 1, end = start[index + 1];
      const uint32_t header = refs[begin - 1];
      if (header != kNoPlane) {
        // The cell's patches share a plane (CellPlane). Each patch test
        // divides num = d - n.o by denom = n.dir; if num is never of
        // denom's sign over the range of d, every t is <= 0 and, with
        // tMin >= 0, every test below would fail its range check: the
        // cell is passed without reading a patch. The products and sums
        // are IntersectPatch's, on the other sign of the normal for some
        // patches, which negates them exactly; no division is needed.
        const CellPlane& pl = planes[header];
        float denom = pl.n.x * r.d.x + pl.n.y * r.d.y + pl.n.z * r.d.z;
        float s = pl.n.x * r.o.x + pl.n.y * r.o.y + pl.n.z * r.o.z;
        float numLo = pl.dLo - s, numHi = pl.dHi - s;
        if (denom == 0.0f || (r.tMin >= 0.0f && (denom > 0.0f ? numHi <= 0.0f : numLo >= 0.0f))) {
          tests += end - begin;
          begin = end;
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
        ++tests;
        if (p == skip.patch || !IntersectPatch(geom[p], r, &t, &front) || p == skip.twin) continue;
        if (kAnyHit) {
          if (hit) hit->patch = p;
          steps_ += tests + static_cast<uint64_t>(kx + ky + kz) + 1;
          return true;
        }
        // t <= bestT here. On a tie a front side, then the lower index, so
        // that of two coplanar twins the ray lands on the one it faces.
        if (t < bestT || TieWins(p, front, bestPatch, bestFront)) {
          bestPatch = p;
          bestT = t;
          bestFront = front;
          r.tMax = std::nextafter(t, std::numeric_limits<float>::infinity());
          limit = std::min(t1, t);
        }
      }
    }
    // Step across the plane that comes first (ties: y before x, z before
    // both), unless the ray ends, or its best hit is, before that plane.
    if (tx < ty && tx < tz) {
      if (!(tx < limit)) break;
      index += move[0];
      kx += 1.0f;
      tx = fx + kx * dx;
    } else if (ty < tz) {
      if (!(ty < limit)) break;
      index += move[1];
      ky += 1.0f;
      ty = fy + ky * dy;
    } else {
      if (!(tz < limit)) break;
      index += move[2];
      kz += 1.0f;
      tz = fz + kz * dz;
    }
  }
  steps_ += tests + static_cast<uint64_t>(kx + ky + kz) + 1;
  if (bestPatch == kNoPatch) return false;
  hit->patch = bestPatch;
  hit->t = bestT;
  hit->front = bestFront;
  return true;
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
