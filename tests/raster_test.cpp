// Raster: exact pixel coverage (a 1-pixel box filter), pieces that tile a
// patch or a plane, bilinear interpolation in a quad's own parameters, and
// the composite's independence of grouping and order.
#include "vismask/display/raster.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <vector>

namespace vismask {
namespace {

constexpr int kW = 64, kH = 64;
constexpr float kFocal = 100.0f;

// Eye at the origin looking +z: at depth kFocal a world unit is a pixel.
View TestView() {
  View v;
  v.eye = glm::vec3(0.0f);
  v.right = glm::vec3(1, 0, 0);
  v.up = glm::vec3(0, 1, 0);
  v.forward = glm::vec3(0, 0, 1);
  v.focal = kFocal;
  v.nearZ = 1e-3f;
  v.width = kW;
  v.height = kH;
  return v;
}

// The world point seen at pixel coordinates (px, py) at depth z.
glm::vec3 AtPixel(double px, double py, double z = kFocal) {
  return glm::vec3(float((px - 0.5 * kW) * z / kFocal), float((0.5 * kH - py) * z / kFocal),
                   float(z));
}

DisplayPiece Piece(std::vector<glm::vec3> p, std::vector<float> c, uint32_t id) {
  DisplayPiece piece{};
  piece.numCorners = static_cast<uint32_t>(p.size());
  piece.id = id;
  for (size_t k = 0; k < p.size(); ++k) {
    piece.p[k] = p[k];
    piece.c[k] = glm::vec3(c[k]);
  }
  return piece;
}

struct Fb {
  Arena arena{1 << 22};
  Framebuffer fb;
  explicit Fb(bool aa, int h = kH) {
    fb.Layout(arena, kW, h, aa);
    fb.Clear();
  }
};

void DrawAll(const std::vector<DisplayPiece>& pieces, Framebuffer* fb) {
  View view = TestView();
  for (const DisplayPiece& p : pieces) DrawPiece(view, p, fb);
  Resolve(fb);
}

// Exact area of the pixel square [x, x+1] x [y, y+1] on the side
// a * px + b * py + c >= 0 (clipping the square by the half-plane).
double HalfPlaneCover(int x, int y, double a, double b, double c) {
  std::vector<std::pair<double, double>> sq = {{x, y}, {x + 1, y}, {x + 1, y + 1}, {x, y + 1}}, out;
  for (size_t k = 0; k < 4; ++k) {
    auto p = sq[k], q = sq[(k + 1) % 4];
    double fp = a * p.first + b * p.second + c, fq = a * q.first + b * q.second + c;
    if (fp >= 0) out.push_back(p);
    if ((fp >= 0) != (fq >= 0)) {
      double t = fp / (fp - fq);
      out.push_back({p.first + t * (q.first - p.first), p.second + t * (q.second - p.second)});
    }
  }
  double area = 0;
  for (size_t k = 0; k < out.size(); ++k) {
    auto p = out[k], q = out[(k + 1) % out.size()];
    area += p.first * q.second - p.second * q.first;
  }
  return std::fabs(0.5 * area);
}

// The largest |pixel - exact coverage| of a white polygon bounded, inside
// the image, by the one edge through pixel points e0 and e1.
double MaxEdgeError(const Framebuffer& fb, glm::dvec2 e0, glm::dvec2 e1, glm::dvec2 inside) {
  double a = -(e1.y - e0.y), b = e1.x - e0.x, c = -(a * e0.x + b * e0.y);
  if (a * inside.x + b * inside.y + c < 0) a = -a, b = -b, c = -c;
  double worst = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      double exact = HalfPlaneCover(x, y, a, b, c);
      worst = std::max(worst, std::fabs(double(fb.color[size_t(y) * kW + x].x) - exact));
    }
  return worst;
}

TEST(RasterTest, StraightEdgeMatchesExactCoverage) {
  // Slope 0.3719 (not axis-aligned, not 45 degrees); the white side reaches
  // well past the image, so the only edge inside it is the slanted one.
  const double s = 0.3719, y0 = 17.21;
  glm::dvec2 e0(-20, y0 - 20 * s), e1(90, y0 + 90 * s);
  // Corners counter-clockwise in the world (y up): seen from the front.
  std::vector<DisplayPiece> face = {
      Piece({AtPixel(-20, 150), AtPixel(90, 150), AtPixel(e1.x, e1.y), AtPixel(e0.x, e0.y)},
            {1, 1, 1, 1}, 7)};
  Fb aa(true), point(false);
  DrawAll(face, &aa.fb);
  DrawAll(face, &point.fb);
  EXPECT_LE(MaxEdgeError(aa.fb, e0, e1, {0, 100}), 0.01);
  // Point sampling is 0 or 1: it misses by up to about a half.
  EXPECT_GT(MaxEdgeError(point.fb, e0, e1, {0, 100}), 0.3);

  // The same in perspective: a triangle on a plane receding in depth (its
  // edge projects to a straight line through the projected endpoints).
  auto project = [](glm::vec3 p) {
    return glm::dvec2(0.5 * kW + double(kFocal) * p.x / p.z, 0.5 * kH - double(kFocal) * p.y / p.z);
  };
  glm::vec3 a = AtPixel(-30, 5, 80), b = AtPixel(100, 40, 160), c = AtPixel(10, 200, 300);
  Fb tilted(true);
  DrawAll({Piece({a, b, c}, {1, 1, 1}, 3)}, &tilted.fb);
  glm::dvec2 pc = project(c);
  EXPECT_LE(MaxEdgeError(tilted.fb, project(a), project(b), pc), 0.01);
}

TEST(RasterTest, BackFacesHideNothingBehindTheirObject) {
  // A black wedge over a white wall: its front face (x from 20.3 to 44 px)
  // and, sharing its left edge, a back face receding behind it. Along that
  // edge the wall shows in exactly the part the front face leaves open.
  glm::vec3 wall[4] = {AtPixel(-10, 80, 300), AtPixel(80, 80, 300), AtPixel(80, -10, 300),
                       AtPixel(-10, -10, 300)};
  glm::vec3 f0 = AtPixel(20.3, 54), f1 = AtPixel(44, 54), f2 = AtPixel(44, 10),
            f3 = AtPixel(20.3, 10);
  // The back face's far edge, at depth 150 (rows 32 -+ 22 * 100 / 150 on screen).
  glm::vec3 b0 = AtPixel(30, 32 - 22.0 * 100 / 150, 150),
            b1 = AtPixel(30, 32 + 22.0 * 100 / 150, 150);
  std::vector<DisplayPiece> scene = {
      Piece({wall[0], wall[1], wall[2], wall[3]}, {1, 1, 1, 1}, 1),
      Piece({f0, f1, f2, f3}, {0, 0, 0, 0}, 2),  // counter-clockwise: the front
      Piece({f3, b1, b0, f0}, {0, 0, 0, 0}, 3),  // clockwise on screen: a back face
  };
  Fb fb(true);
  DrawAll(scene, &fb.fb);
  for (int y = 12; y < 52; ++y) {
    EXPECT_NEAR(fb.fb.color[size_t(y) * kW + 20].x, 0.3f, 1e-4f) << "row " << y;
    EXPECT_NEAR(fb.fb.color[size_t(y) * kW + 19].x, 1.0f, 1e-4f) << "row " << y;
    EXPECT_NEAR(fb.fb.color[size_t(y) * kW + 25].x, 0.0f, 1e-4f) << "row " << y;
  }
}

TEST(RasterTest, BackFacesHideNothingBehindAGrazingFrontFace) {
  // As above, but the front face recedes toward the silhouette edge (x =
  // 20.7 px, depth 200) from depth 100, so its plane at pixel 20's centre,
  // beyond the edge, lies deeper (201.7) than any point of the back face in
  // that pixel (at most 200.3). The back face still hides nothing: pixel 20
  // is the wall's 0.7 and the front face's 0.3. Likewise with a back face
  // at the edge's depth throughout (its covered part ends as deep as the
  // front face's: only the front face's start is nearer).
  glm::vec3 wall[4] = {AtPixel(-10, 80, 300), AtPixel(80, 80, 300), AtPixel(80, -10, 300),
                       AtPixel(-10, -10, 300)};
  const float xEdge = (20.7f - 32.0f) * 2.0f;
  glm::vec3 f0(xEdge, -44, 200), f1(12, -44, 100), f2(12, 44, 100), f3(xEdge, 44, 200);
  for (float backDepth : {210.0f, 200.0f}) {
    const float xBack = (30.0f - 32.0f) * backDepth / kFocal;
    glm::vec3 b0(xBack, -44, backDepth), b1(xBack, 44, backDepth);
    std::vector<DisplayPiece> scene = {
        Piece({wall[0], wall[1], wall[2], wall[3]}, {1, 1, 1, 1}, 1),
        Piece({f0, f1, f2, f3}, {0, 0, 0, 0}, 2),
        Piece({f3, b1, b0, f0}, {0, 0, 0, 0}, 3),
    };
    Fb fb(true);
    DrawAll(scene, &fb.fb);
    for (int y = 12; y < 52; ++y) {
      EXPECT_NEAR(fb.fb.color[size_t(y) * kW + 20].x, 0.7f, 1e-3f) << backDepth << " row " << y;
      EXPECT_NEAR(fb.fb.color[size_t(y) * kW + 19].x, 1.0f, 1e-4f) << backDepth << " row " << y;
      EXPECT_NEAR(fb.fb.color[size_t(y) * kW + 25].x, 0.0f, 1e-4f) << backDepth << " row " << y;
    }
  }
}

TEST(RasterTest, TheInsideOfABoxStaysHiddenBehindItsBack) {
  // A box's near wall seen from behind (a back face receding from depth 100
  // at x = 40.3 px to 150 at the left) and, meeting it at that edge, the
  // box's side wall seen from inside (a front face receding to depth 200,
  // on screen within the near wall). In the edge's pixel the side wall
  // starts where the near wall ends (at the edge) and reaches deeper: it
  // lies behind, and the pixel is the near wall's black.
  const float xEdge = 40.3f - 32.0f, xLeft = (-10.0f - 32.0f) * 1.5f;
  glm::vec3 n0(xLeft, 44, 150), n1(xEdge, 44, 100), n2(xEdge, -44, 100), n3(xLeft, -44, 150);
  glm::vec3 s1(xEdge - 30, 44, 200), s2(xEdge - 30, -44, 200);
  for (bool flip : {false, true}) {
    // Either winding of the pair: the one whose near wall is a back face.
    std::vector<DisplayPiece> scene = {
        flip ? Piece({n3, n2, n1, n0}, {0, 0, 0, 0}, 1) : Piece({n0, n1, n2, n3}, {0, 0, 0, 0}, 1),
        flip ? Piece({s2, s1, n1, n2}, {1, 1, 1, 1}, 2) : Piece({n2, n1, s1, s2}, {1, 1, 1, 1}, 2),
    };
    Fb fb(true);
    DrawAll(scene, &fb.fb);
    const Fragment* f = &fb.fb.frags[(size_t(30) * kW + 40) * kFragments];
    bool nearBack = false, sideFront = false;
    for (int k = 0; k < kFragments; ++k) {
      nearBack |= f[k].id == 1 && f[k].coverage < 0.0f;
      sideFront |= f[k].id == 2 && f[k].coverage > 0.0f;
    }
    if (!(nearBack && sideFront)) continue;
    for (int y = 12; y < 52; ++y) {
      EXPECT_NEAR(fb.fb.color[size_t(y) * kW + 40].x, 0.0f, 1e-4f) << "row " << y;
      EXPECT_NEAR(fb.fb.color[size_t(y) * kW + 30].x, 0.0f, 1e-4f) << "row " << y;
    }
    return;
  }
  ADD_FAILURE() << "no winding gives a back-facing near wall and a front-facing side wall";
}

// The image of a white quad, whole or cut into pieces.
TEST(RasterTest, TwoObjectsEdgesKeepWhatLiesPastBoth) {
  // Two slabs, each a front face and its back face (the same screen
  // rectangle deeper, wound the other way), over a lit far wall: slab A left
  // of x = 20.5 px, slab B right of it and below y = 30.5. Pixel (20, 30)
  // holds five ids, and the wall, the deepest, shows in its upper right
  // quarter (with four kept, the wall fell off and the pixel was black).
  auto slab = [](float x0, float y0, float x1, float y1, float z, uint32_t id) {
    glm::vec3 a = AtPixel(x0, y1, z), b = AtPixel(x1, y1, z), c = AtPixel(x1, y0, z),
              d = AtPixel(x0, y0, z);
    glm::vec3 ab = AtPixel(x0, y1, z + 50), bb = AtPixel(x1, y1, z + 50),
              cb = AtPixel(x1, y0, z + 50), db = AtPixel(x0, y0, z + 50);
    return std::vector<DisplayPiece>{Piece({a, b, c, d}, {0, 0, 0, 0}, id),
                                     Piece({db, cb, bb, ab}, {0, 0, 0, 0}, id + 1)};
  };
  std::vector<DisplayPiece> scene = {Piece(
      {AtPixel(-10, 80, 300), AtPixel(80, 80, 300), AtPixel(80, -10, 300), AtPixel(-10, -10, 300)},
      {1, 1, 1, 1}, 1)};
  for (const DisplayPiece& p : slab(-10, -10, 20.5f, 80, 100, 2)) scene.push_back(p);
  for (const DisplayPiece& p : slab(20.5f, 30.5f, 80, 80, 120, 4)) scene.push_back(p);
  for (bool reversed : {false, true}) {
    if (reversed) std::reverse(scene.begin(), scene.end());
    Fb fb(true);
    DrawAll(scene, &fb.fb);
    EXPECT_NEAR(fb.fb.color[size_t(30) * kW + 20].x, 0.25f, 1e-4f) << reversed;
    EXPECT_NEAR(fb.fb.color[size_t(10) * kW + 20].x, 0.5f, 1e-4f) << reversed;
    EXPECT_NEAR(fb.fb.color[size_t(30) * kW + 40].x, 0.5f, 1e-4f) << reversed;
    EXPECT_NEAR(fb.fb.color[size_t(20) * kW + 40].x, 1.0f, 1e-4f) << reversed;
  }
}

// MarkShown: the fragments Resolve gives a share, the ones whose direct
// light the second pass gathers. A near quad over the left of a wall (its
// edge at x = 20.5 px) and, behind the wall, a quad it hides entirely.
TEST(RasterTest, MarkShownMarksWhatResolveShows) {
  std::vector<DisplayPiece> scene = {Piece({AtPixel(-10, 80, 300), AtPixel(80, 80, 300),
                                            AtPixel(80, -10, 300), AtPixel(-10, -10, 300)},
                                           {1, 1, 1, 1}, 1),
                                     Piece({AtPixel(-10, 80, 100), AtPixel(20.5, 80, 100),
                                            AtPixel(20.5, -10, 100), AtPixel(-10, -10, 100)},
                                           {0, 0, 0, 0}, 2),
                                     Piece({AtPixel(-10, 80, 400), AtPixel(80, 80, 400),
                                            AtPixel(80, -10, 400), AtPixel(-10, -10, 400)},
                                           {1, 1, 1, 1}, 3)};
  Fb fb(true);
  View view = TestView();
  for (const DisplayPiece& p : scene) DrawPiece(view, p, &fb.fb);
  MarkShown(&fb.fb);
  auto shown = [&](int x, int y, uint32_t id) {
    const size_t i = size_t(y) * kW + x;
    for (int k = 0; k < kFragments; ++k)
      if (fb.fb.frags[i * kFragments + k].id == id) return ((fb.fb.shown[i] >> k) & 1u) != 0;
    return false;
  };
  for (int y : {5, 30, 60}) {
    EXPECT_TRUE(shown(10, y, 2) && !shown(10, y, 1) && !shown(10, y, 3)) << y;
    EXPECT_TRUE(shown(20, y, 2) && shown(20, y, 1) && !shown(20, y, 3)) << y;
    EXPECT_TRUE(!shown(40, y, 2) && shown(40, y, 1) && !shown(40, y, 3)) << y;
  }
}

TEST(RasterTest, PiecesSharingEdgesCoverExactlyOnce) {
  // Two coplanar quads of different patches sharing a slanted edge, covering
  // the whole image: every pixel is fully and once covered.
  glm::vec3 tl = AtPixel(-10, -10), tr = AtPixel(80, -10), br = AtPixel(80, 80),
            bl = AtPixel(-10, 80);
  glm::vec3 m0 = AtPixel(23.3, -10), m1 = AtPixel(41.7, 80);  // the shared edge
  // Seen from behind (clockwise on screen) and from the front.
  for (bool reverse : {false, true}) {
    DisplayPiece p1 = Piece({tl, m0, m1, bl}, {0.5f, 0.5f, 0.5f, 0.5f}, 1);
    DisplayPiece p2 = Piece({m0, tr, br, m1}, {0.5f, 0.5f, 0.5f, 0.5f}, 2);
    if (reverse) {
      std::swap(p1.p[1], p1.p[3]);
      std::swap(p2.p[1], p2.p[3]);
    }
    Fb two(true);
    DrawAll({p1, p2}, &two.fb);
    for (size_t i = 0; i < two.fb.color.size(); ++i) {
      ASSERT_NEAR(two.fb.color[i].x, 0.5f, 1e-5f) << "pixel " << i << " reverse " << reverse;
      ASSERT_NE(two.fb.id[i], kNoPatch);
    }
  }

  // A quad rotated by 17 degrees, and the same quad cut into 2 x 2 bilinear
  // sub-quads (and into two triangles) with the same id: the same coverage.
  glm::dvec2 centre(31.3, 30.8), du(20 * std::cos(0.3), 20 * std::sin(0.3)), dv(-du.y, du.x);
  auto at = [&](double u, double v) {
    glm::dvec2 p = centre + (2 * u - 1) * du + (2 * v - 1) * dv * 0.8;
    return AtPixel(p.x, p.y);
  };
  Fb whole(true), quarters(true), halves(true);
  DrawAll({Piece({at(0, 0), at(1, 0), at(1, 1), at(0, 1)}, {1, 1, 1, 1}, 5)}, &whole.fb);
  std::vector<DisplayPiece> four;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      four.push_back(Piece({at(0.5 * i, 0.5 * j), at(0.5 * i + 0.5, 0.5 * j),
                            at(0.5 * i + 0.5, 0.5 * j + 0.5), at(0.5 * i, 0.5 * j + 0.5)},
                           {1, 1, 1, 1}, 5));
  DrawAll(four, &quarters.fb);
  DrawAll({Piece({at(0, 0), at(1, 0), at(1, 1)}, {1, 1, 1}, 5),
           Piece({at(0, 0), at(1, 1), at(0, 1)}, {1, 1, 1}, 5)},
          &halves.fb);
  size_t full = 0, partial = 0;
  for (size_t i = 0; i < whole.fb.color.size(); ++i) {
    float w = whole.fb.color[i].x;
    full += w == 1.0f;
    partial += w > 0.0f && w < 1.0f;
    ASSERT_NEAR(quarters.fb.color[i].x, w, 1e-5f) << "pixel " << i;
    ASSERT_NEAR(halves.fb.color[i].x, w, 1e-5f) << "pixel " << i;
  }
  EXPECT_GT(full, 600u);     // 40 x 32 pixels: the inner ones are whole...
  EXPECT_GT(partial, 100u);  // ...and its slanted border partial
  float area = 0;
  for (const glm::vec3& c : quarters.fb.color) area += c.x;
  EXPECT_NEAR(area, 40.0 * 32.0, 0.01);  // the quad's area in pixels, counted once
}

// (u, v) of point p in the planar quad q (Newton's method, in double).
glm::dvec2 InverseBilinear(const glm::dvec3* q, glm::dvec3 p) {
  glm::dvec2 uv(0.5, 0.5);
  for (int it = 0; it < 50; ++it) {
    glm::dvec3 x = (1 - uv.x) * (1 - uv.y) * q[0] + uv.x * (1 - uv.y) * q[1] + uv.x * uv.y * q[2] +
                   (1 - uv.x) * uv.y * q[3];
    glm::dvec3 xu = (1 - uv.y) * (q[1] - q[0]) + uv.y * (q[2] - q[3]);
    glm::dvec3 xv = (1 - uv.x) * (q[3] - q[0]) + uv.x * (q[2] - q[1]);
    // Least squares step in the plane: [xu xv] d = p - x.
    glm::dvec3 r = p - x;
    double a = glm::dot(xu, xu), b = glm::dot(xu, xv), c = glm::dot(xv, xv);
    double ru = glm::dot(xu, r), rv = glm::dot(xv, r), det = a * c - b * b;
    uv += glm::dvec2((c * ru - b * rv) / det, (a * rv - b * ru) / det);
  }
  return uv;
}

TEST(RasterTest, QuadsAreBilinearInTheirOwnParameters) {
  // Face-on, on pixel edges: corners 0, 0, 0, 1 give (1 - u) v, whose mean
  // over a pixel is its value at the pixel centre.
  std::vector<DisplayPiece> quad = {
      Piece({AtPixel(8, 56), AtPixel(56, 56), AtPixel(56, 8), AtPixel(8, 8)}, {0, 0, 0, 1}, 1)};
  Fb aa(true), point(false);
  DrawAll(quad, &aa.fb);
  DrawAll(quad, &point.fb);
  double worst = 0, split = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      bool in = x >= 8 && x < 56 && y >= 8 && y < 56;
      double u = (x + 0.5 - 8) / 48, v = (56 - y - 0.5) / 48;
      double exact = in ? (1 - u) * v : 0.0;
      size_t i = size_t(y) * kW + x;
      worst = std::max(worst, std::fabs(aa.fb.color[i].x - exact));
      if (in) split = std::max(split, std::fabs(point.fb.color[i].x - exact));
    }
  EXPECT_LE(worst, 1e-4);
  EXPECT_GT(split, 0.1);  // the two Gouraud triangles (0,1,2), (0,2,3) are not bilinear

  // A planar trapezoid receding in depth: at every inner pixel, the radiance
  // of the point the pixel centre's ray meets (perspective-correct).
  glm::dvec3 q[4] = {glm::dvec3(-40, -30, 150), glm::dvec3(40, -30, 150), glm::dvec3(20, 30, 250),
                     glm::dvec3(-25, 30, 250)};
  glm::vec3 qf[4];
  for (int k = 0; k < 4; ++k) qf[k] = glm::vec3(q[k]);
  Fb persp(true);
  DrawAll({Piece({qf[0], qf[1], qf[2], qf[3]}, {0, 0, 0, 1}, 1)}, &persp.fb);
  glm::dvec3 n = glm::normalize(glm::cross(q[1] - q[0], q[3] - q[0]));
  size_t inner = 0;
  worst = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      // Inner: every corner of the pixel lies inside the quad.
      bool allIn = true;
      glm::dvec2 centreUv;
      for (int corner = 0; corner < 5; ++corner) {
        double px = corner < 4 ? x + (corner & 1) : x + 0.5,
               py = corner < 4 ? y + (corner >> 1) : y + 0.5;
        glm::dvec3 r((px - 0.5 * kW) / kFocal, (0.5 * kH - py) / kFocal, 1.0);
        glm::dvec3 p = r * (glm::dot(n, q[0]) / glm::dot(n, r));
        glm::dvec2 uv = InverseBilinear(q, p);
        allIn &= uv.x > 0 && uv.x < 1 && uv.y > 0 && uv.y < 1;
        centreUv = uv;
      }
      if (!allIn) continue;
      ++inner;
      double exact = (1 - centreUv.x) * centreUv.y;
      worst = std::max(worst, std::fabs(persp.fb.color[size_t(y) * kW + x].x - exact));
    }
  EXPECT_GT(inner, 500u);
  EXPECT_LE(worst, 2e-3);  // the pixel's mean against its centre: second order
}

TEST(RasterTest, CompositeMatchesOneFramebufferInAnyOrder) {
  // Overlapping pieces: two at the same depth (the id breaks the tie), one
  // nearer, a patch drawn as two pieces with one id, and a stack of small
  // quads deep enough to overflow kFragments.
  std::vector<DisplayPiece> pieces = {
      Piece({AtPixel(2, 60, 120), AtPixel(50, 60, 120), AtPixel(50, 4, 120), AtPixel(2, 4, 120)},
            {1, 2, 3, 4}, 12),
      Piece(
          {AtPixel(10.5, 50, 120), AtPixel(62, 55, 120), AtPixel(60, 9, 120), AtPixel(14, 3, 120)},
          {2, 2, 2, 2}, 11),
      Piece({AtPixel(20.2, 40, 90), AtPixel(40, 41.3, 90), AtPixel(30, 20.7, 90)}, {5, 1, 0}, 3),
      Piece({AtPixel(5.5, 35, 100), AtPixel(27.3, 36, 100), AtPixel(27.3, 12, 100)},
            {0.5, 0.5, 0.5}, 8),
      Piece({AtPixel(5.5, 35, 100), AtPixel(27.3, 12, 100), AtPixel(5.5, 12, 100)}, {0.5, 0.5, 0.5},
            8),
  };
  for (uint32_t k = 0; k < 6; ++k) {
    double z = 60 + 7 * k, o = 0.37 * k;
    pieces.push_back(Piece({AtPixel(40 + o, 30 + o, z), AtPixel(47 + o, 30, z),
                            AtPixel(47, 22 + o, z), AtPixel(40, 22 - o, z)},
                           {float(k), 1, 1, 1}, 20 + k));
  }
  std::vector<DisplayPiece> reversed(pieces.rbegin(), pieces.rend());
  // Pieces of one id stay in one framebuffer, in their order.
  std::vector<DisplayPiece> a, b;
  for (const DisplayPiece& p : pieces) (p.id % 2 ? a : b).push_back(p);
  View view = TestView();
  auto draw = [&](const std::vector<DisplayPiece>& list, Framebuffer* fb) {
    for (const DisplayPiece& p : list) DrawPiece(view, p, fb);
  };
  for (bool aa : {true, false}) {
    Fb all(aa), back(aa), ab(aa), ba(aa), bands(aa), partB(aa), band(aa, 5);
    draw(pieces, &all.fb);
    draw(reversed, &back.fb);
    draw(a, &ab.fb);
    draw(b, &partB.fb);
    draw(b, &ba.fb);
    draw(a, &bands.fb);
    Composite(partB.fb, &ab.fb);  // a, then b composited in
    {
      Fb partA(aa);
      draw(a, &partA.fb);
      Composite(partA.fb, &ba.fb);  // b, then a composited in
    }
    // b composited into a in bands of 5 rows, as ranks send them.
    for (int y = 0; y < kH; y += 5) {
      int rows = std::min(5, kH - y);
      size_t n = size_t(rows) * kW, first = size_t(y) * kW;
      if (aa) {
        std::memcpy(band.fb.frags.data(), &partB.fb.frags[first * kFragments],
                    n * kFragments * sizeof(Fragment));
        std::memcpy(band.fb.dropped.data(), &partB.fb.dropped[first], n);
      } else {
        std::memcpy(band.fb.color.data(), &partB.fb.color[first], n * sizeof(glm::vec3));
        std::memcpy(band.fb.depth.data(), &partB.fb.depth[first], n * sizeof(float));
        std::memcpy(band.fb.id.data(), &partB.fb.id[first], n * sizeof(uint32_t));
      }
      CompositeRows(band.fb, y, rows, &bands.fb);
    }
    size_t dropped = 0;
    for (Fb* f : {&all, &back, &ab, &ba, &bands}) Resolve(&f->fb);
    for (uint8_t d : all.fb.dropped) dropped += d;
    if (aa) {
      EXPECT_GT(dropped, 10u);  // the stack overflowed the list
    }
    for (Fb* f : {&back, &ab, &ba, &bands}) {
      ASSERT_EQ(0, std::memcmp(all.fb.color.data(), f->fb.color.data(), all.fb.color.bytes()))
          << aa;
      ASSERT_EQ(0, std::memcmp(all.fb.id.data(), f->fb.id.data(), all.fb.id.bytes())) << aa;
      if (aa) {
        ASSERT_EQ(0, std::memcmp(all.fb.frags.data(), f->fb.frags.data(), all.fb.frags.bytes()));
      }
    }
    size_t covered = 0;
    for (uint32_t id : all.fb.id) covered += id != kNoPatch;
    EXPECT_GT(covered, 2000u);
  }
}

}  // namespace
}  // namespace vismask
