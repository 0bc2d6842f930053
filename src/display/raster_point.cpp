// The point-sampled raster (--aa off; raster.h): the original raster, kept
// byte for byte. Each triangle is clipped to the near plane and drawn with
// edge functions at pixel centres, its radiance (and texture coordinates)
// Gouraud-interpolated perspective-correctly; a quad is two triangles.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "direct_gather.h"
#include "raster_internal.h"
#include "vismask/display/camera.h"
#include "vismask/display/raster.h"
#include "vismask/scene/texture.h"

namespace vismask {
namespace {

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
      glm::vec3 extra(0.0f);
      if (piece.direct) {
        // Per-pixel direct light at the pixel centre.
        glm::vec3 pc = z * glm::vec3((px - halfW) / view.focal, (halfH - py) / view.focal, 1.0f);
        glm::vec3 w = view.eye + pc.x * view.right + pc.y * view.up + pc.z * view.forward;
        extra =
            GatherDirect(*piece.direct, w, static_cast<uint32_t>(idx), [&](uint32_t) { return w; });
      }
      if constexpr (kTextured) {
        glm::vec2 uv =
            (b0 * invZ[0]) * v[0].uv + (b1 * invZ[1]) * v[1].uv + (b2 * invZ[2]) * v[2].uv;
        fb->color[idx] = piece.ke + piece.texture->Modulation(uv * z) *
                                        ((piece.direct ? c * z + extra : c * z) - piece.ke);
      } else {
        fb->color[idx] = piece.direct ? c * z + extra : c * z;
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

}  // namespace

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

template void DrawPiecePoint<false>(const View& view, const DisplayPiece& piece, Framebuffer* fb);
template void DrawPiecePoint<true>(const View& view, const DisplayPiece& piece, Framebuffer* fb);

}  // namespace vismask
