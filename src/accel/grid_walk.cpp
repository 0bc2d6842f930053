#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "vismask/accel/grid.h"

// Grid::Intersect and Grid::Occluded: the 3D-DDA walk of the top grid and
// of the sub-grids in its dense cells, the cells' patch tests, and every
// patch tested for a ray the grid cannot walk (src/accel/grid.cpp plans and
// builds the grid).
namespace vismask {

namespace {
// std::nextafter(t, +inf) for a finite t, without the library call (0.9%
// of a solve's instructions on the Cornell box): the next float up.
inline float NextUp(float t) {
  uint32_t b;
  std::memcpy(&b, &t, sizeof b);
  b = t > 0.0f ? b + 1 : t == 0.0f ? 1u : b - 1;
  std::memcpy(&t, &b, sizeof t);
  return t;
}

// Of two hits at the same t, whether patch p (side `front`) beats `best`:
// a front side beats a back side, then the lower index wins. A total order
// (so the walk's cell order cannot matter): of two coplanar twins, whose t
// is bit-identical (patch.h, TwinGeom), the ray lands on the one it faces.
// Runs on exact ties only, off the walk's hot path.
inline bool TieWins(uint32_t p, bool front, uint32_t best, bool bestFront) {
  return front != bestFront ? front : p < best;
}

// A 3D-DDA across the cells of a grid (the top one or a sub-grid). Per axis
// the k-th cell plane ahead (k = 0, 1, ...) is crossed at first + k * delta,
// a product and a sum per step that is never accumulated, so its error stays
// a few ulps of the scene magnitude, far inside the registration padding.
// The plane where the ray leaves the grid bounds its end by the same formula
// (same bits, and the formula grows with k), so no step can take the walk
// out of the grid. Inlined, its members stay in registers.
struct Dda {
  float fx, fy, fz;                       // the first plane's t, per axis
  float dx, dy, dz;                       // the t between planes
  float tx, ty, tz;                       // the next plane's t
  float kx = 0.0f, ky = 0.0f, kz = 0.0f;  // planes crossed
  int move[3];                            // the cell index's step

  // From the point at t of the ray o + t d (invD: 1 / d, 0 where d is 0) on
  // a grid of res cells from lo: the entry cell's index, and *tEnd bounded
  // by the plane where the ray leaves the grid. The axes are spelled out,
  // not looped over: a loop with a branch per axis stays a loop, and every
  // glm::vec3 read in it is a switch on the axis.
  inline __attribute__((always_inline)) int Start(const float o[3], const float d[3],
                                                  const float invD[3], float t, const glm::vec3& lo,
                                                  const glm::vec3& cellSize,
                                                  const glm::vec3& invCellSize, const int res[3],
                                                  float* tEnd) {
    const int stride[3] = {1, res[0], res[0] * res[1]};
    float first[3], delta[3];
    int index = StartAxis(o[0], d[0], invD[0], t, lo.x, cellSize.x, invCellSize.x, res[0],
                          stride[0], &first[0], &delta[0], &move[0], tEnd);
    index += StartAxis(o[1], d[1], invD[1], t, lo.y, cellSize.y, invCellSize.y, res[1], stride[1],
                       &first[1], &delta[1], &move[1], tEnd);
    index += StartAxis(o[2], d[2], invD[2], t, lo.z, cellSize.z, invCellSize.z, res[2], stride[2],
                       &first[2], &delta[2], &move[2], tEnd);
    fx = first[0], fy = first[1], fz = first[2];
    dx = delta[0], dy = delta[1], dz = delta[2];
    tx = fx, ty = fy, tz = fz;
    return index;
  }

  // One axis of Start: the entry cell's coordinate times its stride, the
  // axis's first plane, spacing and index step, and its last plane's bound.
  static inline __attribute__((always_inline)) int StartAxis(float o, float d, float invD, float t,
                                                             float lo, float cellSize,
                                                             float invCellSize, int res, int stride,
                                                             float* first, float* delta, int* move,
                                                             float* tEnd) {
    // t is finite (the clip bounds it on an axis the ray moves along), so
    // where d is 0 the point is o itself, up to the sign of a zero, which
    // the cell index does not keep: no branch.
    float p = o + t * d;
    float f = (p - lo) * invCellSize;
    // The entry cell, clamped to [0, res - 1] (a NaN to 0): the cell that
    // comparing f with 0 and res would give, by a max and a min (float(res -
    // 1) is exact) instead of two branches.
    int c = static_cast<int>(std::min(0.0f < f ? f : 0.0f, static_cast<float>(res - 1)));
    if (d == 0.0f) {
      *first = std::numeric_limits<float>::infinity();
      *delta = 0.0f;
      *move = 0;
      return c * stride;
    }
    bool up = d > 0.0f;
    *first = (lo + static_cast<float>(up ? c + 1 : c) * cellSize - o) * invD;
    *delta = cellSize * std::fabs(invD);
    *move = up ? stride : -stride;
    float exit = *first + static_cast<float>(up ? res - 1 - c : c) * *delta;
    if (exit < *tEnd) *tEnd = exit;
    return c * stride;
  }

  // Steps across the plane that comes first (ties: y before x, z before
  // both) into the next cell, unless that plane is not before bound.
  inline __attribute__((always_inline)) bool Step(float bound, int* index) {
    if (tx < ty && tx < tz) {
      if (!(tx < bound)) return false;
      *index += move[0];
      kx += 1.0f;
      tx = fx + kx * dx;
    } else if (ty < tz) {
      if (!(ty < bound)) return false;
      *index += move[1];
      ky += 1.0f;
      ty = fy + ky * dy;
    } else {
      if (!(tz < bound)) return false;
      *index += move[2];
      kz += 1.0f;
      tz = fz + kz * dz;
    }
    return true;
  }

  // Where the ray entered the current cell: the last plane it crossed, by
  // the steps' own formula (t0 if none); and where it leaves the cell.
  float Entered(float t0) const {
    float t = t0;
    if (kx > 0.0f) t = std::max(t, fx + (kx - 1.0f) * dx);
    if (ky > 0.0f) t = std::max(t, fy + (ky - 1.0f) * dy);
    if (kz > 0.0f) t = std::max(t, fz + (kz - 1.0f) * dz);
    return t;
  }
  float Leave() const { return std::min(std::min(tx, ty), tz); }
  // Through int64_t: the same count (a small whole number), without the
  // float-to-unsigned conversion x86-64 spells as a branch and two converts.
  uint64_t Crossed() const { return static_cast<uint64_t>(static_cast<int64_t>(kx + ky + kz)); }
};

// One axis of the walk's clip to the grid box [lo, hi]: its inverse
// direction (0 when d is 0) and (t0, t1) narrowed to the slab. kOut: the ray
// does not move along the axis and lies outside the slab; kTestAll: the
// inverse overflows.
enum Clip : int { kIn = 0, kOut = 1, kTestAll = 2 };
inline __attribute__((always_inline)) Clip ClipAxis(float o, float d, float lo, float hi,
                                                    float* invD, float* t0, float* t1) {
  if (d == 0.0f) {
    *invD = 0.0f;
    return o < lo || o > hi ? kOut : kIn;
  }
  *invD = 1.0f / d;
  if (!(std::fabs(*invD) <= std::numeric_limits<float>::max())) return kTestAll;
  float tNear = (lo - o) * *invD;
  float tFar = (hi - o) * *invD;
  if (tNear > tFar) std::swap(tNear, tFar);
  if (tNear > *t0) *t0 = tNear;
  if (tFar < *t1) *t1 = tFar;
  return kIn;
}

// The set bits of w: the rank of an occupied cell among its bitmap word's.
// x86-64's baseline has no instruction for it (the builtin would call
// libgcc), so the count is formed by bit slices there; elsewhere (aarch64)
// the builtin is an instruction. The same integers either way.
inline __attribute__((always_inline)) uint32_t Popcount(uint64_t w) {
#if defined(__x86_64__) && !defined(__POPCNT__)
  w = w - ((w >> 1) & 0x5555555555555555ull);
  w = (w & 0x3333333333333333ull) + ((w >> 2) & 0x3333333333333333ull);
  w = (w + (w >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<uint32_t>((w * 0x0101010101010101ull) >> 56);
#else
  return static_cast<uint32_t>(__builtin_popcountll(w));
#endif
}

// Reference k of a cell's list: 32-bit (two 16-bit units, low first) or
// 16-bit from the block's base.
template <bool kWide>
inline __attribute__((always_inline)) uint32_t RefAt(const uint16_t* refs, uint32_t k,
                                                     uint32_t base) {
  if (kWide) {
    uint32_t v;
    std::memcpy(&v, refs + 2 * k, sizeof v);
    return v;
  }
  return base + refs[k];
}

}  // namespace

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

template <bool kAnyHit, bool kWide>
bool Grid::Walk(const Ray& ray, Skip skip, Hit* hit) const {
  DCHECK(records_.data() != nullptr);  // built
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
  const Clip cx = ClipAxis(o[0], d[0], lo.x, hi.x, &invD[0], &t0, &t1);
  const Clip cy = ClipAxis(o[1], d[1], lo.y, hi.y, &invD[1], &t0, &t1);
  const Clip cz = ClipAxis(o[2], d[2], lo.z, hi.z, &invD[2], &t0, &t1);
  // The first axis (x, y, z) that is not kIn decides.
  if (__builtin_expect((cx | cy | cz) != Clip::kIn, 0)) {
    for (Clip c : {cx, cy, cz}) {
      if (c == Clip::kOut) return false;
      if (c == Clip::kTestAll) return TestAll<kAnyHit>(ray, skip, hit);
    }
  }
  if (!(t0 <= t1)) return false;

  Dda dda;
  int index = dda.Start(o, d, invD, t0, lo, cellSize_, invCellSize_, plan_.res, &t1);

  const uint64_t* occupied = occupied_.data();
  const uint32_t* rank = rank_.data();
  const CellRecord* records = records_.data();
  const uint32_t base = plan_.topBase;
  WalkState st;
  st.tMax = ray.tMax;  // shrinks to just past the best hit so far
  st.t1 = t1;
  st.limit = t1;          // no step into a cell beyond this: the ray's end or the best hit
  st.bestT = ray.tMax;    // every hit is nearer than the ray's end
  uint64_t subSteps = 0;  // sub-grid cells entered
  auto done = [&] { steps_ += st.tests + subSteps + dda.Crossed() + 1; };
  for (;;) {
    // Most cells a ray crosses are empty: one bit in a small bitmap says so;
    // an occupied cell's record is the occupied cells before its word plus
    // those before it in the word.
    const uint32_t u = static_cast<uint32_t>(index);
    const uint64_t word = occupied[u >> 6];
    if (((word >> (u & 63)) & 1) != 0) {
      const CellRecord* r =
          records + rank[u >> 6] + Popcount(word & ((uint64_t{1} << (u & 63)) - 1));
      const uint32_t header = r->header;
      // kSubGrid .. kNoPlane - 1: a sub-grid.
      if (__builtin_expect(header - kSubGrid < kNoPlane - kSubGrid, 0)) {
        // Where the ray entered the top cell, and where it leaves it.
        const float tEnter = dda.Entered(t0);
        const float tLeave = dda.Leave();
        // A copy goes out of line: the walk's own state never leaves this
        // function, so it stays in registers.
        WalkState sub = st;
        const bool found = EnterSub<kAnyHit>(subs_.data()[header - kSubGrid], ray, invD, tEnter,
                                             tLeave, skip, hit, &sub, &subSteps);
        st = sub;
        if (found) {
          done();
          return true;
        }
      } else if (TestCell<kAnyHit, kWide>(r, base, ray, skip, hit, &st)) {
        done();
        return true;
      }
    }
    // The ray ends, or its best hit is, before the next plane: done.
    if (!dda.Step(st.limit, &index)) break;
  }
  done();
  if (st.bestPatch == kNoPatch) return false;
  hit->patch = st.bestPatch;
  hit->t = st.bestT;
  hit->front = st.bestFront;
  return true;
}

template <bool kAnyHit, bool kWide>
inline __attribute__((always_inline)) bool Grid::TestCell(const CellRecord* rec, uint32_t base,
                                                          const Ray& r, Skip skip, Hit* hit,
                                                          WalkState* st) const {
  const uint16_t* refs = refs_.data() + rec->start;
  const uint32_t n = kWide ? (rec[1].start - rec->start) / 2 : rec[1].start - rec->start;
  // Every patch of the cell counts as tested (an any-hit walk that stops
  // early takes back the ones after its hit).
  st->tests += n;
  const uint32_t header = rec->header;
  if (header != kNoPlane) {
    // The cell's patches share a plane (CellPlane). Each patch test
    // divides num = d - n.o by denom = n.dir; if num is never of
    // denom's sign over the range of d, every t is <= 0 and, with
    // tMin >= 0, every test below would fail its range check: the
    // cell is passed without reading a patch. The products and sums
    // are IntersectPatch's, on the other sign of the normal for some
    // patches, which negates them exactly; no division is needed.
    const CellPlane& pl = planes_.data()[header];
    float denom = pl.n.x * r.d.x + pl.n.y * r.d.y + pl.n.z * r.d.z;
    float s = pl.n.x * r.o.x + pl.n.y * r.o.y + pl.n.z * r.o.z;
    float numLo = pl.dLo - s, numHi = pl.dHi - s;
    if (denom == 0.0f || (r.tMin >= 0.0f && (denom > 0.0f ? numHi <= 0.0f : numLo >= 0.0f)))
      return false;
  }
  // Reference q is patch from + q (16-bit: from is the block's base;
  // 32-bit: 0), and the skipped patches are compared as references (exact:
  // p - from wraps alike for every p).
  const uint32_t from = kWide ? 0 : base;
  const PatchGeom* geom = geom_.data() + from;
  const uint32_t skipQ = skip.patch - from, twinQ = skip.twin - from;
  // Ask for every patch of the cell at once: their cache misses overlap
  // instead of coming one test at a time.
  for (uint32_t k = 0; k < n; ++k) {
    const char* g = reinterpret_cast<const char*>(geom + RefAt<kWide>(refs, k, 0));
    __builtin_prefetch(g);
    __builtin_prefetch(g + sizeof(PatchGeom) - 1);
  }
  for (uint32_t k = 0; k < n; ++k) {
    const uint32_t q = RefAt<kWide>(refs, k, 0);
    float t;
    bool front;
    if (q == skipQ || !IntersectPatch(geom[q], r.o, r.d, r.tMin, st->tMax, &t, &front) ||
        q == twinQ)
      continue;
    const uint32_t p = q + from;
    if (kAnyHit) {
      st->tests -= n - 1 - k;
      if (hit) hit->patch = p;
      return true;
    }
    // t <= bestT here. On a tie a front side, then the lower index, so
    // that of two coplanar twins the ray lands on the one it faces.
    if (t < st->bestT || TieWins(p, front, st->bestPatch, st->bestFront)) {
      st->bestPatch = p;
      st->bestT = t;
      st->bestFront = front;
      st->tMax = NextUp(t);
      st->limit = std::min(st->t1, t);
    }
  }
  return false;
}

// A sub-grid at its own reference width.
template <bool kAnyHit>
bool Grid::EnterSub(const SubGrid& sg, const Ray& ray, const float invD[3], float tEnter,
                    float tLeave, Skip skip, Hit* hit, WalkState* st, uint64_t* steps) const {
  return sg.wide ? WalkSub<kAnyHit, true>(sg, ray, invD, tEnter, tLeave, skip, hit, st, steps)
                 : WalkSub<kAnyHit, false>(sg, ray, invD, tEnter, tLeave, skip, hit, st, steps);
}

// A top cell's sub-grid, from where the ray entered the top cell to where it
// leaves it (or to the best hit): the same DDA on the sub-grid's cells, its
// end bounded by the sub-grid's last planes (the same formula, so no step
// leaves it). The sub-grid's planes and the top cell's differ by rounding
// only, far inside the registration padding. Out of line, with its own copy
// of the walk's state, so that the top walk keeps its own in registers.
template <bool kAnyHit, bool kWide>
__attribute__((noinline)) bool Grid::WalkSub(const SubGrid& sg, const Ray& ray, const float invD[3],
                                             float tEnter, float tLeave, Skip skip, Hit* hit,
                                             WalkState* state, uint64_t* steps) const {
  WalkState st = *state;
  const float o[3] = {ray.o.x, ray.o.y, ray.o.z};
  const float d[3] = {ray.d.x, ray.d.y, ray.d.z};
  float tEnd = tLeave;
  Dda dda;
  int32_t index = static_cast<int32_t>(sg.first) +
                  dda.Start(o, d, invD, tEnter, sg.lo, sg.cellSize, sg.invCellSize, sg.res, &tEnd);
  const uint64_t* occupied = subOccupied_.data();
  const uint32_t* rank = subRank_.data();
  const CellRecord* records = records_.data();
  const uint32_t base = sg.base;
  bool done = false;
  for (;;) {
    const uint32_t u = static_cast<uint32_t>(index);
    const uint64_t word = occupied[u >> 6];
    if (((word >> (u & 63)) & 1) != 0 &&
        TestCell<kAnyHit, kWide>(
            records + rank[u >> 6] + Popcount(word & ((uint64_t{1} << (u & 63)) - 1)), base, ray,
            skip, hit, &st)) {
      done = true;
      break;
    }
    if (!dda.Step(std::min(tEnd, st.limit), &index)) break;
  }
  *steps += dda.Crossed() + 1;
  *state = st;
  return done;
}

// The walk for the top cells' reference width.
template <bool kAnyHit>
inline bool Grid::WalkAny(const Ray& ray, Skip skip, Hit* hit) const {
  return plan_.topWide ? Walk<kAnyHit, true>(ray, skip, hit) : Walk<kAnyHit, false>(ray, skip, hit);
}

bool Grid::Intersect(const Ray& ray, Skip skip, Hit* hit) const {
  return WalkAny<false>(ray, skip, hit);
}

bool Grid::Occluded(const Ray& ray, Skip skip) const {
  return WalkAny<true>(ray, skip, nullptr);
}

bool Grid::Occluded(const Ray& ray, Skip skip, uint32_t* hint) const {
  uint32_t h = *hint;
  float t;
  bool front;
  if (h != kNoPatch && h != skip.patch && h != skip.twin &&
      IntersectPatch(geom_[h], ray, &t, &front))
    return true;
  Hit hit;
  if (!WalkAny<true>(ray, skip, &hit)) return false;
  *hint = hit.patch;
  return true;
}

}  // namespace vismask
