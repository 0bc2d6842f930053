#include "vismask/solve/partition.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "../scene/geometry_util.h"
#include "vismask/core/check.h"
#include "vismask/scene/mesh.h"
#include "vismask/scene/texture.h"

namespace vismask {
namespace {

// Clean-up of clipped pieces. Corners closer than kRepeatTol times the
// polygon's size are one corner; a corner whose |sin| is at most kCollinearTol
// is flat (both far below the loader's 1e-5 limits, so only clipping and float
// rounding make them). Pieces under kMinAreaRatio of their polygon are slivers
// left by a plane through a corner or an edge, and dropped.
constexpr double kRepeatTol = 1e-6;
constexpr double kCollinearTol = 1e-6;
constexpr double kMinAreaRatio = 1e-7;

// A corner of a piece; `cut` if clipping made it (it lies on a plane).
struct Corner {
  glm::vec3 p;
  bool cut;
};
using Ring = std::vector<Corner>;

// A clipped piece before it is sorted into place.
struct Piece {
  uint32_t env;
  uint32_t source;
  Polygon polygon;
};

// The point where edge ab crosses plane `value` on `axis`, computed from the
// endpoint lower on the axis so that both pieces sharing the edge get the
// same point; its axis coordinate is exactly `value`.
glm::vec3 Crossing(glm::vec3 a, glm::vec3 b, int axis, float value) {
  if (b[axis] < a[axis]) std::swap(a, b);
  glm::dvec3 u(a), w(b);
  double t = (static_cast<double>(value) - u[axis]) / (w[axis] - u[axis]);
  glm::vec3 x(glm::clamp(u + t * (w - u), glm::min(u, w), glm::max(u, w)));
  x[axis] = value;
  return x;
}

// Sutherland-Hodgman against one plane: keeps the part of `in` whose `axis`
// coordinate is >= value (keepAbove) or <= value. Corners on the plane stay.
Ring ClipHalf(const Ring& in, int axis, float value, bool keepAbove) {
  auto side = [&](const Corner& c) {  // 1 inside, 0 on the plane, -1 outside
    int above = c.p[axis] > value ? 1 : (c.p[axis] < value ? -1 : 0);
    return keepAbove ? above : -above;
  };
  Ring out;
  const size_t n = in.size();
  for (size_t i = 0; i < n; ++i) {
    const Corner& a = in[i];
    const Corner& b = in[(i + 1) % n];
    int sa = side(a), sb = side(b);
    if (sa >= 0) out.push_back(a);
    if (sa * sb < 0) out.push_back({Crossing(a.p, b.p, axis, value), true});
  }
  return out;
}

// Removes repeated corners (within `repeat`; a cut corner outlives an
// original one) and flat corners, until there are none or fewer than 3 left.
void Tidy(double repeat, Ring* ring) {
  Ring& r = *ring;
  bool changed = true;
  while (changed && r.size() >= 3) {
    changed = false;
    for (size_t i = 0; i < r.size() && r.size() >= 3; ++i) {
      const size_t n = r.size(), next = (i + 1) % n;
      if (glm::length(glm::dvec3(r[next].p) - glm::dvec3(r[i].p)) <= repeat) {
        bool dropNext = r[i].cut && !r[next].cut;
        r.erase(r.begin() + static_cast<std::ptrdiff_t>(dropNext ? next : i));
        changed = true;
        break;
      }
    }
    for (size_t i = 0; i < r.size() && r.size() >= 3 && !changed; ++i) {
      const size_t n = r.size();
      glm::dvec3 a(r[(i + n - 1) % n].p), b(r[i].p), c(r[(i + 1) % n].p);
      glm::dvec3 u = b - a, v = c - b;
      if (glm::length(glm::cross(u, v)) <= kCollinearTol * glm::length(u) * glm::length(v)) {
        r.erase(r.begin() + static_cast<std::ptrdiff_t>(i));
        changed = true;
      }
    }
  }
}

// Counts the internal planes (1..n-1) below `x` (orEqual: at or below).
int PlanesBelow(const std::vector<float>& planes, float x, bool orEqual) {
  int count = 0;
  for (size_t k = 1; k + 1 < planes.size(); ++k)
    if (planes[k] < x || (orEqual && planes[k] == x)) ++count;
  return count;
}

// The slabs [*first, *last] of one axis that polygon `p` overlaps with
// positive area. A polygon across the axis (all corners at one coordinate)
// has one slab: on an internal plane, the one its normal points into.
void SlabRange(const std::vector<float>& planes, const Polygon& p, int axis, int* first,
               int* last) {
  float lo = p.corners[0][axis], hi = lo;
  for (const glm::vec3& v : p.corners) {
    lo = std::min(lo, v[axis]);
    hi = std::max(hi, v[axis]);
  }
  if (lo == hi) {
    *first = *last = PlanesBelow(planes, lo, p.normal[axis] >= 0.0f);
  } else {
    *first = PlanesBelow(planes, lo, true);
    *last = PlanesBelow(planes, hi, false);
  }
}

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", x);
  return buf;
}

}  // namespace

Bounds EnvGrid::EnvBox(int index) const {
  CHECK(0 <= index && index < count());
  int c[3];
  Cell(index, c);
  Bounds b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = Plane(a, c[a]);
    b.hi[a] = Plane(a, c[a] + 1);
  }
  return b;
}

float EnvGrid::Plane(int axis, int k) const {
  CHECK(0 <= axis && axis < 3 && 0 <= k && k <= n[axis]);
  if (k == 0) return box.lo[axis];
  if (k == n[axis]) return box.hi[axis];
  if (balanced) return cut[axis][k];
  const float lo = box.lo[axis], hi = box.hi[axis];
  return lo + (hi - lo) * static_cast<float>(k) / static_cast<float>(n[axis]);
}

bool ParseEnvGrid(const char* text, int n[3]) {
  if (text == nullptr) return false;
  int parsed[3] = {1, 1, 1};
  int count = 0;
  const char* s = text;
  for (;;) {
    if (count == 3) return false;
    if (*s < '1' || *s > '9') return false;  // no sign, space, or leading zero
    int value = 0;
    for (; *s >= '0' && *s <= '9'; ++s) {
      value = value * 10 + (*s - '0');
      if (value > kMaxEnvsPerAxis) return false;
    }
    parsed[count++] = value;
    if (*s == '\0') break;
    if (*s++ != 'x') return false;
  }
  std::copy(parsed, parsed + 3, n);
  return true;
}

bool ChooseEnvShape(int count, const glm::vec3& extent, int n[3]) {
  bool found = false;
  double best = 0.0;
  for (int nx = 1; nx <= std::min(count, kMaxEnvsPerAxis); ++nx) {
    if (count % nx) continue;
    for (int ny = 1; ny <= std::min(count / nx, kMaxEnvsPerAxis); ++ny) {
      if ((count / nx) % ny) continue;
      int nz = count / nx / ny;
      if (nz > kMaxEnvsPerAxis) continue;
      const int m[3] = {nx, ny, nz};
      double area = 0.0;
      bool flat = false;
      for (int a = 0; a < 3; ++a) {
        if (m[a] > 1 && !(extent[a] > 0.0f)) flat = true;
        area += (m[a] - 1) * static_cast<double>(extent[(a + 1) % 3]) * extent[(a + 2) % 3];
      }
      if (flat || (found && !(area < best))) continue;
      found = true;
      best = area;
      std::copy(m, m + 3, n);
    }
  }
  return found;
}

double EstimatedPatches(const glm::vec3* c, int n, float patchSize) {
  CHECK(n >= 3 && patchSize > 0.0f);
  auto cells = [&](int i, int j) {
    double len = glm::length(glm::dvec3(c[j]) - glm::dvec3(c[i]));
    return EdgeDivisions(len, patchSize);
  };
  if (n == 4) return std::max(cells(0, 1), cells(2, 3)) * std::max(cells(1, 2), cells(3, 0));
  double longest = 1.0;
  for (int i = 0; i < n; ++i) longest = std::max(longest, cells(i, (i + 1) % n));
  if (n > 4) {
    // A convex polygon of many corners that MeshScene cuts in strips: their
    // count (the sliver estimate would be far too high).
    std::vector<glm::dvec3> d(c, c + n);
    const glm::dvec3 newell = NewellSum(d);
    Polygon poly;
    poly.corners.assign(c, c + n);
    poly.area = 0.5 * glm::length(newell);
    if (poly.area > 0.0) {
      poly.normal = glm::vec3(newell / glm::length(newell));
      double patches = 0.0, vertices = 0.0;
      bool strips = false;
      if (CountPolygonPatches("", poly, patchSize, &patches, &vertices, &strips).ok() && strips)
        return patches;
    }
  }
  return (n - 2) * longest * longest;
}

WorkSplitter::WorkSplitter() {
  for (Axis& a : axis_) a.bins.assign(kBins, 0.0);
}

// Widens axis `a` until [lo, hi] lies inside its bins: each doubling merges
// the bins pairwise into one half, growing towards the side that is short.
void WorkSplitter::Cover(Axis* a, double lo, double hi, double scale) {
  if (a->width == 0.0) {
    // The first polygon: its extent (or, flat on this axis, its size) spans
    // a quarter of the bins, so later polygons rarely force a doubling.
    double span = std::max(hi - lo, scale);
    a->width = 4.0 * span / kBins;
    a->lo = lo - 1.5 * span;
  }
  while (lo < a->lo || hi >= a->lo + a->width * kBins) {
    std::vector<double>& b = a->bins;
    const int half = kBins / 2;
    if (lo < a->lo) {  // grow down: the old bins become the upper half
      for (int j = kBins - 1; j >= half; --j) b[j] = b[2 * (j - half)] + b[2 * (j - half) + 1];
      for (int j = 0; j < half; ++j) b[j] = 0.0;
      a->lo -= a->width * kBins;
    } else {  // grow up: the lower half
      for (int j = 0; j < half; ++j) b[j] = b[2 * j] + b[2 * j + 1];
      for (int j = half; j < kBins; ++j) b[j] = 0.0;
    }
    a->width *= 2.0;
  }
}

void WorkSplitter::Add(const glm::vec3* corners, int n, double area, double weight) {
  CHECK(n >= 3);
  if (!(weight > 0.0) || !(area > 0.0)) return;
  glm::dvec3 lo(corners[0]), hi(corners[0]);
  for (int i = 1; i < n; ++i) {
    lo = glm::min(lo, glm::dvec3(corners[i]));
    hi = glm::max(hi, glm::dvec3(corners[i]));
  }
  const double scale = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, std::sqrt(area)});
  for (int k = 0; k < 3; ++k) {
    Axis& a = axis_[k];
    Cover(&a, lo[k], hi[k], scale);
    double x0 = (lo[k] - a.lo) / a.width, x1 = (hi[k] - a.lo) / a.width;
    int b0 = std::min(kBins - 1, static_cast<int>(x0)),
        b1 = std::min(kBins - 1, static_cast<int>(x1));
    if (b0 == b1) {
      a.bins[b0] += weight;
      continue;
    }
    // Evenly over [x0, x1]: each bin its share of the length.
    const double density = weight / (x1 - x0);
    for (int b = b0; b <= b1; ++b) {
      double from = std::max(x0, static_cast<double>(b)),
             to = std::min(x1, static_cast<double>(b + 1));
      if (to > from) a.bins[b] += density * (to - from);
    }
  }
  total_ += weight;
  ++count_;
}

std::vector<double> WorkSplitter::PlanesOf(int axis, int n, float boxLo, float boxHi) const {
  const Axis& a = axis_[axis];
  if (n <= 1 || a.width == 0.0 || !(boxHi > boxLo)) return {};
  // Edges e (0..kBins) strictly inside the box, and the weight below each.
  std::vector<double> below(kBins + 1, 0.0);
  for (int b = 0; b < kBins; ++b) below[b + 1] = below[b] + a.bins[b];
  const double total = below[kBins];
  if (!(total > 0.0)) return {};
  auto at = [&](int e) { return static_cast<float>(a.lo + a.width * e); };
  int eMin = 0, eMax = kBins;
  while (eMin <= kBins && !(at(eMin) > boxLo)) ++eMin;
  while (eMax >= 0 && !(at(eMax) < boxHi)) --eMax;
  std::vector<double> planes;
  int prev = eMin - 1;
  for (int k = 1; k < n; ++k) {
    const double target = total * k / n;
    // Leave room for the planes still to come.
    const int first = prev + 1, last = eMax - (n - 1 - k);
    if (first > last) return {};
    double bestDist = 0.0;
    int bestFrom = -1, bestTo = -1;
    for (int e = first; e <= last; ++e) {
      double d = std::fabs(below[e] - target);
      if (bestFrom < 0 || d < bestDist) {
        bestDist = d;
        bestFrom = bestTo = e;
      } else if (d == bestDist && bestTo == e - 1) {
        bestTo = e;  // a run of equally near edges (an empty stretch)
      }
    }
    int e = bestFrom + (bestTo - bestFrom) / 2;
    if (!planes.empty() && !(at(e) > static_cast<float>(planes.back()))) return {};
    planes.push_back(at(e));
    prev = e;
  }
  return planes;
}

void WorkSplitter::Planes(EnvGrid* grid) const {
  grid->balanced = true;
  for (int axis = 0; axis < 3; ++axis) {
    const int n = grid->n[axis];
    CHECK(1 <= n && n <= kMaxEnvsPerAxis);
    std::vector<double> planes = PlanesOf(axis, n, grid->box.lo[axis], grid->box.hi[axis]);
    for (int k = 0; k <= n; ++k) grid->cut[axis][k] = 0.0f;
    for (int k = 1; k < n; ++k) {
      const float lo = grid->box.lo[axis], hi = grid->box.hi[axis];
      grid->cut[axis][k] = planes.empty()
                               ? lo + (hi - lo) * static_cast<float>(k) / static_cast<float>(n)
                               : static_cast<float>(planes[k - 1]);
    }
    grid->cut[axis][0] = grid->box.lo[axis];
    grid->cut[axis][n] = grid->box.hi[axis];
  }
}

Status PartitionScene(const Scene& scene, const EnvGrid& grid, Partition* out) {
  for (int a = 0; a < 3; ++a) CHECK(1 <= grid.n[a] && grid.n[a] <= kMaxEnvsPerAxis);
  // The grid's box must hold every corner (NaN boxes fail too).
  for (const Polygon& p : scene.polygons) {
    for (const glm::vec3& v : p.corners) {
      for (int a = 0; a < 3; ++a) {
        if (!(grid.box.lo[a] <= v[a] && v[a] <= grid.box.hi[a]))
          return Status::At(scene.objPath, p.line,
                            "face corner (" + Num(v.x) + ", " + Num(v.y) + ", " + Num(v.z) +
                                ") is outside the environment grid's box");
      }
    }
  }
  std::vector<float> planes[3];
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k <= grid.n[a]; ++k) planes[a].push_back(grid.Plane(a, k));

  std::vector<Piece> pieces;
  for (uint32_t i = 0; i < scene.polygons.size(); ++i) {
    const Polygon& poly = scene.polygons[i];
    int first[3], last[3];
    for (int a = 0; a < 3; ++a) SlabRange(planes[a], poly, a, &first[a], &last[a]);
    // Within one environment: kept whole, exactly as loaded.
    if (first[0] == last[0] && first[1] == last[1] && first[2] == last[2]) {
      pieces.push_back({static_cast<uint32_t>(grid.Index(first[0], first[1], first[2])), i, poly});
      continue;
    }

    // Convex parts, so that every clipped piece is convex.
    std::vector<glm::dvec3> c(poly.corners.begin(), poly.corners.end());
    const glm::dvec3 normal(poly.normal);
    std::vector<Ring> parts;
    std::vector<std::array<size_t, 3>> tris;
    if (!IsConvex(c, normal) && Triangulate(c, normal, &tris)) {
      for (const auto& t : tris)
        parts.push_back({{poly.corners[t[0]], false},
                         {poly.corners[t[1]], false},
                         {poly.corners[t[2]], false}});
    } else {
      // Convex, or no ear found (not a loadable face): Sutherland-Hodgman
      // still conserves its area.
      parts.emplace_back();
      for (const glm::vec3& v : poly.corners) parts.back().push_back({v, false});
    }

    glm::vec3 lo = poly.corners[0], hi = lo;
    for (const glm::vec3& v : poly.corners) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    const double repeat = kRepeatTol * glm::length(glm::dvec3(hi) - glm::dvec3(lo));
    // Texture coordinates of clipped corners: the polygon's affine map.
    const UvMap uvMap = FitUvMap(poly);
    // Cuts ring `r` to slab j of `axis` (a no-op on an axis the polygon does not cross).
    auto toSlab = [&](const Ring& r, int axis, int j) {
      if (first[axis] == last[axis]) return r;
      return ClipHalf(ClipHalf(r, axis, planes[axis][j], true), axis, planes[axis][j + 1], false);
    };
    for (const Ring& part : parts) {
      for (int iz = first[2]; iz <= last[2]; ++iz) {
        Ring rz = toSlab(part, 2, iz);
        if (rz.size() < 3) continue;
        for (int iy = first[1]; iy <= last[1]; ++iy) {
          Ring ry = toSlab(rz, 1, iy);
          if (ry.size() < 3) continue;
          for (int ix = first[0]; ix <= last[0]; ++ix) {
            Ring rx = toSlab(ry, 0, ix);
            Tidy(repeat, &rx);
            if (rx.size() < 3) continue;
            Polygon piece;
            piece.normal = poly.normal;
            piece.material = poly.material;
            piece.line = poly.line;
            std::vector<glm::dvec3> pc;
            for (const Corner& corner : rx) {
              piece.corners.push_back(corner.p);
              pc.emplace_back(corner.p);
              if (!poly.uv.empty()) piece.uv.push_back(uvMap.At(corner.p));
            }
            piece.area = glm::length(NewellSum(pc)) / 2;
            if (piece.area <= kMinAreaRatio * poly.area) continue;
            pieces.push_back({static_cast<uint32_t>(grid.Index(ix, iy, iz)), i, std::move(piece)});
          }
        }
      }
    }
  }

  // By environment; within one, pieces stay in source and piece order.
  std::vector<size_t> order(pieces.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t x, size_t y) { return pieces[x].env < pieces[y].env; });
  Partition result;
  result.grid = grid;
  result.scene.objPath = scene.objPath;
  result.scene.materials = scene.materials;
  result.scene.bounds = scene.bounds;
  result.scene.polygons.reserve(pieces.size());
  result.env.reserve(pieces.size());
  result.source.reserve(pieces.size());
  for (size_t k : order) {
    result.scene.polygons.push_back(std::move(pieces[k].polygon));
    result.env.push_back(pieces[k].env);
    result.source.push_back(pieces[k].source);
  }
  *out = std::move(result);
  return Status::Ok();
}

}  // namespace vismask
