#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <vector>

#include "geometry_util.h"
#include "mesh_internal.h"
#include "vismask/scene/mesh.h"

namespace vismask::meshing {

namespace {

// How far a strip's chord may pass from a corner it skips, in patch sizes
// (StripPieces).
constexpr double kStripTolerance = 1.0 / 64.0;

// A chain of a convex polygon's outline in its plane's frame, u strictly
// increasing: the polygon's bottom or top between its leftmost and
// rightmost points.
struct Chain {
  std::vector<glm::dvec2> p;
  // The point of the chain at `u` (within its range); *seg: the segment
  // it is on, searched from *seg onwards.
  glm::dvec2 At(double u, size_t* seg) const {
    while (*seg + 2 < p.size() && p[*seg + 1].x < u) ++*seg;
    const glm::dvec2 a = p[*seg], b = p[*seg + 1];
    if (u <= a.x) return a;
    if (u >= b.x) return b;
    const double f = (u - a.x) / (b.x - a.x);
    return glm::dvec2(u, a.y + f * (b.y - a.y));
  }
};

// Distance from q to the segment ab.
double SegmentDistance(glm::dvec2 q, glm::dvec2 a, glm::dvec2 b) {
  const glm::dvec2 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0.0 ? std::clamp(glm::dot(q - a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(a + t * ab - q);
}

// How far right of `u` (at x on the chain, on segment `seg`) the next cut
// of the chain may be: its chord from x at most `s` long and every corner
// it passes within `tol` of it.
double ChainLimit(const Chain& ch, double u, glm::dvec2 x, size_t seg, double s, double tol) {
  double limit = u;
  for (size_t j = seg + 1; j < ch.p.size(); ++j) {
    const glm::dvec2 y = ch.p[j];
    bool fits = glm::length(y - x) <= s;
    for (size_t k = seg + 1; fits && k < j; ++k) fits = SegmentDistance(ch.p[k], x, y) <= tol;
    if (fits) {
      limit = y.x;
      continue;
    }
    // The corners up to j - 1 fit: cut on the segment (j - 1, j) where the
    // chord reaches s, if the corners passed stay close to that chord.
    const glm::dvec2 a = j - 1 > seg ? ch.p[j - 1] : x;
    double lo = 0.0, hi = 1.0;  // |x - (a + f (y - a))| <= s at f = lo
    if (glm::length(a - x) > s) return limit;
    for (int it = 0; it < 60; ++it) {
      const double f = 0.5 * (lo + hi);
      (glm::length(a + f * (y - a) - x) <= s ? lo : hi) = f;
    }
    const glm::dvec2 z = a + lo * (y - a);
    bool close = true;
    for (size_t k = seg + 1; close && k < j; ++k) close = SegmentDistance(ch.p[k], x, z) <= tol;
    if (close && z.x > limit) limit = z.x;
    return limit;
  }
  return limit;
}

}  // namespace

// A convex polygon with more corners than a quad, as strips: cut across
// its longest extent into slabs whose outline chords are at most `s` long
// and pass every corner they skip within s * kStripTolerance, each slab a
// column of quads (a fan at a pointed end). Its patches then follow its
// area and outline (about (4/pi) A / s^2 + P / (2 s) for a disc), whatever
// its corner count, where ear clipping made n - 2 slivers of up to
// (longest / s)^2 patches each. False when it does not apply.
bool StripPieces(const std::vector<glm::dvec3>& c, glm::dvec3 normal, uint32_t index, double s,
                 std::vector<Piece>* pieces, double* numPatches, double* numVertices) {
  const size_t n = c.size();
  if (n <= 4) return false;
  // The frame: u along the longest extent from corner 0 (v = normal x u).
  size_t far = 0;
  for (size_t k = 1; k < n; ++k)
    if (glm::length(c[k] - c[0]) > glm::length(c[far] - c[0])) far = k;
  glm::dvec3 e1 = c[far] - c[0];
  e1 = glm::normalize(e1 - glm::dot(e1, normal) * normal);
  const glm::dvec3 e2 = glm::cross(normal, e1);
  std::vector<glm::dvec2> q(n);
  for (size_t k = 0; k < n; ++k)
    q[k] = glm::dvec2(glm::dot(c[k] - c[0], e1), glm::dot(c[k] - c[0], e2));
  auto to3 = [&](glm::dvec2 x) { return c[0] + x.x * e1 + x.y * e2; };
  const double tol = s * kStripTolerance;
  // Convex: every corner turns left, or right by no more than the
  // tolerance (float corners of a tilted disc wobble by far less).
  for (size_t k = 0; k < n; ++k) {
    const glm::dvec2 a = q[(k + n - 1) % n], b = q[k], d = q[(k + 1) % n];
    const double len = glm::length(d - a);
    if (!(len > 0.0) || Cross2(b - a, d - b) < -tol * len) return false;
  }
  // The leftmost corner (the lowest of them) and the rightmost (the
  // highest): counter-clockwise from the first is the bottom chain to the
  // second, clockwise the top.
  size_t lo = 0, hi = 0;
  for (size_t k = 1; k < n; ++k) {
    if (q[k].x < q[lo].x || (q[k].x == q[lo].x && q[k].y < q[lo].y)) lo = k;
    if (q[k].x > q[hi].x || (q[k].x == q[hi].x && q[k].y > q[hi].y)) hi = k;
  }
  Chain bottom, top;
  for (size_t k = lo;; k = (k + 1) % n) {
    bottom.p.push_back(q[k]);
    if (k == hi) break;
  }
  for (size_t k = lo;; k = (k + n - 1) % n) {
    top.p.push_back(q[k]);
    if (k == hi) break;
  }
  // Vertical edges at the ends: the bottom ends at the lowest right corner,
  // the top starts at the highest left one.
  while (bottom.p.size() > 2 && bottom.p[bottom.p.size() - 2].x == bottom.p.back().x)
    bottom.p.pop_back();
  while (top.p.size() > 2 && top.p[1].x == top.p[0].x) top.p.erase(top.p.begin());
  // u strictly increasing: a corner that does not move right (a wobble
  // within the tolerance) is skipped.
  for (Chain* ch : {&bottom, &top}) {
    std::vector<glm::dvec2> kept = {ch->p.front()};
    for (size_t k = 1; k < ch->p.size(); ++k)
      if (ch->p[k].x > kept.back().x) kept.push_back(ch->p[k]);
    ch->p = kept;
  }
  if (bottom.p.size() < 2 || top.p.size() < 2) return false;
  const double uMin = q[lo].x, uMax = q[hi].x;
  if (!(uMax > uMin)) return false;
  std::vector<Piece> out;
  double patches = 0.0, vertices = 0.0;
  size_t segB = 0, segT = 0;
  for (double u = uMin; u < uMax;) {
    const glm::dvec2 bl = bottom.At(u, &segB), tl = top.At(u, &segT);
    double next =
        std::min(ChainLimit(bottom, u, bl, segB, s, tol), ChainLimit(top, u, tl, segT, s, tol));
    if (!(next > u)) return false;  // no progress (cannot happen for a convex polygon)
    if (uMax - next < 1e-12 * (uMax - uMin)) next = uMax;
    size_t sb = segB, st = segT;
    const glm::dvec2 br = bottom.At(next, &sb), tr = top.At(next, &st);
    const double hl = tl.y - bl.y, hr = tr.y - br.y;
    const double chord = std::max(glm::length(br - bl), glm::length(tr - tl));
    Piece piece{index, 4, {to3(bl), to3(br), to3(tr), to3(tl)}, EdgeDivisions(chord, s), 0.0};
    if (hl <= 0.0 || hr <= 0.0) {
      // A pointed end: a fan from the point over the other side.
      piece.numCorners = 3;
      piece.fan = true;
      piece.m = 0.0;
      if (hl <= 0.0) {
        piece.c[0] = to3(bl), piece.c[1] = to3(br), piece.c[2] = to3(tr);
        piece.n = EdgeDivisions(hr, s);
      } else {
        piece.c[0] = to3(br), piece.c[1] = to3(tl), piece.c[2] = to3(bl);
        piece.n = EdgeDivisions(hl, s);
      }
      piece.c[3] = piece.c[2];
      patches += piece.n;
      vertices += piece.n + 2.0;
    } else {
      piece.n = EdgeDivisions(std::max(hl, hr), s);
      patches += piece.m * piece.n;
      vertices += (piece.m + 1.0) * (piece.n + 1.0);
    }
    out.push_back(piece);
    u = next;
  }
  if (pieces) pieces->insert(pieces->end(), out.begin(), out.end());
  *numPatches += patches;
  *numVertices += vertices;
  return true;
}

}  // namespace vismask::meshing
