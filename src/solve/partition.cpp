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
