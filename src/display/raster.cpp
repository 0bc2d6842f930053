// Drawing into a framebuffer (raster.h): DrawPiece, which sends a piece to
// the point-sampled raster (raster_point.cpp) or the antialiased one
// (raster_aa.cpp), and RasterPatches, which draws patches as pieces. The
// framebuffers themselves, compositing and resolving are in framebuffer.cpp.
#include "vismask/display/raster.h"

#include <cstdint>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "raster_internal.h"
#include "vismask/core/check.h"
#include "vismask/core/span.h"
#include "vismask/display/camera.h"
#include "vismask/solve/patch.h"

namespace vismask {

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

}  // namespace vismask
