#include "vismask/solve/centre_raster.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <glm/geometric.hpp>

#include "vismask/core/fast_trig.h"

namespace vismask {

using Arc = PixelArc;
using View = PolygonView;

namespace {

constexpr double kHalfPi = 1.5707963267948966;
constexpr double kPi = 3.141592653589793;
constexpr double kTwoPi = 6.283185307179586;
constexpr int kMaxCols = 4 * 4096;  // --mask-res is at most 4096

// The error of FastAcos and FastAtan2, with room to spare: it widens the
// arcs that must hold every hit and narrows those that must hold only hits.
constexpr double kApprox = 1e-6;
static_assert(kApprox > 10 * kTrigError, "room for the approximations' error");

// floor and ceil to int (libm's are calls on baseline x86-64).
int Floor(double x) {
  int i = static_cast<int>(x);
  return i - (x < i);
}
int Ceil(double x) {
  int i = static_cast<int>(x);
  return i + (x > i);
}

// The columns whose centres lie in the angles [a - w, a + w] (`at`: a in
// columns less half a column, `half`: w in columns), and one more each
// side (Grown) or one fewer (Shrunk).
Arc Grown(double at, double half) {
  return Arc{Floor(at - half) - 1, Ceil(at + half) + 1};
}
Arc Shrunk(double at, double half) {
  return Arc{Ceil(at - half) + 1, Floor(at + half) - 1};
}

// cur = cur ∩ arc on a circle of `cols`. Where that is two pieces: their
// hull (grow: a superset) or the wider one (!grow: a subset). False when
// empty.
bool Intersect(Arc arc, int cols, bool grow, Arc* cur) {
  if (arc.hi - arc.lo + 1 >= cols) return true;
  if (cur->hi - cur->lo + 1 >= cols) {
    *cur = arc;
    return true;
  }
  while (arc.lo > cur->lo) {  // so that arc.lo <= cur.lo < arc.lo + cols
    arc.lo -= cols;
    arc.hi -= cols;
  }
  while (arc.lo + cols <= cur->lo) {
    arc.lo += cols;
    arc.hi += cols;
  }
  Arc a{std::max(cur->lo, arc.lo), std::min(cur->hi, arc.hi)};
  Arc b{std::max(cur->lo, arc.lo + cols), std::min(cur->hi, arc.hi + cols)};
  bool ha = a.lo <= a.hi, hb = b.lo <= b.hi;
  if (ha && hb)
    *cur = grow ? Arc{a.lo, b.hi} : (a.hi - a.lo >= b.hi - b.lo ? a : b);
  else if (ha)
    *cur = a;
  else if (hb)
    *cur = b;
  return ha || hb;
}

// A convex polygon in the frame of the rays' origin (z: the hemisphere's
// axis), in double.
struct Local {
  glm::dvec3 corner[4];
  uint32_t corners = 0;
  glm::dvec3 normal, mean;
  double radius = 0.0, dist = 0.0;
  double largest = 0.0;  // the largest world coordinate involved
};

void ToLocal(const glm::vec3* corner, uint32_t corners, const glm::vec3& normal,
             const CentreRays& rays, Local* l) {
  const Frame& f = rays.frame;
  glm::dvec3 t(f.t), b(f.b), n(f.n), o(rays.origin);
  l->corners = corners;
  l->mean = glm::dvec3(0.0);
  l->largest = std::max({std::fabs(o.x), std::fabs(o.y), std::fabs(o.z)});
  for (uint32_t k = 0; k < corners; ++k) {
    glm::dvec3 c(corner[k]);
    l->largest = std::max({l->largest, std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)});
    glm::dvec3 q = c - o;
    l->corner[k] = glm::dvec3(glm::dot(q, t), glm::dot(q, b), glm::dot(q, n));
    l->mean += l->corner[k];
  }
  l->mean /= static_cast<double>(corners);
  l->radius = 0.0;
  for (uint32_t k = 0; k < corners; ++k)
    l->radius = std::max(l->radius, glm::length(l->corner[k] - l->mean));
  l->dist = glm::length(l->mean);
  glm::dvec3 m(normal);
  l->normal = glm::dvec3(glm::dot(m, t), glm::dot(m, b), glm::dot(m, n));
}

// The edge planes of `l` into `v`, widened by `margin`; false (and none)
// when the origin is near the polygon's plane or an edge is degenerate.
bool EdgePlanes(const Local& l, double margin, double colsPerRad, View* v) {
  v->edges = 0;
  if (!(std::fabs(glm::dot(l.normal, l.mean)) > 1e-3 * l.dist + 1e-9 * l.largest)) return false;
  double sign = 0.0;
  glm::dvec3 e[4];
  for (uint32_t k = 0; k < l.corners; ++k) {
    e[k] = glm::cross(l.corner[k], l.corner[(k + 1) % l.corners]);
    double len = glm::length(e[k]);
    if (!(len > 0.0)) return false;
    e[k] /= len;
    sign += glm::dot(e[k], l.mean);
  }
  if (sign == 0.0) return false;
  for (uint32_t k = 0; k < l.corners; ++k) {
    glm::dvec3 u = sign > 0.0 ? e[k] : -e[k];
    double xy = std::sqrt(u.x * u.x + u.y * u.y);
    v->invXY[k] = xy > 1e-9 ? 1.0 / xy : 0.0;
    v->psiCols[k] = FastAtan2(u.y, u.x) * colsPerRad - 0.5;
    v->z[k] = u.z;
  }
  v->edges = static_cast<int>(l.corners);
  v->margin = margin;
  return true;
}

// The view of patch `p` for its hits: a cone about a sphere around the
// corners, widened for the edge tolerance (patch.cpp: 1e-5 of the size and
// 4 float steps of the plane offsets) and for the rounding of the hit
// point, both many times over, then one pixel more each side; the edge
// planes widened by as much. False when no centre can see it.
bool PatchView(const Patch& p, const CentreRays& rays, uint32_t res, View* v) {
  const int rows = static_cast<int>(res), cols = 4 * rows;
  const double dTheta = kHalfPi / rows, colsPerRad = cols / kTwoPi;
  Local l;
  ToLocal(p.corner, p.numCorners, p.normal, rays, &l);
  double slack = 1e-3 * l.radius + 1e-5 * l.dist + 256.0 * FLT_EPSILON * l.largest;
  double reach = l.radius + slack;
  v->rowLo = 0;
  v->rowHi = rows - 1;
  v->colLo = 0;
  v->colHi = cols - 1;
  v->edges = 0;
  v->inner = -1.0;
  if (!(l.dist > 1.01 * reach + slack)) return true;  // the origin is at or near the patch
  double alpha = std::asin(reach / l.dist) + 2.0 * slack / (l.dist - reach) + 1e-5;
  double theta = std::acos(std::clamp(l.mean.z / l.dist, -1.0, 1.0));
  v->rowLo = std::max(0, Floor((theta - alpha) / dTheta - 0.5) - 1);
  v->rowHi = std::min(rows - 1, Ceil(std::min(double(rows), (theta + alpha) / dTheta) - 0.5) + 1);
  if (v->rowLo > v->rowHi) return false;  // below the horizon
  if (theta - alpha > 0.0 && theta + alpha < kPi) {
    double beta = std::asin(std::min(1.0, std::sin(alpha) / std::sin(theta)));
    Arc arc = Grown(FastAtan2(l.mean.y, l.mean.x) * colsPerRad - 0.5,
                    (beta + 2.0 * kApprox) * colsPerRad);
    if (arc.hi - arc.lo + 1 < cols) {
      v->colLo = arc.lo;
      v->colHi = arc.hi;
    }
  }
  double margin = 2.0 * slack / (l.dist - reach) + 1e-5;
  if (!EdgePlanes(l, margin, colsPerRad, v)) return true;
  // Well inside every plane, a ray surely passes IntersectPatch: its hit
  // lies farther from each edge than the hit point's rounding, when no
  // corner is seen near edge-on (so t's relative error stays small) and
  // the patch is far compared with its size.
  double edgeOn = 1.0;
  for (uint32_t k = 0; k < l.corners; ++k)
    edgeOn =
        std::min(edgeOn, std::fabs(glm::dot(l.normal, l.corner[k])) / glm::length(l.corner[k]));
  if (edgeOn > 0.02 && l.dist > 2.0 * reach) v->inner = 2.0 * margin + 1e-4;
  return true;
}

// The columns of row (sine s, cosine c) inside every edge plane of `v`,
// within its columns: *out. False when there are none. With `sure`, also
// *sure: the columns inside every plane by v.inner (empty: lo > hi).
bool RowArcs(const View& v, double s, double c, int cols, double colsPerRad, Arc* out, Arc* sure) {
  *out = Arc{v.colLo, v.colHi};
  bool inner = sure != nullptr;
  if (inner) *sure = Arc{0, cols - 1};
  const double invS = 1.0 / s;
  for (int k = 0; k < v.edges; ++k) {
    // On the row, normal . d = s * xy * cos(phi - psi) + z * c >= -margin
    // (out), >= inner (sure).
    double h = -v.z[k] * c;
    if (v.invXY[k] == 0.0 || !(s > 1e-9)) {  // normal . d is z * c on the whole row
      if (h - v.margin > 0.0) return false;
      if (inner && h + v.inner > 0.0) inner = false;
      continue;
    }
    double scale = invS * v.invXY[k];
    double ratio = (h - v.margin) * scale;
    if (ratio > 1.0) return false;
    if (ratio > -1.0) {
      Arc arc = Grown(v.psiCols[k], (FastAcos(ratio) + 2.0 * kApprox) * colsPerRad);
      if (!Intersect(arc, cols, true, out)) return false;
    }
    if (!inner) continue;
    double in = (h + v.inner) * scale;
    if (in > 1.0) {
      inner = false;
    } else if (in > -1.0) {
      Arc arc = Shrunk(v.psiCols[k], (FastAcos(in) - 2.0 * kApprox) * colsPerRad);
      if (arc.lo > arc.hi || !Intersect(arc, cols, false, sure)) inner = false;
    }
  }
  if (sure && !inner) *sure = Arc{1, 0};
  return true;
}

// Whether no centre ray can meet the plane of `g` ahead of the origin: t =
// num / denom must be positive, num (the origin's offset from the plane,
// the very float IntersectPatch forms) is the same for every ray, and the
// sign of denom = normal . d is known over the whole hemisphere when
// normal . d stays clear of 0 there. The coplanar neighbours of the
// shooter, behind its lifted origin, are the common case.
bool BehindOrigin(const PatchGeom& g, const CentreRays& rays) {
  const glm::vec3& o = rays.origin;
  float num = g.d - (g.n.x * o.x + g.n.y * o.y + g.n.z * o.z);
  if (num == 0.0f) return true;  // t = 0 is never past tMin = 0
  // Over the pixel centres (theta in [0, m], m the last row's, any phi),
  // normal . d spans [nz cos(theta) - q sin(theta), nz cos(theta) + q sin(theta)],
  // q = |normal.xy|.
  glm::dvec3 n(g.n);
  double nz = glm::dot(n, glm::dvec3(rays.frame.n));
  double nt = glm::dot(n, glm::dvec3(rays.frame.t)), nb = glm::dot(n, glm::dvec3(rays.frame.b));
  double q = std::sqrt(nt * nt + nb * nb), a = std::sqrt(nz * nz + q * q);
  double gamma = FastAtan2(q, nz);  // in [0, pi]
  const uint32_t last = rays.dirs->res() - 1;
  const double m = (last + 0.5) * kHalfPi / rays.dirs->res();
  const double cm = rays.dirs->rowCos(last), sm = rays.dirs->rowSin(last);
  constexpr double kClear = 1e-4;  // far beyond the rounding of the float dot products
  if (num < 0.0f) {
    // The least of a cos(theta + gamma): -a if theta + gamma reaches pi.
    double least = gamma + m >= kPi ? -a : std::min(nz, nz * cm - q * sm);
    return least > kClear;  // denom > 0 everywhere: t < 0
  }
  // The most of a cos(theta - gamma): a if theta - gamma reaches 0.
  double most = gamma <= m ? a : std::max(nz, nz * cm + q * sm);
  return most < -kClear;  // denom < 0 everywhere: t < 0
}

// Whether any pixel of the row starting at `base` is open in columns [lo, hi].
bool AnyOpen(const MaskBits& mask, uint32_t base, int lo, int hi, int cols) {
  if (hi - lo + 1 >= cols) return mask.CountOpen(base, base + cols) > 0;
  int a = ((lo % cols) + cols) % cols, b = a + (hi - lo);
  if (b < cols) return mask.CountOpen(base + a, base + b + 1) > 0;
  return mask.CountOpen(base + a, base + cols) > 0 ||
         mask.CountOpen(base, base + (b - cols) + 1) > 0;
}

}  // namespace

uint64_t RasterCentres(Span<const Patch> patches, Span<const PatchGeom> geom, Skip skip,
                       const CentreRays& rays, MaskBits* mask) {
  const MaskDirections& dirs = *rays.dirs;
  const uint32_t res = dirs.res();
  const int cols = 4 * static_cast<int>(res);
  const double colsPerRad = cols / kTwoPi;
  uint32_t open = mask->CountOpen();
  uint64_t tests = 0;
  View v;
  for (uint32_t i = 0; i < patches.size() && open > 0; ++i) {
    if (i == skip.patch || i == skip.twin || BehindOrigin(geom[i], rays)) continue;
    if (!PatchView(patches[i], rays, res, &v)) continue;
    const PatchGeom& g = geom[i];
    // Only a view wider than the two columns shrinking takes can hold a sure arc.
    const bool wantSure = v.inner >= 0.0 && v.colHi - v.colLo > 4;
    for (int row = v.rowLo; row <= v.rowHi; ++row) {
      const uint32_t base = static_cast<uint32_t>(row) * static_cast<uint32_t>(cols);
      if (!AnyOpen(*mask, base, v.colLo, v.colHi, cols)) continue;  // hidden, or a twin's
      Arc arc, sure{1, 0};
      if (!RowArcs(v, dirs.rowSin(row), dirs.rowCos(row), cols, colsPerRad, &arc,
                   wantSure ? &sure : nullptr))
        continue;
      ForArc(arc, sure, cols, [&](int col, bool surely) {
        uint32_t p = base + static_cast<uint32_t>(col);
        if (!mask->IsOpen(p)) return;
        if (!surely) {
          ++tests;
          float t;
          bool front;
          if (!IntersectPatch(g, rays.Of(static_cast<uint32_t>(row), static_cast<uint32_t>(col)),
                              &t, &front))
            return;
        }
        mask->Close(p);
        --open;
      });
    }
  }
  return tests;
}

bool FaceView(const Patch& face, const CentreRays& rays, double margin, double inner,
              PolygonView* v) {
  const int rows = static_cast<int>(rays.dirs->res()), cols = 4 * rows;
  Local l;
  ToLocal(face.corner, face.numCorners, face.normal, rays, &l);
  v->rowLo = 0;
  v->rowHi = rows - 1;
  v->colLo = 0;
  v->colHi = cols - 1;
  if (!EdgePlanes(l, margin, cols / kTwoPi, v)) return false;
  v->inner = inner;
  return true;
}

bool ViewRow(const PolygonView& v, const CentreRays& rays, uint32_t row, PixelArc* may,
             PixelArc* sure) {
  const MaskDirections& dirs = *rays.dirs;
  const int cols = 4 * static_cast<int>(dirs.res());
  return RowArcs(v, dirs.rowSin(row), dirs.rowCos(row), cols, cols / kTwoPi, may,
                 v.inner >= 0.0 ? sure : nullptr);
}

Patch BoxFace(const Bounds& box, int axis, int side) {
  Patch f{};
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  const float u[4] = {box.lo[a1], box.hi[a1], box.hi[a1], box.lo[a1]};
  const float v[4] = {box.lo[a2], box.lo[a2], box.hi[a2], box.hi[a2]};
  for (int k = 0; k < 4; ++k) {
    f.corner[k][axis] = side == 0 ? box.lo[axis] : box.hi[axis];
    f.corner[k][a1] = u[k];
    f.corner[k][a2] = v[k];
  }
  f.normal[axis] = side == 0 ? -1.0f : 1.0f;
  f.numCorners = 4;
  return f;
}

uint32_t KeepExits(Span<const Patch> exits, const CentreRays& rays, MaskBits* mask) {
  const MaskDirections& dirs = *rays.dirs;
  const uint32_t res = dirs.res();
  const int rows = static_cast<int>(res), cols = 4 * rows;
  // A pixel's directions lie within 1.5 rows of its centre's (rows and
  // columns are at most pi / 2R apart), so planes widened by that much keep
  // every pixel any of whose directions can leave.
  const double margin = std::sin(1.5 * kHalfPi / rows) + 1e-6;
  View views[6];
  const uint32_t n = std::min<uint32_t>(static_cast<uint32_t>(exits.size()), 6);
  for (uint32_t e = 0; e < n; ++e)
    if (!FaceView(exits[e], rays, margin, -1.0, &views[e])) return 0;  // the origin is on an exit
  uint32_t closed = 0;
  uint64_t keep[kMaxCols / 64];
  for (int row = 0; row < rows; ++row) {
    const uint32_t base = static_cast<uint32_t>(row) * static_cast<uint32_t>(cols);
    for (int w = 0; w < (cols + 63) / 64; ++w) keep[w] = 0;
    for (uint32_t e = 0; e < n; ++e) {
      Arc arc, none;
      if (!ViewRow(views[e], rays, static_cast<uint32_t>(row), &arc, &none)) continue;
      ForArc(arc, none, cols, [&](int col, bool) { keep[col >> 6] |= uint64_t{1} << (col & 63); });
    }
    // mask &= keep over the row's words; bits of other rows are kept.
    uint64_t* words = mask->words().data();
    for (uint32_t w = base >> 6; w <= (base + cols - 1) >> 6; ++w) {
      int off = static_cast<int>(w * 64) - static_cast<int>(base);  // column of the word's bit 0
      uint64_t k = 0;
      for (int b = 0; b < 64;) {
        int col = off + b;  // bits b.. of the word are columns col.. (within one keep word)
        int run = std::min(64 - b, 64 - (col & 63));
        uint64_t ones = run == 64 ? ~uint64_t{0} : (uint64_t{1} << run) - 1;
        uint64_t part = ones;  // another row's pixels: kept
        if (col >= 0 && col < cols) {
          part = (keep[col >> 6] >> (col & 63)) & ones;
          if (col + run > cols) part |= ones & ~((uint64_t{1} << (cols - col)) - 1);
        }
        k |= part << b;
        b += run;
      }
      closed += PopCount(words[w] & ~k);
      words[w] &= k;
    }
  }
  return closed;
}

uint64_t WalkCentres(const Grid& grid, Skip skip, const CentreRays& rays, MaskBits* mask) {
  const uint64_t steps0 = grid.steps();
  uint32_t hint = kNoPatch;  // the last pixel's occluder: neighbours' rays often hit it too
  for (uint32_t p = 0, pixels = mask->bits(); p < pixels; ++p)
    if (mask->IsOpen(p) && grid.Occluded(rays.Of(p), skip, &hint)) mask->Close(p);
  return grid.steps() - steps0;
}

}  // namespace vismask
