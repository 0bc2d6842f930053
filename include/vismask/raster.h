// Raster: draws patches into a colour + depth + id framebuffer with Gouraud
// shading (perspective-correct interpolation of the lattice vertices'
// radiance). The depth test compares (depth, global patch id), so the image
// does not depend on the order patches are drawn in: framebuffers drawn from
// disjoint sets of patches composite to the same bytes as one drawn from all.
#pragma once
#include <cstdint>

#include <glm/vec3.hpp>

#include "vismask/arena.h"
#include "vismask/camera.h"
#include "vismask/patch.h"
#include "vismask/span.h"

namespace vismask {

struct Framebuffer {
  int width = 0;
  int height = 0;
  Span<glm::vec3> color;  // linear radiance, row 0 at the top
  Span<float> depth;      // distance along the view direction; +inf = empty
  Span<uint32_t> id;      // global patch id; kNoPatch = empty

  void Layout(Arena& arena, int w, int h);
  void Clear();
};

// One drawable piece of a patch: corners in world space, counter-clockwise
// from the front, the radiance at each (already divided by pi), and the
// patch's global id for the depth tie rule. numCorners is 3 or 4 (then p[3]
// is used).
struct DisplayPiece {
  glm::vec3 p[4];
  glm::vec3 c[4];
  uint32_t numCorners;
  uint32_t id;
};

// Draws one piece into `fb` (clipped at the near plane).
void DrawPiece(const View& view, const DisplayPiece& piece, Framebuffer* fb);

// Draws `patches` (corners via `vertices`, radiance per vertex) into `fb`.
// Triangles crossing the near plane are clipped.
void RasterPatches(const View& view, Span<const Patch> patches, Span<const glm::vec3> vertices,
                   Span<const glm::vec3> vertexRadiance, Framebuffer* fb);

// Keeps, per pixel, the nearer of `fb` and `other` (same tie rule).
void Composite(const Framebuffer& other, Framebuffer* fb);

}  // namespace vismask
