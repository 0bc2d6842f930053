#include "vismask/raster.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "vismask/texture.h"

namespace vismask {

void Framebuffer::Layout(Arena& arena, int w, int h, bool antialiased) {
  width = w;
  height = h;
  aa = antialiased;
  size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  color = arena.Alloc<glm::vec3>(n);
  id = arena.Alloc<uint32_t>(n);
  if (aa) {
    frags = arena.Alloc<Fragment>(n * kFragments);
    dropped = arena.Alloc<uint8_t>(n);
  } else {
    depth = arena.Alloc<float>(n);
  }
}

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr Fragment kEmptyFragment = {kInf, kNoPatch, 0.0f, {0.0f, 0.0f, 0.0f}};

}  // namespace

void Framebuffer::Clear() {
  for (size_t i = 0; i < color.size(); ++i) {
    color[i] = glm::vec3(0.0f);
    id[i] = kNoPatch;
  }
  for (float& d : depth) d = kInf;
  for (Fragment& f : frags) f = kEmptyFragment;
  for (uint8_t& d : dropped) d = 0;
}

namespace {

inline bool Nearer(float z, uint32_t id, float zOld, uint32_t idOld) {
  return z < zOld || (z == zOld && id < idOld);
}

// ---------------------------------------------------------------------------
// Point sampled (--aa off): the original raster, kept byte for byte.

// A vertex in camera space (x right, y up, z forward) with its radiance
// (and, textured, its texture coordinates).
template <bool kTextured>
struct CamVert {
  glm::vec3 p;
  glm::vec3 c;
};
template <>
struct CamVert<true> {
  glm::vec3 p;
  glm::vec3 c;
  glm::vec2 uv;
};

template <bool kTextured>
void DrawTriangle(const View& view, const CamVert<kTextured>* v, const DisplayPiece& piece,
                  Framebuffer* fb) {
  const uint32_t id = piece.id;
  float sx[3], sy[3], invZ[3];
  float halfW = 0.5f * static_cast<float>(view.width),
        halfH = 0.5f * static_cast<float>(view.height);
  for (int k = 0; k < 3; ++k) {
    invZ[k] = 1.0f / v[k].p.z;
    sx[k] = halfW + view.focal * v[k].p.x * invZ[k];
    sy[k] = halfH - view.focal * v[k].p.y * invZ[k];
  }
  float area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
  if (!(std::fabs(area) > 0.0f)) return;
  float minX = std::fmin(sx[0], std::fmin(sx[1], sx[2]));
  float maxX = std::fmax(sx[0], std::fmax(sx[1], sx[2]));
  float minY = std::fmin(sy[0], std::fmin(sy[1], sy[2]));
  float maxY = std::fmax(sy[0], std::fmax(sy[1], sy[2]));
  int x0 = std::max(0, static_cast<int>(std::floor(minX - 0.5f)));
  int x1 = std::min(view.width - 1, static_cast<int>(std::ceil(maxX - 0.5f)));
  int y0 = std::max(0, static_cast<int>(std::floor(minY - 0.5f)));
  int y1 = std::min(view.height - 1, static_cast<int>(std::ceil(maxY - 0.5f)));
  float invArea = 1.0f / area;
  for (int y = y0; y <= y1; ++y) {
    float py = static_cast<float>(y) + 0.5f;
    for (int x = x0; x <= x1; ++x) {
      float px = static_cast<float>(x) + 0.5f;
      // Barycentrics from edge functions; inclusive edges leave no cracks.
      float b0 = ((sx[1] - px) * (sy[2] - py) - (sx[2] - px) * (sy[1] - py)) * invArea;
      float b1 = ((sx[2] - px) * (sy[0] - py) - (sx[0] - px) * (sy[2] - py)) * invArea;
      float b2 = 1.0f - b0 - b1;
      if (b0 < 0.0f || b1 < 0.0f || b2 < 0.0f) continue;
      float iz = b0 * invZ[0] + b1 * invZ[1] + b2 * invZ[2];
      float z = 1.0f / iz;
      size_t idx =
          static_cast<size_t>(y) * static_cast<size_t>(view.width) + static_cast<size_t>(x);
      if (!Nearer(z, id, fb->depth[idx], fb->id[idx])) continue;
      glm::vec3 c = (b0 * invZ[0]) * v[0].c + (b1 * invZ[1]) * v[1].c + (b2 * invZ[2]) * v[2].c;
      if constexpr (kTextured) {
        glm::vec2 uv =
            (b0 * invZ[0]) * v[0].uv + (b1 * invZ[1]) * v[1].uv + (b2 * invZ[2]) * v[2].uv;
        fb->color[idx] = piece.ke + piece.texture->Modulation(uv * z) * (c * z - piece.ke);
      } else {
        fb->color[idx] = c * z;
      }
      fb->depth[idx] = z;
      fb->id[idx] = id;
    }
  }
}

// Clips triangle `in` to z >= nearZ (Sutherland-Hodgman, one plane) and
// draws the resulting 0, 1 or 2 triangles.
template <bool kTextured>
void ClipAndDraw(const View& view, const CamVert<kTextured>* in, const DisplayPiece& piece,
                 Framebuffer* fb) {
  using V = CamVert<kTextured>;
  V out[4];
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    const V& a = in[k];
    const V& b = in[(k + 1) % 3];
    bool aIn = a.p.z >= view.nearZ, bIn = b.p.z >= view.nearZ;
    if (aIn) out[n++] = a;
    if (aIn != bIn) {
      float t = (view.nearZ - a.p.z) / (b.p.z - a.p.z);
      V& x = out[n++];
      x.p = a.p + t * (b.p - a.p);
      x.c = a.c + t * (b.c - a.c);
      if constexpr (kTextured) x.uv = a.uv + t * (b.uv - a.uv);
    }
  }
  if (n < 3) return;
  DrawTriangle(view, out, piece, fb);
  if (n == 4) {
    V second[3] = {out[0], out[2], out[3]};
    DrawTriangle(view, second, piece, fb);
  }
}

inline glm::vec3 ToCamera(const View& view, const glm::vec3& w) {
  glm::vec3 d = w - view.eye;
  return glm::vec3(glm::dot(d, view.right), glm::dot(d, view.up), glm::dot(d, view.forward));
}

template <bool kTextured>
void DrawPiecePoint(const View& view, const DisplayPiece& piece, Framebuffer* fb) {
  using V = CamVert<kTextured>;
  V cv[4];
  for (uint32_t k = 0; k < piece.numCorners; ++k) {
    cv[k].p = ToCamera(view, piece.p[k]);
    cv[k].c = piece.c[k];
    if constexpr (kTextured) cv[k].uv = piece.uv[k];
  }
  ClipAndDraw(view, cv, piece, fb);
  if (piece.numCorners == 4) {
    V second[3] = {cv[0], cv[2], cv[3]};
    ClipAndDraw(view, second, piece, fb);
  }
}

// ---------------------------------------------------------------------------
// Antialiased.

// Adds `in` (one id's share of a pixel) to the pixel's list `f`: merged into
// the fragment of the same id (depth: the nearer), else inserted in (depth,
// id) order; what falls off the end is dropped and the pixel marked.
inline void AddFragment(Fragment* f, uint8_t* dropped, const Fragment& in) {
  int k = 0;
  for (; k < kFragments && f[k].id != kNoPatch; ++k) {
    if (f[k].id != in.id) continue;
    f[k].coverage += in.coverage;
    for (int c = 0; c < 3; ++c) f[k].rgb[c] += in.rgb[c];
    if (in.depth < f[k].depth) {
      Fragment moved = f[k];
      moved.depth = in.depth;
      for (; k > 0 && Nearer(moved.depth, moved.id, f[k - 1].depth, f[k - 1].id); --k)
        f[k] = f[k - 1];
      f[k] = moved;
    }
    return;
  }
  // k: the first empty slot, or kFragments. Find the insertion point.
  int at = k;
  while (at > 0 && Nearer(in.depth, in.id, f[at - 1].depth, f[at - 1].id)) --at;
  if (at == kFragments) {
    *dropped = 1;
    return;
  }
  if (k == kFragments) {
    *dropped = 1;  // the last one falls off
    k = kFragments - 1;
  }
  for (; k > at; --k) f[k] = f[k - 1];
  f[at] = in;
}

// A convex polygon in 2D or 3D with a fixed capacity: a quad clipped by the
// near plane and the four sides of the view (5 planes) has at most 9 corners.
constexpr int kMaxPoly = 12;

// Clips `in` (n corners) by the half-space dot(plane.xyz, p) + plane.w >= 0.
// The crossing point of an edge is computed from its endpoints in a fixed
// order (the lexicographically smaller first), so two pieces sharing an edge
// get bit-identical clipped corners.
int ClipPoly(const glm::vec3* in, int n, const glm::vec3& pn, float pw, glm::vec3* out) {
  int m = 0;
  for (int k = 0; k < n; ++k) {
    const glm::vec3& a = in[k];
    const glm::vec3& b = in[(k + 1) % n];
    float fa = glm::dot(pn, a) + pw, fb = glm::dot(pn, b) + pw;
    bool aIn = fa >= 0.0f, bIn = fb >= 0.0f;
    if (aIn) out[m++] = a;
    if (aIn != bIn) {
      bool swap = b.x < a.x || (b.x == a.x && (b.y < a.y || (b.y == a.y && b.z < a.z)));
      const glm::vec3& s = swap ? b : a;
      const glm::vec3& e = swap ? a : b;
      float fs = swap ? fb : fa, fe = swap ? fa : fb;
      float t = fs / (fs - fe);
      out[m++] = s + t * (e - s);
    }
  }
  return m;
}

struct Vec2 {
  float x, y;
};

inline float Cross(Vec2 a, Vec2 b) {
  return a.x * b.y - a.y * b.x;
}

// Area and centroid of the part of convex polygon `poly` (n corners, pixel
// coordinates relative to the pixel's corner) inside the unit square, and
// the range [*lo, *hi] over that part of the affine function
// base + grad.x * x + grad.y * y. Returns the area (0 if none). Inlined into
// both instances of DrawPieceAa, as it was into the one before textures
// (called from two places, GCC no longer inlines it: +4% raster cost).
[[gnu::always_inline]] inline float CoverInUnitSquare(const Vec2* poly, int n, Vec2 grad,
                                                      float base, Vec2* centroid, float* lo,
                                                      float* hi) {
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
  centroid->x = cx / (3.0f * twiceArea);
  centroid->y = cy / (3.0f * twiceArea);
  return std::fmin(area, 1.0f);
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
template <bool kTextured>
glm::vec3 RadianceAt(const PieceSetup& s, const DisplayPiece& piece, Vec2 h) {
  if (s.numCorners == 3) {
    Vec2 e{s.c2[1].x - s.c2[0].x, s.c2[1].y - s.c2[0].y};
    Vec2 f{s.c2[2].x - s.c2[0].x, s.c2[2].y - s.c2[0].y};
    float b1 = Cross(h, f) * s.invDet, b2 = Cross(e, h) * s.invDet;
    b1 = std::fmin(std::fmax(b1, 0.0f), 1.0f);
    b2 = std::fmin(std::fmax(b2, 0.0f), 1.0f - b1);
    glm::vec3 c = (1.0f - b1 - b2) * piece.c[0] + b1 * piece.c[1] + b2 * piece.c[2];
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
                (u * v) * piece.c[2] + ((1.0f - u) * v) * piece.c[3];
  if constexpr (kTextured)
    return Textured(piece, c,
                    ((1.0f - u) * (1.0f - v)) * piece.uv[0] + (u * (1.0f - v)) * piece.uv[1] +
                        (u * v) * piece.uv[2] + ((1.0f - u) * v) * piece.uv[3]);
  return c;
}

template <bool kTextured>
void DrawPieceAa(const View& view, const DisplayPiece& piece, Framebuffer* fb) {
  const uint32_t nc = piece.numCorners;
  glm::vec3 q[4];
  for (uint32_t k = 0; k < nc; ++k) q[k] = ToCamera(view, piece.p[k]);

  // The piece's plane (Newell's normal) and 2D frame.
  PieceSetup s;
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
  if (!(nLen > 0.0f) || !(eLen > 0.0f)) return;
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
    if (det == 0.0f) return;
    s.invDet = 1.0f / det;
  }

  // Clip to the near plane and the sides of the view (one pixel outside it,
  // so the clip's own edges never cross a pixel that is drawn).
  const float halfW = 0.5f * static_cast<float>(view.width),
              halfH = 0.5f * static_cast<float>(view.height);
  const float f = view.focal;
  glm::vec3 bufA[kMaxPoly], bufB[kMaxPoly];
  int m = static_cast<int>(nc);
  for (int k = 0; k < m; ++k) bufA[k] = q[k];
  m = ClipPoly(bufA, m, glm::vec3(0, 0, 1), -view.nearZ, bufB);
  m = ClipPoly(bufB, m, glm::vec3(f, 0, halfW + 1.0f), 0.0f, bufA);
  m = ClipPoly(bufA, m, glm::vec3(-f, 0, halfW + 1.0f), 0.0f, bufB);
  m = ClipPoly(bufB, m, glm::vec3(0, f, halfH + 1.0f), 0.0f, bufA);
  m = ClipPoly(bufA, m, glm::vec3(0, -f, halfH + 1.0f), 0.0f, bufB);
  if (m < 3) return;

  // Project; orient the polygon counter-clockwise in pixel coordinates.
  Vec2 sp[kMaxPoly];
  float minX = kInf, maxX = -kInf, minY = kInf, maxY = -kInf, zMin = kInf, zMax = 0.0f;
  for (int k = 0; k < m; ++k) {
    float invZ = 1.0f / bufB[k].z;
    sp[k] = Vec2{halfW + f * bufB[k].x * invZ, halfH - f * bufB[k].y * invZ};
    minX = std::fmin(minX, sp[k].x), maxX = std::fmax(maxX, sp[k].x);
    minY = std::fmin(minY, sp[k].y), maxY = std::fmax(maxY, sp[k].y);
    zMin = std::fmin(zMin, bufB[k].z), zMax = std::fmax(zMax, bufB[k].z);
  }
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
      float izHi = 0.0f;  // the covered part's nearest: not needed
      if (!inside) {
        Vec2 local[kMaxPoly], c{0.5f, 0.5f};
        for (int k = 0; k < m; ++k) local[k] = Vec2{sp[k].x - fx, sp[k].y - fy};
        cover = CoverInUnitSquare(local, m, Vec2{ia, ib}, izCorner, &c, &izLo, &izHi);
        if (!(cover > 1e-6f)) continue;
        sx = fx + c.x, sy = fy + c.y;
      }
      float zSample = 1.0f / (ia * sx + ib * sy + ic);
      if (!(zSample > 0.0f)) zSample = zMin;
      // The sort key. A front face: its plane's depth at the pixel centre
      // (the same for every piece of a plane, and it keeps a light just
      // below a ceiling in front of it however grazing the view), or the
      // sample's where the centre's ray grazes the plane. A back face: the
      // farthest depth of its covered part, so that at a silhouette a closed
      // object's back face sorts behind the front face sharing its edge.
      float key;
      if (back) {
        key = 1.0f / izLo;
        if (!(key >= zMin && key <= zMax)) key = std::fmin(std::fmax(key, zMin), zMax);
      } else {
        key = 1.0f / (izCorner + 0.5f * ia + 0.5f * ib);
        if (!(key >= 0.5f * zMin && key <= 2.0f * zMax)) key = zSample;
      }
      glm::vec3 pCam = zSample * glm::vec3((sx - halfW) * invF, (halfH - sy) * invF, 1.0f);
      glm::vec3 r = pCam - s.origin;
      glm::vec3 rad = RadianceAt<kTextured>(s, piece, Vec2{glm::dot(r, s.e1), glm::dot(r, s.e2)});
      Fragment in{
          key, piece.id, back ? -cover : cover, {cover * rad.x, cover * rad.y, cover * rad.z}};
      size_t idx =
          static_cast<size_t>(y) * static_cast<size_t>(view.width) + static_cast<size_t>(x);
      AddFragment(&fb->frags[idx * kFragments], &fb->dropped[idx], in);
    }
  }
}

}  // namespace

void DrawPiece(const View& view, const DisplayPiece& piece, Framebuffer* fb) {
  DCHECK(piece.numCorners == 3 || piece.numCorners == 4);
  // Textured pieces take their own instance of each raster, so an untextured
  // one runs the same code per pixel as before textures existed.
  if (fb->aa) {
    if (piece.texture)
      DrawPieceAa<true>(view, piece, fb);
    else
      DrawPieceAa<false>(view, piece, fb);
  } else {
    if (piece.texture)
      DrawPiecePoint<true>(view, piece, fb);
    else
      DrawPiecePoint<false>(view, piece, fb);
  }
}

void RasterPatches(const View& view, Span<const Patch> patches, Span<const glm::vec3> vertices,
                   Span<const glm::vec3> vertexRadiance, Framebuffer* fb) {
  constexpr float kInvPi = 0.318309886183790672f;
  for (const Patch& p : patches) {
    // The back of a one-sided patch reflects nothing: it is drawn black.
    bool facing = glm::dot(p.normal, view.eye - p.corner[0]) > 0.0f;
    DisplayPiece piece;
    piece.numCorners = p.numCorners;
    piece.id = p.globalId;
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      piece.p[k] = vertices[p.vertex[k]];
      piece.c[k] = facing ? kInvPi * vertexRadiance[p.vertex[k]] : glm::vec3(0.0f);
    }
    DrawPiece(view, piece, fb);
  }
}

void CompositeRows(const Framebuffer& band, int firstRow, int rows, Framebuffer* fb) {
  CHECK(band.width == fb->width && band.aa == fb->aa && rows <= band.height);
  CHECK(firstRow >= 0 && firstRow + rows <= fb->height);
  size_t n = static_cast<size_t>(rows) * static_cast<size_t>(fb->width);
  size_t base = static_cast<size_t>(firstRow) * static_cast<size_t>(fb->width);
  if (fb->aa) {
    for (size_t i = 0; i < n; ++i) {
      const Fragment* src = &band.frags[i * kFragments];
      Fragment* dst = &fb->frags[(base + i) * kFragments];
      uint8_t* dropped = &fb->dropped[base + i];
      *dropped |= band.dropped[i];
      for (int k = 0; k < kFragments && src[k].id != kNoPatch; ++k)
        AddFragment(dst, dropped, src[k]);
    }
    return;
  }
  for (size_t i = 0; i < n; ++i) {
    size_t j = base + i;
    if (Nearer(band.depth[i], band.id[i], fb->depth[j], fb->id[j])) {
      fb->color[j] = band.color[i];
      fb->depth[j] = band.depth[i];
      fb->id[j] = band.id[i];
    }
  }
}

void Composite(const Framebuffer& other, Framebuffer* fb) {
  CHECK(other.width == fb->width && other.height == fb->height);
  CompositeRows(other, 0, other.height, fb);
}

namespace {

// One antialiased pixel's fragments composed: its colour, the id with the
// largest visible share, and the share front faces took.
void ResolvePixel(const Fragment* f, bool dropped, glm::vec3* color, uint32_t* id,
                  float* frontShare) {
  float open = 1.0f, front = 0.0f, best = 0.0f;
  uint32_t bestId = kNoPatch;
  glm::vec3 c(0.0f);
  for (int k = 0; k < kFragments && f[k].id != kNoPatch && open > 0.0f; ++k) {
    // A front face takes what is still open (pieces meeting at edges, a
    // silhouette over what is behind: disjoint parts). A back face lies
    // behind its object's front faces, within their silhouette: it shows
    // only where it covers more than the front faces before it took (and
    // is disjoint from other back faces, like the pieces of a wall seen
    // from behind).
    float cover = std::fabs(f[k].coverage);
    bool isFront = f[k].coverage >= 0.0f;
    float w = std::fmin(isFront ? cover : cover - front, open);
    if (!(w > 0.0f)) continue;
    if (isFront) front += w;
    float scale = w / cover;
    c += scale * glm::vec3(f[k].rgb[0], f[k].rgb[1], f[k].rgb[2]);
    open -= w;
    if (w > best) best = w, bestId = f[k].id;
  }
  // Where ids were dropped, the kept ones stand for the whole pixel.
  if (dropped && open > 0.0f && open < 1.0f) c *= 1.0f / (1.0f - open);
  *color = c;
  *id = bestId;
  *frontShare = front;
}

}  // namespace

void Resolve(Framebuffer* fb) {
  if (!fb->aa) return;
  size_t n = fb->color.size();
  float front;
  for (size_t i = 0; i < n; ++i)
    ResolvePixel(&fb->frags[i * kFragments], fb->dropped[i] != 0, &fb->color[i], &fb->id[i],
                 &front);
}

ImageContent InspectImage(const Framebuffer& fb) {
  ImageContent content;
  for (size_t i = 0; i < fb.color.size() && !content.litFront; ++i) {
    if (fb.id[i] == kNoPatch) continue;
    content.surface = true;
    const glm::vec3& c = fb.color[i];
    if (!(c.r > 0.0f || c.g > 0.0f || c.b > 0.0f)) continue;
    float front = 1.0f;
    if (fb.aa) {
      glm::vec3 color;
      uint32_t id;
      ResolvePixel(&fb.frags[i * kFragments], fb.dropped[i] != 0, &color, &id, &front);
    }
    content.litFront = front >= 0.5f;
  }
  return content;
}

}  // namespace vismask
