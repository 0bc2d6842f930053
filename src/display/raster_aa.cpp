// The antialiased raster (raster.h): a piece's plane and 2D frame set up
// once, the piece clipped to the near plane and the view and projected, its
// exact area in each pixel square (the polygon clipped to the square), and
// the radiance at the centroid of the covered part, interpolated in the
// piece's own parameters (barycentric, or inverse bilinear for a quad) and
// modulated by its texture; the result is one fragment per pixel, added to
// the pixel's list (raster_internal.h).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "direct_gather.h"
#include "raster_internal.h"
#include "vismask/display/camera.h"
#include "vismask/display/direct.h"
#include "vismask/display/raster.h"
#include "vismask/scene/texture.h"

namespace vismask {
namespace {

// Area and centroid of the part of convex polygon `poly` (n corners, pixel
// coordinates relative to the pixel's corner) inside the unit square, that
// part's corners (*partCorners of them, at most kMaxPoly + 4, in `part`),
// and the range [*lo, *hi] over it of the affine function
// base + grad.x * x + grad.y * y. Returns the area (0 if none). Inlined into
// both instances of DrawPieceAa, as it was into the one before textures
// (called from two places, GCC no longer inlines it: +4% raster cost).
[[gnu::always_inline]] inline float CoverInUnitSquare(const Vec2* poly, int n, Vec2 grad,
                                                      float base, Vec2* centroid, float* lo,
                                                      float* hi, Vec2* part, int* partCorners) {
  Vec2 a[kMaxPoly + 4], b[kMaxPoly + 4];
  // Four axis-aligned clips: x >= 0, x <= 1, y >= 0, y <= 1.
  auto clip = [](const Vec2* in, int m, Vec2* out, int axis, float bound, float sign) {
    int r = 0;
    for (int k = 0; k < m; ++k) {
      Vec2 p = in[k], q = in[(k + 1) % m];
      float fp = sign * ((axis == 0 ? p.x : p.y) - bound);
      float fq = sign * ((axis == 0 ? q.x : q.y) - bound);
      bool pIn = fp >= 0.0f, qIn = fq >= 0.0f;
      if (pIn) out[r++] = p;
      if (pIn != qIn) {
        float t = fp / (fp - fq);
        Vec2 x{p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
        if (axis == 0)
          x.x = bound;
        else
          x.y = bound;
        out[r++] = x;
      }
    }
    return r;
  };
  int m = clip(poly, n, a, 0, 0.0f, 1.0f);
  m = clip(a, m, b, 0, 1.0f, -1.0f);
  m = clip(b, m, a, 1, 0.0f, 1.0f);
  m = clip(a, m, b, 1, 1.0f, -1.0f);
  if (m < 3) return 0.0f;
  float twiceArea = 0.0f, cx = 0.0f, cy = 0.0f;
  *lo = kInf, *hi = -kInf;
  for (int k = 0; k < m; ++k) {
    Vec2 p = b[k], q = b[(k + 1) % m];
    float g = base + grad.x * p.x + grad.y * p.y;
    *lo = std::fmin(*lo, g), *hi = std::fmax(*hi, g);
    float cr = Cross(p, q);
    twiceArea += cr;
    cx += (p.x + q.x) * cr;
    cy += (p.y + q.y) * cr;
  }
  float area = 0.5f * std::fabs(twiceArea);
  if (!(area > 0.0f)) return 0.0f;
  for (int k = 0; k < m; ++k) part[k] = b[k];
  *partCorners = m;
  centroid->x = cx / (3.0f * twiceArea);
  centroid->y = cy / (3.0f * twiceArea);
  return std::fmin(area, 1.0f);
}

struct SortKey {
  float depth, nearest, farthest;
};

// A fragment's sort depth and its covered part's nearest and farthest
// depths, from 1/depth at the pixel centre and the covered part's greatest
// and least 1/depth. A front
// face sorts by its plane's depth at the pixel centre (the same for every
// piece of a plane, and it keeps a light just below a ceiling in front of
// it however grazing the view), or the sample's where the centre's ray
// grazes the plane. A back face: the farthest depth of its covered part, so
// that at a silhouette a closed object's back face sorts behind the front
// face sharing its edge. Resolve also reads the covered part's depths.
inline SortKey FragmentKey(bool back, float izCentre, float izLo, float izHi, float zMin,
                           float zMax, float zSample) {
  SortKey k;
  auto clamped = [&](float z) { return std::fmin(std::fmax(z, zMin), zMax); };
  k.farthest = 1.0f / izLo;
  if (!(k.farthest >= zMin && k.farthest <= zMax)) k.farthest = clamped(k.farthest);
  k.nearest = 1.0f / izHi;
  if (!(k.nearest >= zMin && k.nearest <= zMax)) k.nearest = clamped(k.nearest);
  if (back) {
    k.depth = k.farthest;
    return k;
  }
  k.depth = 1.0f / izCentre;
  if (!(k.depth >= 0.5f * zMin && k.depth <= 2.0f * zMax)) k.depth = zSample;
  return k;
}

// Whether point q lies in convex polygon `p` (m corners, either winding).
inline bool InPolygon(const Vec2* p, int m, Vec2 q) {
  bool neg = false, pos = false;
  for (int k = 0; k < m; ++k) {
    const Vec2 a = p[k], b = p[(k + 1) % m];
    const float c = Cross(Vec2{b.x - a.x, b.y - a.y}, Vec2{q.x - a.x, q.y - a.y});
    neg |= c < 0.0f;
    pos |= c > 0.0f;
  }
  return !(neg && pos);
}

// A piece's plane as pixels see it: 1/depth = ia x + ib y + ic at (x, y).
struct PixelPlane {
  float ia, ib, ic, halfW, halfH, invF;
  float zFallback;  // the depth where the ray grazes the plane
  glm::vec3 WorldAt(const View& view, float px, float py) const {
    float z = 1.0f / (ia * px + ib * py + ic);
    if (!(z > 0.0f)) z = zFallback;
    glm::vec3 pc = z * glm::vec3((px - halfW) * invF, (halfH - py) * invF, 1.0f);
    return view.eye + pc.x * view.right + pc.y * view.up + pc.z * view.forward;
  }
};

// Per-pixel direct light of a piece at pixel (x, y), E0 at the covered
// centroid (sx, sy): samples over the pixel square, or over the covered part
// `part` (relative to the pixel's corner) where it covers part: the offsets
// that fall in it, in order (a subset of a low-discrepancy sequence stays
// well spread), at most kOffsetTries tried a sample, then the centroid.
inline glm::vec3 PieceDirect(const View& view, const DirectHook& dh, const PixelPlane& plane, int x,
                             int y, float sx, float sy, const Vec2* part, int partCorners,
                             bool mayBeHidden = true) {
  constexpr uint32_t kOffsetTries = 16;
  const float fx = static_cast<float>(x), fy = static_cast<float>(y);
  const uint32_t pixel =
      static_cast<uint32_t>(y) * static_cast<uint32_t>(view.width) + static_cast<uint32_t>(x);
  const glm::vec3 centre = plane.WorldAt(view, sx, sy);
  const DirectPixelSequence offsets(pixel, DirectPixelSequence::Kind::kOffset);
  uint32_t tried = 0;
  return GatherDirect(
      dh, centre, pixel,
      [&](uint32_t k) {
        if (!part) {
          const glm::vec2 off = offsets(k);
          return plane.WorldAt(view, fx + off.x, fy + off.y);
        }
        while (tried < kOffsetTries * dh.samples) {
          const glm::vec2 off = offsets(tried++);
          if (InPolygon(part, partCorners, Vec2{off.x, off.y}))
            return plane.WorldAt(view, fx + off.x, fy + off.y);
        }
        return centre;
      },
      mayBeHidden ? &view.eye : nullptr);
}

// What a piece needs per pixel, set up once.
struct PieceSetup {
  glm::vec3 n;       // plane normal, camera space (not unit)
  float d;           // plane: dot(n, p) = d
  glm::vec3 origin;  // corner 0, camera space
  glm::vec3 e1, e2;  // the plane's 2D frame
  Vec2 c2[4];        // corners in that frame
  float invDet = 0;  // triangles: 1 / Cross(c2[1] - c2[0], c2[2] - c2[0])
  uint32_t numCorners;
};

// The texture's modulation of the interpolated radiance `c` at `uv`.
inline glm::vec3 Textured(const DisplayPiece& piece, const glm::vec3& c, glm::vec2 uv) {
  return piece.ke + piece.texture->Modulation(uv) * (c - piece.ke);
}

// The piece's parameters at 2D plane point `h` (relative to corner 0) and the
// radiance there.
// `extra` (per-pixel direct light) is added to the interpolated radiance
// before the texture modulates it.
template <bool kTextured>
glm::vec3 RadianceAt(const PieceSetup& s, const DisplayPiece& piece, Vec2 h,
                     const glm::vec3& extra) {
  if (s.numCorners == 3) {
    Vec2 e{s.c2[1].x - s.c2[0].x, s.c2[1].y - s.c2[0].y};
    Vec2 f{s.c2[2].x - s.c2[0].x, s.c2[2].y - s.c2[0].y};
    float b1 = Cross(h, f) * s.invDet, b2 = Cross(e, h) * s.invDet;
    b1 = std::fmin(std::fmax(b1, 0.0f), 1.0f);
    b2 = std::fmin(std::fmax(b2, 0.0f), 1.0f - b1);
    glm::vec3 c = (1.0f - b1 - b2) * piece.c[0] + b1 * piece.c[1] + b2 * piece.c[2] + extra;
    if constexpr (kTextured)
      return Textured(piece, c,
                      (1.0f - b1 - b2) * piece.uv[0] + b1 * piece.uv[1] + b2 * piece.uv[2]);
    return c;
  }
  // Inverse bilinear map: p = a + e u + f v + g u v (corner 0 at the origin).
  Vec2 e{s.c2[1].x, s.c2[1].y}, f{s.c2[3].x, s.c2[3].y};
  Vec2 g{s.c2[2].x - s.c2[1].x - s.c2[3].x, s.c2[2].y - s.c2[1].y - s.c2[3].y};
  float k2 = Cross(g, f), k1 = Cross(e, f) + Cross(h, g), k0 = Cross(h, e);
  float v;
  if (k2 == 0.0f) {
    v = k1 != 0.0f ? -k0 / k1 : 0.0f;
  } else {
    // Both roots, computed stably; the one nearer [0, 1] is the point's.
    float disc = std::sqrt(std::fmax(k1 * k1 - 4.0f * k0 * k2, 0.0f));
    float q = -0.5f * (k1 + (k1 >= 0.0f ? disc : -disc));
    float v1 = q / k2, v2 = q != 0.0f ? k0 / q : v1;
    auto outside = [](float t) { return t < 0.0f ? -t : (t > 1.0f ? t - 1.0f : 0.0f); };
    v = outside(v2) <= outside(v1) ? v2 : v1;
  }
  Vec2 w{e.x + g.x * v, e.y + g.y * v};
  float ww = w.x * w.x + w.y * w.y;
  float u = ww > 0.0f ? ((h.x - f.x * v) * w.x + (h.y - f.y * v) * w.y) / ww : 0.0f;
  u = std::fmin(std::fmax(u, 0.0f), 1.0f);
  v = std::fmin(std::fmax(v, 0.0f), 1.0f);
  glm::vec3 c = ((1.0f - u) * (1.0f - v)) * piece.c[0] + (u * (1.0f - v)) * piece.c[1] +
                (u * v) * piece.c[2] + ((1.0f - u) * v) * piece.c[3] + extra;
  if constexpr (kTextured)
    return Textured(piece, c,
                    ((1.0f - u) * (1.0f - v)) * piece.uv[0] + (u * (1.0f - v)) * piece.uv[1] +
                        (u * v) * piece.uv[2] + ((1.0f - u) * v) * piece.uv[3]);
  return c;
}

// The piece's plane (Newell's normal) and 2D frame from its corners in
// camera space, q[0 .. nc); false for a degenerate piece.
bool PlaneSetup(const glm::vec3* q, uint32_t nc, PieceSetup* out) {
  PieceSetup& s = *out;
  s.numCorners = nc;
  glm::vec3 n(0.0f), mid(0.0f);
  for (uint32_t k = 0; k < nc; ++k) {
    const glm::vec3& a = q[k];
    const glm::vec3& b = q[(k + 1) % nc];
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
    mid += a;
  }
  float nLen = glm::length(n);
  glm::vec3 edge = q[1] - q[0];
  float eLen = glm::length(edge);
  if (!(nLen > 0.0f) || !(eLen > 0.0f)) return false;
  s.n = n / nLen;
  s.d = glm::dot(s.n, mid / static_cast<float>(nc));
  s.origin = q[0];
  s.e1 = edge / eLen;
  s.e2 = glm::cross(s.n, s.e1);
  for (uint32_t k = 0; k < nc; ++k) {
    glm::vec3 r = q[k] - q[0];
    s.c2[k] = Vec2{glm::dot(r, s.e1), glm::dot(r, s.e2)};
  }
  if (nc == 3) {
    float det = Cross(Vec2{s.c2[1].x - s.c2[0].x, s.c2[1].y - s.c2[0].y},
                      Vec2{s.c2[2].x - s.c2[0].x, s.c2[2].y - s.c2[0].y});
    if (det == 0.0f) return false;
    s.invDet = 1.0f / det;
  }

  return true;
}

// A pixel (x, y) and the point (sx, sy) a piece shades there.
struct PixelPoint {
  int x, y;
  float sx, sy;
};

// DrawPass::kDirect: the piece's direct light at pixel `idx` (covering
// `cover` of it), gathered only where its id's fragment shows, and added to
// that fragment as the whole pass would have (the radiance with it less
// the radiance without it: a texture modulates it too).
template <bool kTextured>
void AddShownDirect(const View& view, const PieceSetup& s, const DisplayPiece& piece,
                    const PixelPlane& plane, PixelPoint at, const Vec2* part, int partCorners,
                    float cover, Vec2 h, size_t idx, Framebuffer* fb) {
  Fragment* f = &fb->frags[idx * kFragments];
  int k = 0;
  while (k < kFragments && f[k].id != piece.id) ++k;
  if (k == kFragments || !((fb->shown[idx] >> k) & 1u)) return;
  // Split by other pieces, it gathers its share of the samples
  // (PartSamples). The nearest fragment and the only one shown, with none
  // dropped: nothing nearer covers any of the pixel, so no sample point is
  // hidden from the eye and none is tested.
  DirectHook dh = *piece.direct;
  if (part) dh.samples = PartSamples(dh.samples, cover);
  const bool alone = k == 0 && fb->shown[idx] == 1u && fb->dropped[idx] == 0;
  const glm::vec3 extra =
      PieceDirect(view, dh, plane, at.x, at.y, at.sx, at.sy, part, partCorners, !alone);
  const glm::vec3 d = RadianceAt<kTextured>(s, piece, h, extra) -
                      RadianceAt<kTextured>(s, piece, h, glm::vec3(0.0f));
  for (int c = 0; c < 3; ++c) f[k].rgb[c] += cover * d[c];
}

}  // namespace

template <bool kTextured>
void DrawPieceAa(const View& view, const DisplayPiece& piece, Framebuffer* fb) {
  const uint32_t nc = piece.numCorners;
  glm::vec3 q[4];
  for (uint32_t k = 0; k < nc; ++k) q[k] = ToCamera(view, piece.p[k]);
  PieceSetup s;
  s.numCorners = nc;
  if (!PlaneSetup(q, nc, &s)) return;
  ScreenPoly poly;
  if (!ClipProject(view, q, nc, &poly)) return;
  const float halfW = 0.5f * static_cast<float>(view.width),
              halfH = 0.5f * static_cast<float>(view.height);
  const float f = view.focal;
  // Orient the polygon counter-clockwise in pixel coordinates.
  Vec2* sp = poly.sp;
  const int m = poly.m;
  const float minX = poly.minX, maxX = poly.maxX, minY = poly.minY, maxY = poly.maxY;
  const float zMin = poly.zMin, zMax = poly.zMax;
  float twice = 0.0f;
  for (int k = 0; k < m; ++k) twice += Cross(sp[k], sp[(k + 1) % m]);
  if (!(std::fabs(twice) > 0.0f)) return;
  // Corners counter-clockwise from the front turn clockwise in pixel
  // coordinates (y down): positive area is the back of the piece.
  const bool back = twice > 0.0f;
  if (twice < 0.0f) std::reverse(sp, sp + m);
  // Edge functions A x + B y + C >= 0 inside.
  float ea[kMaxPoly], eb[kMaxPoly], ec[kMaxPoly];
  for (int k = 0; k < m; ++k) {
    Vec2 a = sp[k], b = sp[(k + 1) % m];
    ea[k] = a.y - b.y;
    eb[k] = b.x - a.x;
    ec[k] = -(ea[k] * a.x + eb[k] * a.y);
  }

  int x0 = std::max(0, static_cast<int>(std::floor(minX)));
  int x1 = std::min(view.width - 1, static_cast<int>(std::ceil(maxX)) - 1);
  int y0 = std::max(0, static_cast<int>(std::floor(minY)));
  int y1 = std::min(view.height - 1, static_cast<int>(std::ceil(maxY)) - 1);
  const float invF = 1.0f / f;
  // 1/depth on the plane is affine in pixel coordinates: iz(x, y) = ia x + ib y + ic.
  if (s.d == 0.0f) return;  // the plane passes through the eye
  if (y0 <= y1) fb->MarkDirty(y0, y1);
  const float ia = s.n.x * invF / s.d, ib = -s.n.y * invF / s.d;
  const float ic = (s.n.z - s.n.x * halfW * invF + s.n.y * halfH * invF) / s.d;
  for (int y = y0; y <= y1; ++y) {
    float fy = static_cast<float>(y);
    for (int x = x0; x <= x1; ++x) {
      float fx = static_cast<float>(x);
      // Classify the pixel square against each edge: the extremes of a
      // linear function over the square are at its corners.
      bool inside = true, outside = false;
      for (int k = 0; k < m; ++k) {
        float e = ea[k] * fx + eb[k] * fy + ec[k];
        float lo = e + std::fmin(ea[k], 0.0f) + std::fmin(eb[k], 0.0f);
        float hi = e + std::fmax(ea[k], 0.0f) + std::fmax(eb[k], 0.0f);
        inside &= lo >= 0.0f;
        outside |= hi <= 0.0f;
      }
      if (outside) continue;
      float cover = 1.0f;
      float sx = fx + 0.5f, sy = fy + 0.5f;  // where the radiance is taken
      float izCorner = ia * fx + ib * fy + ic;
      float izLo = izCorner + std::fmin(ia, 0.0f) + std::fmin(ib, 0.0f);
      float izHi = izCorner + std::fmax(ia, 0.0f) + std::fmax(ib, 0.0f);
      Vec2 part[kMaxPoly + 4];  // the covered part, where the piece covers the pixel in part
      int partCorners = 0;
      if (!inside) {
        Vec2 local[kMaxPoly], c{0.5f, 0.5f};
        for (int k = 0; k < m; ++k) local[k] = Vec2{sp[k].x - fx, sp[k].y - fy};
        cover = CoverInUnitSquare(local, m, Vec2{ia, ib}, izCorner, &c, &izLo, &izHi, part,
                                  &partCorners);
        if (!(cover > 1e-6f)) continue;
        sx = fx + c.x, sy = fy + c.y;
      }
      float zSample = 1.0f / (ia * sx + ib * sy + ic);
      if (!(zSample > 0.0f)) zSample = zMin;
      const SortKey key =
          FragmentKey(back, izCorner + 0.5f * ia + 0.5f * ib, izLo, izHi, zMin, zMax, zSample);
      glm::vec3 pCam = zSample * glm::vec3((sx - halfW) * invF, (halfH - sy) * invF, 1.0f);
      glm::vec3 r = pCam - s.origin;
      const Vec2 h{glm::dot(r, s.e1), glm::dot(r, s.e2)};
      size_t idx =
          static_cast<size_t>(y) * static_cast<size_t>(view.width) + static_cast<size_t>(x);
      const PixelPlane plane{ia, ib, ic, halfW, halfH, invF, zSample};
      const Vec2* covered = inside ? nullptr : part;
      if (fb->pass == DrawPass::kDirect) {
        if (piece.direct)
          AddShownDirect<kTextured>(view, s, piece, plane, PixelPoint{x, y, sx, sy}, covered,
                                    partCorners, cover, h, idx, fb);
        continue;
      }
      glm::vec3 extra(0.0f);
      if (piece.direct && fb->pass == DrawPass::kWhole)
        extra = PieceDirect(view, *piece.direct, plane, x, y, sx, sy, covered, partCorners);
      glm::vec3 rad = RadianceAt<kTextured>(s, piece, h, extra);
      Fragment in{key.depth,
                  piece.id,
                  back ? -cover : cover,
                  {cover * rad.x, cover * rad.y, cover * rad.z},
                  key.nearest,
                  key.farthest};
      AddFragment(&fb->frags[idx * kFragments], &fb->dropped[idx], in);
    }
  }
}

template void DrawPieceAa<false>(const View& view, const DisplayPiece& piece, Framebuffer* fb);
template void DrawPieceAa<true>(const View& view, const DisplayPiece& piece, Framebuffer* fb);

}  // namespace vismask
