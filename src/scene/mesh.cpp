#include "vismask/scene/mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <limits>
#include <string>
#include <vector>

#include "geometry_util.h"
#include "vismask/core/check.h"

namespace vismask {
namespace {

// How far a strip's chord may pass from a corner it skips, in patch sizes
// (StripPieces).
constexpr double kStripTolerance = 1.0 / 64.0;

// A part of a polygon to subdivide: a convex quad into an m x n grid of quads,
// or a triangle into n x n similar triangles (m unused).
struct Piece {
  uint32_t polygon;
  int numCorners;
  glm::dvec3 c[4];
  double m, n;
  // A triangle as a fan of n triangles from c[0] to points from c[1] to
  // c[2] (a strip's end, StripPieces), not n x n similar ones.
  bool fan = false;
};

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), x < 1e18 && x == std::floor(x) ? "%.0f" : "%.3g", x);
  return buf;
}

bool IsConvexQuad(const std::vector<glm::dvec3>& c, glm::dvec3 normal) {
  return c.size() == 4 && IsConvex(c, normal);
}

// Appends the patch over lattice vertices v[0..k) of one polygon.
void AddPatch(const Scene& scene, uint32_t polygon, const uint32_t* v, uint32_t k, Mesh* mesh) {
  const Polygon& poly = scene.polygons[polygon];
  const Material& mat = scene.materials[poly.material];
  Patch p{};
  for (uint32_t q = 0; q < 4; ++q) {
    p.vertex[q] = v[std::min(q, k - 1)];
    p.corner[q] = mesh->vertices[p.vertex[q]];
  }
  p.numCorners = k;
  p.normal = poly.normal;
  p.kd = mat.kd;
  p.ke = mat.ke;
  // Area projected on the normal: two triangles (the second is empty for k == 3).
  glm::dvec3 n(poly.normal), a(p.corner[0]), b(p.corner[1]), c(p.corner[2]), d(p.corner[3]);
  p.area = static_cast<float>(
      0.5 * (glm::dot(n, glm::cross(b - a, c - a)) + glm::dot(n, glm::cross(c - a, d - a))));
  p.surface = polygon;
  p.globalId = static_cast<uint32_t>(mesh->patches.size());
  mesh->patches.push_back(p);
}

// Appends an m x n grid over a convex quad: (m+1)(n+1) shared lattice points.
void MeshQuad(const Scene& scene, const Piece& q, Mesh* mesh) {
  const uint64_t m = static_cast<uint64_t>(q.m), n = static_cast<uint64_t>(q.n);
  const uint64_t base = mesh->vertices.size();
  for (uint64_t j = 0; j <= n; ++j) {
    for (uint64_t i = 0; i <= m; ++i) {
      double u = static_cast<double>(i) / q.m, v = static_cast<double>(j) / q.n;
      glm::dvec3 x =
          (1 - u) * (1 - v) * q.c[0] + u * (1 - v) * q.c[1] + u * v * q.c[2] + (1 - u) * v * q.c[3];
      mesh->vertices.emplace_back(x);
    }
  }
  auto at = [&](uint64_t i, uint64_t j) { return static_cast<uint32_t>(base + j * (m + 1) + i); };
  for (uint64_t j = 0; j < n; ++j) {
    for (uint64_t i = 0; i < m; ++i) {
      uint32_t v[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
      AddPatch(scene, q.polygon, v, 4, mesh);
    }
  }
}

// Appends n x n triangles similar to the piece over a triangular lattice of
// (n+1)(n+2)/2 points; point (i, j) is c0 + (i(c1-c0) + j(c2-c0)) / n.
void MeshTriangle(const Scene& scene, const Piece& t, Mesh* mesh) {
  const uint64_t n = static_cast<uint64_t>(t.n);
  const uint64_t base = mesh->vertices.size();
  for (uint64_t j = 0; j <= n; ++j) {
    for (uint64_t i = 0; i + j <= n; ++i) {
      glm::dvec3 x = (static_cast<double>(n - i - j) * t.c[0] + static_cast<double>(i) * t.c[1] +
                      static_cast<double>(j) * t.c[2]) /
                     t.n;
      mesh->vertices.emplace_back(x);
    }
  }
  auto at = [&](uint64_t i, uint64_t j) {
    return static_cast<uint32_t>(base + j * (n + 1) - j * (j - 1) / 2 + i);
  };
  for (uint64_t j = 0; j < n; ++j) {
    for (uint64_t i = 0; i + j < n; ++i) {
      uint32_t up[3] = {at(i, j), at(i + 1, j), at(i, j + 1)};
      AddPatch(scene, t.polygon, up, 3, mesh);
      if (i + j + 1 < n) {
        uint32_t down[3] = {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
        AddPatch(scene, t.polygon, down, 3, mesh);
      }
    }
  }
}

// Appends the fan of t.n triangles from t.c[0] over t.c[1] .. t.c[2]: n + 2
// lattice points.
void MeshFan(const Scene& scene, const Piece& t, Mesh* mesh) {
  const uint64_t n = static_cast<uint64_t>(t.n);
  const uint32_t apex = static_cast<uint32_t>(mesh->vertices.size());
  mesh->vertices.emplace_back(t.c[0]);
  for (uint64_t j = 0; j <= n; ++j) {
    const double f = static_cast<double>(j) / t.n;
    mesh->vertices.emplace_back((1.0 - f) * t.c[1] + f * t.c[2]);
  }
  for (uint64_t j = 0; j < n; ++j) {
    uint32_t v[3] = {apex, static_cast<uint32_t>(apex + 1 + j),
                     static_cast<uint32_t>(apex + 2 + j)};
    AddPatch(scene, t.polygon, v, 3, mesh);
  }
}

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

// Plans the pieces of one polygon (appended to *pieces unless null) and
// counts their patches and lattice vertices.
Status PlanPolygon(const std::string& objPath, const Polygon& poly, uint32_t index, double s,
                   std::vector<Piece>* pieces, double* numPatches, double* numVertices,
                   bool* inStrips = nullptr) {
  if (inStrips) *inStrips = false;
  std::vector<glm::dvec3> c;
  for (const glm::vec3& v : poly.corners) c.emplace_back(v);
  if (IsConvexQuad(c, glm::dvec3(poly.normal))) {
    Piece q{index, 4, {c[0], c[1], c[2], c[3]}, 0.0, 0.0};
    q.m = EdgeDivisions(std::max(glm::length(c[1] - c[0]), glm::length(c[2] - c[3])), s);
    q.n = EdgeDivisions(std::max(glm::length(c[3] - c[0]), glm::length(c[2] - c[1])), s);
    *numPatches += q.m * q.n;
    *numVertices += (q.m + 1) * (q.n + 1);
    if (pieces) pieces->push_back(q);
    return Status::Ok();
  }
  // A convex polygon of many corners whose ear-clipped slivers would make
  // more than twice its area and outline in patches: as strips, when they
  // make fewer (issue 42: a disc of 10,000 corners made a million patches).
  // Any triangulation has n - 2 patches at least: past the bound by that
  // alone, the strips are taken without triangulating.
  const glm::dvec3 normal(poly.normal);
  double perimeter = 0.0;
  for (size_t k = 0; k < c.size(); ++k) perimeter += glm::length(c[(k + 1) % c.size()] - c[k]);
  const double bound = 2.0 * (0.5 * glm::length(NewellSum(c)) / (s * s) + perimeter / s);
  std::vector<Piece> strips;
  double stripPatches = 0.0, stripVertices = 0.0;
  const bool haveStrips = StripPieces(c, normal, index, s, &strips, &stripPatches, &stripVertices);
  auto useStrips = [&]() {
    *numPatches += stripPatches;
    *numVertices += stripVertices;
    if (pieces) pieces->insert(pieces->end(), strips.begin(), strips.end());
    if (inStrips) *inStrips = true;
    return Status::Ok();
  };
  const double fewest = static_cast<double>(c.size()) - 2.0;
  if (haveStrips && fewest > bound && stripPatches < fewest) return useStrips();
  std::vector<std::array<size_t, 3>> tris;
  if (!Triangulate(c, normal, &tris))
    return Status::At(objPath, poly.line, "cannot triangulate face");
  std::vector<Piece> triangles;
  double triPatches = 0.0, triVertices = 0.0;
  for (const auto& tri : tris) {
    Piece t{index, 3, {c[tri[0]], c[tri[1]], c[tri[2]], c[tri[2]]}, 0.0, 0.0};
    double longest = std::max(
        {glm::length(t.c[1] - t.c[0]), glm::length(t.c[2] - t.c[1]), glm::length(t.c[0] - t.c[2])});
    t.n = t.m = EdgeDivisions(longest, s);
    triPatches += t.n * t.n;
    triVertices += (t.n + 1) * (t.n + 2) / 2;
    triangles.push_back(t);
  }
  if (haveStrips && triPatches > bound && stripPatches < triPatches) return useStrips();
  *numPatches += triPatches;
  *numVertices += triVertices;
  if (pieces) pieces->insert(pieces->end(), triangles.begin(), triangles.end());
  return Status::Ok();
}

}  // namespace

Status CountPolygonPatches(const std::string& objPath, const Polygon& polygon, float patchSize,
                           double* patches, double* vertices, bool* strips) {
  return PlanPolygon(objPath, polygon, 0, patchSize, nullptr, patches, vertices, strips);
}

Status MeshesInStrips(const std::string& objPath, const Polygon& polygon, float patchSize,
                      bool* strips, double* areaChange) {
  std::vector<Piece> pieces;
  double patches = 0.0, vertices = 0.0;
  *areaChange = 0.0;
  Status st = PlanPolygon(objPath, polygon, 0, patchSize, &pieces, &patches, &vertices, strips);
  if (!st.ok() || !*strips) return st;
  double area = 0.0;
  for (const Piece& p : pieces) {
    area += 0.5 * glm::length(glm::cross(p.c[1] - p.c[0], p.c[2] - p.c[0]));
    if (!p.fan) area += 0.5 * glm::length(glm::cross(p.c[2] - p.c[0], p.c[3] - p.c[0]));
  }
  if (polygon.area > 0.0) *areaChange = area / polygon.area - 1.0;
  return Status::Ok();
}

double EdgeDivisions(double len, double patchSize) {
  return std::max(1.0, std::ceil(len / patchSize));
}

Status MeshSizeError(double numPatches, float patchSize, uint64_t maxPatches) {
  return Status::Error("the mesh needs " + Num(numPatches) + " patches at patch size " +
                       Num(patchSize) + ", more than the limit of " +
                       Num(static_cast<double>(maxPatches)));
}

Status MeshScene(const Scene& scene, const std::vector<uint32_t>& polygons, float patchSize,
                 uint64_t maxPatches, Mesh* mesh) {
  if (!(std::isfinite(patchSize) && patchSize > 0.0f))
    return Status::Error("patch size must be a positive finite number, got " + Num(patchSize));
  const double s = patchSize;

  // Plan every piece and count, so that nothing is appended on failure.
  std::vector<Piece> pieces;
  double numPatches = 0.0, numVertices = 0.0;
  for (uint32_t index : polygons) {
    CHECK(index < scene.polygons.size());
    Status st = PlanPolygon(scene.objPath, scene.polygons[index], index, s, &pieces, &numPatches,
                            &numVertices);
    if (!st.ok()) return st;
  }
  if (numPatches > static_cast<double>(maxPatches))
    return MeshSizeError(numPatches, patchSize, maxPatches);
  // Patch and vertex ids are 32-bit (kNoPatch is reserved).
  const double kMaxId = static_cast<double>(kNoPatch);
  if (static_cast<double>(mesh->patches.size()) + numPatches >= kMaxId ||
      static_cast<double>(mesh->vertices.size()) + numVertices >= kMaxId)
    return Status::Error("the mesh needs " + Num(numPatches) + " patches and " + Num(numVertices) +
                         " vertices at patch size " + Num(s) + ", more than 32-bit ids allow");

  CHECK_MSG(mesh->twin.empty(), "twins come after every patch: AddTwins after the last MeshScene");
  mesh->patches.reserve(mesh->patches.size() + static_cast<size_t>(numPatches));
  mesh->vertices.reserve(mesh->vertices.size() + static_cast<size_t>(numVertices));
  for (const Piece& piece : pieces) {
    if (piece.fan) {
      MeshFan(scene, piece, mesh);
    } else if (piece.numCorners == 4) {
      MeshQuad(scene, piece, mesh);
    } else {
      MeshTriangle(scene, piece, mesh);
    }
  }
  return Status::Ok();
}

void AddTwins(const TwinOptions& options, Mesh* mesh, const Scene* scene) {
  if (!options.any()) return;
  const uint32_t n = static_cast<uint32_t>(mesh->patches.size());
  CHECK_MSG(mesh->twin.empty(), "AddTwins runs once, on a mesh without twins");
  mesh->twin.assign(n, kNoPatch);
  // Each original vertex a twin uses gets one copy, shared by the twins of
  // the patches around it: the reversed side has a lattice of its own.
  std::vector<uint32_t> copy(mesh->vertices.size(), kNoPatch);
  for (uint32_t i = 0; i < n; ++i) {
    const Patch p = mesh->patches[i];  // a copy: patches grows below
    const bool emits = p.ke.x > 0.0f || p.ke.y > 0.0f || p.ke.z > 0.0f;
    const uint32_t material = options.materials.empty() ? 0 : scene->polygons[p.surface].material;
    if (!options.Twins(material, emits)) continue;
    // corner[0] stays, the rest run backwards; a triangle repeats its last.
    static const uint32_t kQuad[4] = {0, 3, 2, 1}, kTriangle[4] = {0, 2, 1, 1};
    const uint32_t* from = p.numCorners == 4 ? kQuad : kTriangle;
    Patch t = p;
    for (uint32_t q = 0; q < 4; ++q) {
      uint32_t v = p.vertex[from[q]];
      if (copy[v] == kNoPatch) {
        copy[v] = static_cast<uint32_t>(mesh->vertices.size());
        glm::vec3 x = mesh->vertices[v];
        mesh->vertices.push_back(x);
      }
      t.vertex[q] = copy[v];
      t.corner[q] = p.corner[from[q]];
    }
    t.normal = -p.normal;
    if (!options.TwinEmits(material, emits)) t.ke = glm::vec3(0.0f);
    t.globalId = static_cast<uint32_t>(mesh->patches.size());
    mesh->twin[i] = t.globalId;
    mesh->twin.push_back(i);
    mesh->patches.push_back(t);
  }
}

}  // namespace vismask
