// Raster: draws display pieces (planar convex quads and triangles with a
// radiance per corner) into a framebuffer, in one of two modes chosen at
// Layout (--aa):
//
// - antialiased (default): each piece's exact area in each pixel square is
//   computed analytically (the projected polygon clipped to the pixel), so
//   the image is the scene filtered with a 1-pixel box. A pixel keeps up to
//   kFragments fragments, one per patch id: pieces with the same id add their
//   coverage and coverage-weighted radiance to one fragment, so pieces that
//   tile a patch sum to its full coverage. Fragments are kept sorted by
//   (depth, id), the nearest kFragments, where depth is the piece's plane's
//   depth at the pixel centre for a front face and the farthest point of the
//   covered part for a back face (so a closed object's back face sorts
//   behind the front face it shares a silhouette edge with); Resolve
//   composes them front to back, a front face taking at most the coverage
//   still free, a back face only what it covers beyond what front faces
//   took and what the front faces after it cover whose covered part lies
//   nearer than its own (a grazing front face's plane at the centre of a pixel it covers
//   only in part lies beyond the silhouette edge, deeper than the back face
//   sharing that edge).
// - point sampled (--aa off): the pixel centre only, quads split into two
//   Gouraud-shaded triangles; one (depth, id) sample per pixel.
//
// Either way the result does not depend on the order pieces of different ids
// are drawn in, and framebuffers drawn from disjoint sets of ids composite to
// the same bytes as one drawn from all (pieces of one id must be drawn into
// one framebuffer, in a fixed order: their sums are floating point). The one
// exception is a pixel holding more than kFragments ids whose farthest kept
// key ties, to rounding, with a dropped id drawn as several pieces.
#pragma once
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/display/camera.h"
#include "vismask/solve/patch.h"

namespace vismask {

// Fragments per pixel (antialiased): five, so that where two closed
// objects' edges cross a pixel (each a front face and its back face) the
// surface seen past both is still kept (RasterTest.TwoObjectsEdgesKeepWhatLiesPastBoth).
constexpr int kFragments = 5;
static_assert(kFragments <= 8, "a pixel's shown fragments are bits of a byte");

// One patch id's share of a pixel (antialiased). Empty: id == kNoPatch,
// depth = +inf, the rest 0.
struct Fragment {
  float depth;  // sort depth: the plane's at the pixel centre (back faces: farthest covered); min
                // over pieces
  uint32_t id;  // global patch id
  float coverage;  // summed exact area fraction of the id's pieces in the pixel,
                   // negative for a back face (its corners clockwise on screen)
  float rgb[3];    // summed coverage * radiance
  float nearest;   // the covered part's depths: the nearest, min over pieces,
  float farthest;  // and the farthest, max over pieces
};
static_assert(sizeof(Fragment) == 32, "Fragment is packed");

// How the antialiased raster draws a piece (DrawEnvironment's two passes
// with per-pixel direct light): whole (coverage and radiance, its direct
// light gathered wherever it covers); its coverage and interpolated
// radiance alone; or only its direct light, gathered where its fragment
// shows (MarkShown) and added to that fragment.
enum class DrawPass : uint8_t { kWhole, kCoverage, kDirect };

struct Framebuffer {
  int width = 0;
  int height = 0;
  bool aa = false;
  Span<glm::vec3> color;  // linear radiance, row 0 at the top (antialiased: after Resolve)
  Span<uint32_t> id;      // global patch id; kNoPatch = empty (antialiased: the
                          // id with the largest visible share, after Resolve)
  Span<float> depth;      // point sampled: distance along the view direction; +inf = empty
  Span<Fragment> frags;   // antialiased: kFragments per pixel, nearest first
  Span<uint8_t> dropped;  // antialiased: 1 where a fragment fell off the list
  Span<uint8_t> shown;    // antialiased: bit k set where fragment k shows (MarkShown)
  DrawPass pass = DrawPass::kWhole;  // antialiased: how DrawPiece draws
  // Antialiased: the rows [dirtyLo, dirtyHi] hold every fragment drawn since
  // the last Clear (empty: dirtyLo > dirtyHi).
  int dirtyLo = 0, dirtyHi = -1;

  // Carves w x h pixels from `arena`: point sampled 20 bytes a pixel,
  // antialiased 16 + kFragments * 32 + 2.
  void Layout(Arena& arena, int w, int h, bool antialiased);
  void Clear();
  // Clears the dirty rows only (antialiased; point sampled: Clear).
  void ClearDirty();
  // Widens the dirty rows to include [lo, hi] (lo <= hi).
  void MarkDirty(int lo, int hi) {
    if (dirtyLo > dirtyHi) {
      dirtyLo = lo;
      dirtyHi = hi;
    } else {
      dirtyLo = lo < dirtyLo ? lo : dirtyLo;
      dirtyHi = hi > dirtyHi ? hi : dirtyHi;
    }
  }
};

struct Texture;
class DirectLight;
class Grid;

// Per-pixel direct light for one piece (direct.h): at each point the raster
// shades, `scale` times the irradiance from `light`'s emitters there (at
// most `samples` shadow rays through `grid`) is added to the interpolated
// radiance, before a texture modulates it. The antialiased raster spreads
// a pixel's shadow rays over the pixel square where the piece covers all
// of it (so a shadow edge is box-filtered like a silhouette), and sends
// them all from the covered part's centroid where it covers part; the
// point sampled one from the pixel centre. Sample points come from the
// pixel index (DirectLightSample, DirectPixelOffset; src/display/direct_gather.h).
struct DirectHook {
  const DirectLight* light = nullptr;
  const Grid* grid = nullptr;
  uint32_t patch = kNoPatch;  // the receiver (local to `grid`), skipped by its shadow rays
  uint32_t twin = kNoPatch;
  glm::vec3 normal{0.0f};      // the receiver's unit normal
  glm::vec3 planePoint{0.0f};  // a point of its plane (shaded points are projected onto it)
  glm::vec3 scale{0.0f};       // kd / pi (times the texture's display scale)
  uint32_t samples = 0;
  float epsilon = 0.0f;      // shadow rays stop this far from either end (scene units)
  uint32_t* hint = nullptr;  // the last occluder (Grid::Occluded), or null
  // The receiver's environment, when `light` holds other environments'
  // emitters too (DirectLight::SetTransit); else DirectLight::kNoViewer.
  uint32_t viewer = 0xffffffffu;
};

// A planar convex piece to draw: world corners counter-clockwise from the
// front (a quad's corners are its bilinear parameter square's (0,0), (1,0),
// (1,1), (0,1)), the radiance at each corner (already divided by pi), the
// global patch id. numCorners is 3 or 4. A textured piece also has texture
// coordinates per corner and its emitted radiance `ke`: where the radiance
// is taken, c interpolated becomes ke + texture->Modulation(uv) * (c - ke)
// (texture.h), uv interpolated as c is.
struct DisplayPiece {
  glm::vec3 p[4];
  glm::vec3 c[4];
  uint32_t numCorners;
  uint32_t id;
  const Texture* texture = nullptr;  // null: untextured (uv and ke unused)
  glm::vec2 uv[4];
  glm::vec3 ke;
  const DirectHook* direct = nullptr;  // null: no per-pixel direct light
};

// Draws one piece: antialiased, the radiance interpolated perspective-correctly
// in the piece's own parameters (bilinear for quads, barycentric for
// triangles) at the centroid of the covered part of each pixel; point sampled,
// as two Gouraud triangles (0,1,2) and (0,2,3). Clipped to the near plane.
void DrawPiece(const View& view, const DisplayPiece& piece, Framebuffer* fb);

// Draws `patches` (corners via `vertices`, radiance per vertex, divided by pi
// here) as one piece each; the back of a one-sided patch is drawn black.
void RasterPatches(const View& view, Span<const Patch> patches, Span<const glm::vec3> vertices,
                   Span<const glm::vec3> vertexRadiance, Framebuffer* fb);

// Merges rows [0, rows) of `band` (same width and mode as `fb`) into rows
// [firstRow, firstRow + rows) of `fb` with the same rules as drawing.
void CompositeRows(const Framebuffer& band, int firstRow, int rows, Framebuffer* fb);
// The whole of `other` (same size and mode) into `fb`.
void Composite(const Framebuffer& other, Framebuffer* fb);
// Antialiased: the dirty rows of `other` (same size) into the same rows of `fb`.
void CompositeDirty(const Framebuffer& other, Framebuffer* fb);

// Antialiased: for each pixel of the dirty rows, which of its fragments
// Resolve would give a share (`shown`); the others are hidden behind them,
// and stay hidden whatever is composited in later (what comes in only
// takes coverage). Point sampled: nothing to do.
void MarkShown(Framebuffer* fb);

// Antialiased: composes each pixel's fragments into color and id (empty
// coverage is black; where fragments were dropped, the kept ones are scaled
// to fill the pixel). Point sampled: nothing to do.
void Resolve(Framebuffer* fb);

// What a resolved image shows. surface: some pixel holds a patch. litFront:
// some pixel is not black and, antialiased, front faces take at least half
// of it. (Only front faces are lit, but the antialiased composite can give
// a front face a sliver of a pixel on the silhouette of a back face in front
// of it: a box seen from its closed side shows its inside along the rim, in
// pixels whose centres lie outside the box.) Allocates nothing.
struct ImageContent {
  bool surface = false;
  bool litFront = false;
};
ImageContent InspectImage(const Framebuffer& fb);

}  // namespace vismask
