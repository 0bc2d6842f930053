// What the raster's files share (internal to src/display/raster.cpp,
// raster_point.cpp, raster_aa.cpp, raster_clip.cpp and framebuffer.cpp):
// the (depth, id) order of samples, the camera-space transform, the
// antialiased pixel's fragment list (drawing and compositing add to it
// alike), the clip to the view, and the two rasters DrawPiece chooses
// between.
#pragma once
#include <cstdint>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <limits>

#include "vismask/display/camera.h"
#include "vismask/display/raster.h"
#include "vismask/solve/patch.h"

namespace vismask {

constexpr float kInf = std::numeric_limits<float>::infinity();

inline bool Nearer(float z, uint32_t id, float zOld, uint32_t idOld) {
  return z < zOld || (z == zOld && id < idOld);
}

inline glm::vec3 ToCamera(const View& view, const glm::vec3& w) {
  glm::vec3 d = w - view.eye;
  return glm::vec3(glm::dot(d, view.right), glm::dot(d, view.up), glm::dot(d, view.forward));
}

// Adds `in` (one id's share of a pixel) to the pixel's list `f`: merged into
// the fragment of the same id (depth: the nearer), else inserted in (depth,
// id) order; what falls off the end is dropped and the pixel marked.
inline void AddFragment(Fragment* f, uint8_t* dropped, const Fragment& in) {
  int k = 0;
  for (; k < kFragments && f[k].id != kNoPatch; ++k) {
    if (f[k].id != in.id) continue;
    f[k].coverage += in.coverage;
    for (int c = 0; c < 3; ++c) f[k].rgb[c] += in.rgb[c];
    f[k].nearest = in.nearest < f[k].nearest ? in.nearest : f[k].nearest;
    f[k].farthest = in.farthest > f[k].farthest ? in.farthest : f[k].farthest;
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

struct Vec2 {
  float x, y;
};

inline float Cross(Vec2 a, Vec2 b) {
  return a.x * b.y - a.y * b.x;
}

// A piece clipped to the view and projected: its corners in pixel
// coordinates, their extent and their depths' range.
struct ScreenPoly {
  Vec2 sp[kMaxPoly];
  int m = 0;
  float minX = kInf, maxX = -kInf, minY = kInf, maxY = -kInf, zMin = kInf, zMax = 0.0f;
};

// Clips camera-space corners q[0 .. nc) to the near plane and the sides of
// the view (one pixel outside it, so the clip's own edges never cross a
// pixel that is drawn) and projects them; false when less than a polygon
// is left (raster_clip.cpp).
bool ClipProject(const View& view, const glm::vec3* q, uint32_t nc, ScreenPoly* out);

// DrawPiece's two rasters (raster.h), each with an instance for untextured
// and one for textured pieces: point sampled (raster_point.cpp) and
// antialiased (raster_aa.cpp).
template <bool kTextured>
void DrawPiecePoint(const View& view, const DisplayPiece& piece, Framebuffer* fb);
template <bool kTextured>
void DrawPieceAa(const View& view, const DisplayPiece& piece, Framebuffer* fb);

}  // namespace vismask
