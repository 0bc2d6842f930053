#include "vismask/raster.h"

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

namespace vismask {

void Framebuffer::Layout(Arena& arena, int w, int h) {
  width = w;
  height = h;
  size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  color = arena.Alloc<glm::vec3>(n);
  depth = arena.Alloc<float>(n);
  id = arena.Alloc<uint32_t>(n);
}

void Framebuffer::Clear() {
  for (size_t i = 0; i < color.size(); ++i) {
    color[i] = glm::vec3(0.0f);
    depth[i] = std::numeric_limits<float>::infinity();
    id[i] = kNoPatch;
  }
}

namespace {

// A vertex in camera space (x right, y up, z forward) with its radiance.
struct CamVert {
  glm::vec3 p;
  glm::vec3 c;
};

inline bool Nearer(float z, uint32_t id, float zOld, uint32_t idOld) {
  return z < zOld || (z == zOld && id < idOld);
}

void DrawTriangle(const View& view, const CamVert* v, uint32_t id, Framebuffer* fb) {
  float sx[3], sy[3], invZ[3];
  float halfW = 0.5f * static_cast<float>(view.width), halfH = 0.5f * static_cast<float>(view.height);
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
      size_t idx = static_cast<size_t>(y) * static_cast<size_t>(view.width) + static_cast<size_t>(x);
      if (!Nearer(z, id, fb->depth[idx], fb->id[idx])) continue;
      glm::vec3 c = (b0 * invZ[0]) * v[0].c + (b1 * invZ[1]) * v[1].c + (b2 * invZ[2]) * v[2].c;
      fb->color[idx] = c * z;
      fb->depth[idx] = z;
      fb->id[idx] = id;
    }
  }
}

// Clips triangle `in` to z >= nearZ (Sutherland-Hodgman, one plane) and
// draws the resulting 0, 1 or 2 triangles.
void ClipAndDraw(const View& view, const CamVert* in, uint32_t id, Framebuffer* fb) {
  CamVert out[4];
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    const CamVert& a = in[k];
    const CamVert& b = in[(k + 1) % 3];
    bool aIn = a.p.z >= view.nearZ, bIn = b.p.z >= view.nearZ;
    if (aIn) out[n++] = a;
    if (aIn != bIn) {
      float t = (view.nearZ - a.p.z) / (b.p.z - a.p.z);
      out[n++] = CamVert{a.p + t * (b.p - a.p), a.c + t * (b.c - a.c)};
    }
  }
  if (n < 3) return;
  DrawTriangle(view, out, id, fb);
  if (n == 4) {
    CamVert second[3] = {out[0], out[2], out[3]};
    DrawTriangle(view, second, id, fb);
  }
}

}  // namespace

void RasterPatches(const View& view, Span<const Patch> patches, Span<const glm::vec3> vertices,
                   Span<const glm::vec3> vertexRadiance, Framebuffer* fb) {
  constexpr float kInvPi = 0.318309886183790672f;
  for (const Patch& p : patches) {
    // The back of a one-sided patch reflects nothing: it is drawn black.
    bool facing = glm::dot(p.normal, view.eye - p.corner[0]) > 0.0f;
    CamVert cv[4];
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      glm::vec3 d = vertices[p.vertex[k]] - view.eye;
      cv[k].p = glm::vec3(glm::dot(d, view.right), glm::dot(d, view.up), glm::dot(d, view.forward));
      cv[k].c = facing ? kInvPi * vertexRadiance[p.vertex[k]] : glm::vec3(0.0f);
    }
    ClipAndDraw(view, cv, p.globalId, fb);
    if (p.numCorners == 4) {
      CamVert second[3] = {cv[0], cv[2], cv[3]};
      ClipAndDraw(view, second, p.globalId, fb);
    }
  }
}

void DrawPiece(const View& view, const DisplayPiece& piece, Framebuffer* fb) {
  CamVert cv[4];
  for (uint32_t k = 0; k < piece.numCorners; ++k) {
    glm::vec3 d = piece.p[k] - view.eye;
    cv[k].p = glm::vec3(glm::dot(d, view.right), glm::dot(d, view.up), glm::dot(d, view.forward));
    cv[k].c = piece.c[k];
  }
  ClipAndDraw(view, cv, piece.id, fb);
  if (piece.numCorners == 4) {
    CamVert second[3] = {cv[0], cv[2], cv[3]};
    ClipAndDraw(view, second, piece.id, fb);
  }
}

void Composite(const Framebuffer& other, Framebuffer* fb) {
  CHECK(other.width == fb->width && other.height == fb->height);
  for (size_t i = 0; i < fb->depth.size(); ++i) {
    if (Nearer(other.depth[i], other.id[i], fb->depth[i], fb->id[i])) {
      fb->color[i] = other.color[i];
      fb->depth[i] = other.depth[i];
      fb->id[i] = other.id[i];
    }
  }
}

}  // namespace vismask
