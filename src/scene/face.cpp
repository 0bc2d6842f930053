#include "vismask/scene/face.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <string>
#include <utility>
#include <vector>

#include "geometry_util.h"
#include "scene_parse.h"

namespace vismask {
namespace {

using objload::Num;
using objload::Str;

// Face checks, relative to the face's size (its largest corner-to-corner
// distance). Planarity: corners may be off the Newell plane by 1e-4 of the
// size (0.06 mm on a 0.6 m wall), far above float rounding (~1e-7), below a
// modelling error (the published Cornell left wall is 1e-3 off, so
// scenes/cornell.obj splits it). The others reject only true degeneracy.
constexpr double kPlanarTol = 1e-4;     // max corner distance from the plane
constexpr double kRepeatTol = 1e-6;     // min distance between two corners
constexpr double kAreaTol = 1e-6;       // min area, times size^2
constexpr double kCollinearTol = 1e-5;  // min |sin| of the angle at a corner

double Orient(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Whether p, known to be on the line ab, lies within the segment ab.
bool OnSegment(glm::dvec2 a, glm::dvec2 b, glm::dvec2 p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}

// Whether the closed segments ab and cd cross or touch.
bool SegmentsMeet(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c, glm::dvec2 d) {
  double o1 = Orient(a, b, c), o2 = Orient(a, b, d), o3 = Orient(c, d, a), o4 = Orient(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
    return true;
  return (o1 == 0 && OnSegment(a, b, c)) || (o2 == 0 && OnSegment(a, b, d)) ||
         (o3 == 0 && OnSegment(c, d, a)) || (o4 == 0 && OnSegment(c, d, b));
}

std::vector<glm::dvec3> Corners(const Polygon& p) {
  std::vector<glm::dvec3> c;
  for (const glm::vec3& v : p.corners) c.emplace_back(v);
  return c;
}

double SizeOf(const std::vector<glm::dvec3>& c) {
  double size = 0.0;
  for (size_t i = 0; i < c.size(); ++i)
    for (size_t j = i + 1; j < c.size(); ++j) size = std::max(size, glm::length(c[i] - c[j]));
  return size;
}

// The main axis of `normal` (the one a projection drops).
int MainAxis(glm::dvec3 normal) {
  glm::dvec3 an = glm::abs(normal);
  return an.x > an.y ? (an.x > an.z ? 0 : 2) : (an.y > an.z ? 1 : 2);
}

// The first pair of non-adjacent edges (i, j) that meet in the projection
// along `normal`'s main axis, or false.
bool EdgesMeet(const std::vector<glm::dvec3>& c, glm::dvec3 normal, size_t* ei, size_t* ej) {
  const size_t n = c.size();
  int axis = MainAxis(normal);
  auto at = [&](size_t i) {
    return glm::dvec2(c[i % n][(axis + 1) % 3], c[i % n][(axis + 2) % 3]);
  };
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 2; j < n; ++j)
      if (!(i == 0 && j == n - 1) && SegmentsMeet(at(i), at(i + 1), at(j), at(j + 1))) {
        *ei = i;
        *ej = j;
        return true;
      }
  return false;
}

// The loader's basic checks: sets the normal and area of a good
// face; else returns why it is not one (the messages --strict prints).
std::string FinishPolygon(Polygon* p) {
  const size_t n = p->corners.size();
  std::vector<glm::dvec3> c = Corners(*p);
  double size = SizeOf(c);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      if (glm::length(c[i] - c[j]) <= kRepeatTol * size)
        return "degenerate face: vertices " + Str(i + 1) + " and " + Str(j + 1) + " coincide";
  for (size_t i = 0; i < n; ++i) {
    glm::dvec3 a = c[(i + n - 1) % n] - c[i], b = c[(i + 1) % n] - c[i];
    if (glm::length(glm::cross(a, b)) <= kCollinearTol * glm::length(a) * glm::length(b))
      return "degenerate face: vertex " + Str(i + 1) + " is collinear with its neighbours";
  }
  // Newell's method, about corner 0 for precision.
  glm::dvec3 sum = NewellSum(c);
  double twiceArea = glm::length(sum);
  if (twiceArea / 2 <= kAreaTol * size * size) return "degenerate face: zero area";
  glm::dvec3 normal = sum / twiceArea;
  glm::dvec3 centroid(0.0);
  for (const glm::dvec3& v : c) centroid += v / static_cast<double>(n);
  for (size_t i = 0; i < n; ++i) {
    double off = std::fabs(glm::dot(normal, c[i] - centroid));
    if (off > kPlanarTol * size)
      return "non-planar face: vertex " + Str(i + 1) + " is " + Num(off) +
             " off the face's plane (tolerance " + Num(kPlanarTol * size) + ")";
  }
  // Simple polygon: no two non-adjacent edges meet (in the plane's projection).
  size_t ei = 0, ej = 0;
  if (EdgesMeet(c, normal, &ei, &ej))
    return "self-intersecting face: edges " + Str(ei + 1) + " and " + Str(ej + 1) + " meet";
  p->normal = glm::vec3(normal);
  p->area = twiceArea / 2;
  return "";
}

// Removes corner i of p (and its uv and vn).
void RemoveCorner(Polygon* p, size_t i) {
  p->corners.erase(p->corners.begin() + static_cast<std::ptrdiff_t>(i));
  if (!p->uv.empty()) p->uv.erase(p->uv.begin() + static_cast<std::ptrdiff_t>(i));
  if (!p->vn.empty()) p->vn.erase(p->vn.begin() + static_cast<std::ptrdiff_t>(i));
}

// Removes corners that repeat the one before or lie on the line through
// their neighbours (tolerances against `size`, the face's as read), until
// none does or fewer than 3 are left; returns how many went.
size_t RemoveDegenerateCorners(Polygon* p, double size) {
  size_t removed = 0;
  bool changed = true;
  while (changed && p->corners.size() >= 3) {
    changed = false;
    std::vector<glm::dvec3> c = Corners(*p);
    const size_t n = c.size();
    for (size_t i = 0; i < n && !changed; ++i) {
      glm::dvec3 a = c[(i + n - 1) % n] - c[i], b = c[(i + 1) % n] - c[i];
      bool repeat = glm::length(a) <= kRepeatTol * size;
      bool collinear =
          glm::length(glm::cross(a, b)) <= kCollinearTol * glm::length(a) * glm::length(b);
      if (repeat || collinear) {
        RemoveCorner(p, i);
        ++removed;
        changed = true;
      }
    }
  }
  return removed;
}

// The triangle of corners (i, j, k) of `face`, with their uv and vn.
Polygon Triangle(const Polygon& face, size_t i, size_t j, size_t k) {
  Polygon t;
  t.material = face.material;
  t.line = face.line;
  t.smoothing = face.smoothing;
  for (size_t q : {i, j, k}) {
    t.corners.push_back(face.corners[q]);
    if (!face.uv.empty()) t.uv.push_back(face.uv[q]);
    if (!face.vn.empty()) t.vn.push_back(face.vn[q]);
  }
  return t;
}

// Splits a non-planar face (3 < corners, simple in its projection) into
// triangles of its corners; false if it finds no split that keeps the
// face's side.
bool SplitNonPlanar(const Polygon& face, glm::dvec3 normal,
                    std::vector<std::array<size_t, 3>>* tris) {
  std::vector<glm::dvec3> c = Corners(face);
  if (c.size() == 4) {
    // The diagonal whose triangles are the flatter pair; each must face
    // the face's way (the other diagonal of a concave quad folds it over).
    double best = -2.0;
    for (size_t d = 0; d < 2; ++d) {
      size_t a = d, b = d + 1, e = d + 2, f = (d + 3) % 4;
      glm::dvec3 n1 = glm::cross(c[b] - c[a], c[e] - c[a]),
                 n2 = glm::cross(c[e] - c[a], c[f] - c[a]);
      if (!(glm::dot(n1, normal) > 0.0 && glm::dot(n2, normal) > 0.0)) continue;
      double flat = glm::dot(glm::normalize(n1), glm::normalize(n2));
      if (flat > best) {
        best = flat;
        *tris = {{{a, b, e}}, {{a, e, f}}};
      }
    }
    return best > -2.0;
  }
  return Triangulate(c, normal, tris);
}

}  // namespace

FaceResult ShapeFace(const Polygon& face, bool strict, std::vector<Polygon>* out) {
  FaceResult r;
  Polygon p = face;
  std::string err = FinishPolygon(&p);
  if (err.empty()) {
    out->push_back(std::move(p));
    return r;
  }
  if (strict) {
    r.fate = FaceResult::kRefused;
    r.error = err;
    return r;
  }
  p = face;
  const double size = SizeOf(Corners(face));
  r.removedCorners = RemoveDegenerateCorners(&p, size);
  std::vector<glm::dvec3> c = Corners(p);
  const size_t n = c.size();
  glm::dvec3 sum = n >= 3 ? NewellSum(c) : glm::dvec3(0.0);
  double twiceArea = glm::length(sum);
  if (n < 3 || twiceArea / 2 <= kAreaTol * size * size) {
    r.fate = FaceResult::kDegenerate;
    return r;
  }
  // Corners that repeat further apart: the outline touches itself.
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      if (glm::length(c[i] - c[j]) <= kRepeatTol * size) {
        r.fate = FaceResult::kSelfIntersecting;
        return r;
      }
  glm::dvec3 normal = sum / twiceArea;
  size_t ei = 0, ej = 0;
  if (EdgesMeet(c, normal, &ei, &ej)) {
    r.fate = FaceResult::kSelfIntersecting;
    return r;
  }
  glm::dvec3 centroid(0.0);
  for (const glm::dvec3& v : c) centroid += v / static_cast<double>(n);
  double off = 0.0;
  for (const glm::dvec3& v : c) off = std::max(off, std::fabs(glm::dot(normal, v - centroid)));
  if (off <= kPlanarTol * size) {
    // Planar once its degenerate corners are gone.
    err = FinishPolygon(&p);
    if (!err.empty()) {
      r.fate = FaceResult::kDegenerate;
      return r;
    }
    out->push_back(std::move(p));
    return r;
  }
  std::vector<std::array<size_t, 3>> tris;
  if (!SplitNonPlanar(p, normal, &tris)) {
    r.fate = FaceResult::kSelfIntersecting;
    return r;
  }
  r.fate = FaceResult::kTriangulated;
  r.offPlane = off;
  size_t kept = 0;
  for (const auto& t : tris) {
    Polygon tri = Triangle(p, t[0], t[1], t[2]);
    if (!FinishPolygon(&tri).empty()) {
      ++r.droppedTriangles;
      continue;
    }
    out->push_back(std::move(tri));
    ++kept;
  }
  if (kept == 0) r.fate = FaceResult::kDegenerate;
  return r;
}

}  // namespace vismask
