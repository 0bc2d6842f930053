#include "grid_cells.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vismask::gridcells {

namespace {

// Why the padding: IntersectPatch's float edge tests accept points up to a
// few ulps of the scene magnitude outside its (pushed-out) edges (kEdgeRel,
// which a sharp corner amplifies, so it is kept small), and hit points and the DDA's
// cell boundaries are rounded too. Every patch is registered with a further
// margin of kPadRel * (scene magnitude), about 300 ulps of the largest
// coordinate, which covers the rest while the ray origin is within kFarRel
// magnitudes of the world origin. Rays from farther away test every patch.
constexpr float kEdgeRel = 8.0f * std::numeric_limits<float>::epsilon();
constexpr float kPadRel = 4e-5f;
constexpr float kFarRel = 8.0f;
constexpr double kClipRel = 1e4;  // half-size of the clip square, in patch sizes

// Conservative fallback for a patch whose plane or edges are not usable.
void CornerShape(const Patch& p, double pad, Shape* s) {
  s->lo = glm::dvec3(std::numeric_limits<double>::infinity());
  s->hi = -s->lo;
  for (uint32_t k = 0; k < p.numCorners && k < 4; ++k) {
    s->lo = glm::min(s->lo, glm::dvec3(p.corner[k]) - pad);
    s->hi = glm::max(s->hi, glm::dvec3(p.corner[k]) + pad);
  }
  s->numAxes = 0;
}

void AddAxis(Shape* s, glm::dvec3 a) {
  double len = glm::length(a);
  if (!(len > 1e-9)) return;
  s->axis[s->numAxes++] = a / len;
}

// Separating axes beyond the box's own, with the prism's (verts: 2 * count,
// the polygon's corners shifted by -+pad along nn) projection on each: the
// plane normal, the side faces and the edge-edge crosses with the box's
// axes. A patch whose normal lies along a box axis (two components exactly
// 0, so nn, u and v are exactly +-1 and 0 and every edge has an exact 0
// along the normal) gets from an edge crossed with a box axis either 0, or
// exactly +-nn, or exactly +-cross(nn, edge): axes already there, which
// separate exactly the same cells (a negated axis negates every
// projection), so unless allAxes they are not added again.
void SeparatingAxes(const glm::dvec3& nn, const glm::dvec3* verts, int count, double pad,
                    bool allAxes, Shape* s) {
  const glm::dvec3 boxAxis[3] = {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)};
  const bool aligned = !allAxes && (nn.x == 0.0) + (nn.y == 0.0) + (nn.z == 0.0) == 2;
  s->numAxes = 0;
  AddAxis(s, nn);
  for (int k = 0; k < count; ++k) {
    glm::dvec3 edge = verts[2 * (k + 1 == count ? 0 : k + 1)] - verts[2 * k];
    double len = glm::length(edge);
    if (!(len > 0.0)) continue;
    edge /= len;
    AddAxis(s, glm::cross(nn, edge));
    if (aligned) continue;
    for (const glm::dvec3& b : boxAxis) AddAxis(s, glm::cross(edge, b));
  }
  for (const glm::dvec3& b : boxAxis) AddAxis(s, glm::cross(nn, b));
  for (int i = 0; i < s->numAxes; ++i) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k = 0; k < 2 * count; ++k) {
      double x = glm::dot(s->axis[i], verts[k]);
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    s->pMin[i] = lo - pad;
    s->pMax[i] = hi + pad;
  }
}

}  // namespace

Scale ScaleOf(Span<const Patch> patches) {
  glm::vec3 lo(std::numeric_limits<float>::infinity());
  glm::vec3 hi(-std::numeric_limits<float>::infinity());
  for (const Patch& p : patches) {
    for (uint32_t k = 0; k < p.numCorners && k < 4; ++k) {
      lo = glm::min(lo, p.corner[k]);
      hi = glm::max(hi, p.corner[k]);
    }
  }
  float mag = 0.0f;
  for (int a = 0; a < 3; ++a) {
    if (!(lo[a] <= hi[a])) continue;
    mag = std::max({mag, std::fabs(lo[a]), std::fabs(hi[a]), hi[a] - lo[a]});
  }
  Scale s;
  s.edgePad = kEdgeRel * mag;
  s.pad = kPadRel * mag;
  s.farLimit = kFarRel * mag;
  return s;
}

void MakeShape(const Patch& p, const PatchGeom& g, const Scale& scale, Shape* s, bool boxOnly,
               bool allAxes) {
  double pad = scale.pad;
  glm::dvec3 n(g.n);
  double nLen = glm::length(n);
  if (!(nLen > 0.5 && nLen < 2.0) || !std::isfinite(g.d)) return CornerShape(p, pad, s);
  glm::dvec3 nn = n / nLen;
  glm::dvec3 u = glm::normalize(
      glm::cross(nn, std::fabs(nn.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
  glm::dvec3 v = glm::cross(nn, u);
  glm::dvec3 p0 = n * (static_cast<double>(g.d) / (nLen * nLen));

  // Clip square around the corners, then clipped by each widened edge.
  uint32_t nc = std::min<uint32_t>(p.numCorners, 4);
  glm::dvec3 centre(0.0);
  double size = 0.0;
  for (uint32_t k = 0; k < nc; ++k) {
    centre += glm::dvec3(p.corner[k]);
    size = std::max(size, glm::length(glm::dvec3(p.corner[(k + 1) % nc] - p.corner[k])));
  }
  centre /= static_cast<double>(nc);
  double ca = glm::dot(u, centre - p0), cb = glm::dot(v, centre - p0);
  double r = kClipRel * (size + pad);
  double poly[2][kMaxPolyVerts + 1][2] = {
      {{ca - r, cb - r}, {ca + r, cb - r}, {ca + r, cb + r}, {ca - r, cb + r}}};
  int count = 4, cur = 0;
  glm::dvec3 corner[4];
  for (int i = 0; i < 4; ++i) corner[i] = GeomCorner(g, i);
  // The corners run counter-clockwise about the normal's side where the
  // plane axis's component is +1.
  const glm::dvec3 up = nn * static_cast<double>(g.n[PlaneAxis(g.n)]);
  for (int i = 0; i < 4; ++i) {
    // The edge's inward plane, through its corners along the normal, moved
    // out by the rounding of the edge test (edgePad, twice: the test runs
    // in a projection, whose distances are up to sqrt(3) times shorter).
    const glm::dvec3 along = corner[(i + 1) & 3] - corner[i];
    if (!(glm::length(along) > 0.0)) continue;  // a triangle's repeated corner
    glm::dvec3 ed = glm::normalize(glm::cross(up, along));
    double ea = glm::dot(ed, u), eb = glm::dot(ed, v);
    double c = glm::dot(ed, corner[i]) - 2.0 * scale.edgePad - glm::dot(ed, p0);
    const double(*in)[2] = poly[cur];
    double(*out)[2] = poly[cur ^ 1];
    int outCount = 0;
    for (int k = 0; k < count; ++k) {
      const double* a = in[k];
      const double* b = in[k + 1 == count ? 0 : k + 1];
      double fa = ea * a[0] + eb * a[1] - c;
      double fb = ea * b[0] + eb * b[1] - c;
      if (fa >= 0.0 && outCount < kMaxPolyVerts) {
        out[outCount][0] = a[0];
        out[outCount][1] = a[1];
        ++outCount;
      }
      if ((fa >= 0.0) != (fb >= 0.0) && outCount < kMaxPolyVerts) {
        double w = fa / (fa - fb);
        out[outCount][0] = a[0] + w * (b[0] - a[0]);
        out[outCount][1] = a[1] + w * (b[1] - a[1]);
        ++outCount;
      }
    }
    count = outCount;
    cur ^= 1;
  }
  // Empty, or still reaching the clip square: a degenerate patch (collinear
  // corners give an unbounded strip). Its corner box keeps the grid sane.
  if (count < 3) return CornerShape(p, pad, s);
  for (int k = 0; k < count; ++k) {
    if (std::fabs(poly[cur][k][0] - ca) > 0.5 * r || std::fabs(poly[cur][k][1] - cb) > 0.5 * r)
      return CornerShape(p, pad, s);
  }

  // Prism corners: the polygon shifted by +-pad along the normal.
  glm::dvec3 verts[2 * kMaxPolyVerts];
  for (int k = 0; k < count; ++k) {
    glm::dvec3 x = p0 + poly[cur][k][0] * u + poly[cur][k][1] * v;
    verts[2 * k] = x - pad * nn;
    verts[2 * k + 1] = x + pad * nn;
  }
  int numVerts = 2 * count;
  s->lo = glm::dvec3(std::numeric_limits<double>::infinity());
  s->hi = -s->lo;
  for (int k = 0; k < numVerts; ++k) {
    s->lo = glm::min(s->lo, verts[k]);
    s->hi = glm::max(s->hi, verts[k]);
  }
  s->lo -= pad;
  s->hi += pad;
  if (!std::isfinite(s->lo.x + s->lo.y + s->lo.z + s->hi.x + s->hi.y + s->hi.z))
    return CornerShape(p, pad, s);
  if (boxOnly) {
    s->numAxes = 0;
    return;
  }

  SeparatingAxes(nn, verts, count, pad, allAxes, s);
}

CellGeometry CellGeometryOf(const Grid::Plan& plan) {
  CellGeometry f;
  f.lo = glm::dvec3(plan.bounds.lo);
  for (int a = 0; a < 3; ++a) {
    f.res[a] = plan.res[a];
    double extent = static_cast<double>(plan.bounds.hi[a]) - plan.bounds.lo[a];
    f.size[a] = extent / plan.res[a];
    f.inv[a] = plan.res[a] / extent;
  }
  return f;
}

}  // namespace vismask::gridcells
