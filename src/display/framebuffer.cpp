// Framebuffers (raster.h): their layout in an arena and clearing;
// compositing one into another with the same rules as drawing (rank 0 takes
// the other ranks' framebuffers a band of rows at a time); resolving the
// antialiased pixels' fragments into colour and id; and inspecting what an
// image shows.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>

#include "raster_internal.h"
#include "vismask/core/arena.h"
#include "vismask/core/check.h"
#include "vismask/display/raster.h"
#include "vismask/solve/patch.h"

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
    shown = arena.Alloc<uint8_t>(n);
  } else {
    depth = arena.Alloc<float>(n);
  }
}

namespace {

constexpr Fragment kEmptyFragment = {kInf, kNoPatch, 0.0f, {0.0f, 0.0f, 0.0f}, kInf, 0.0f};

}  // namespace

void Framebuffer::Clear() {
  for (size_t i = 0; i < color.size(); ++i) {
    color[i] = glm::vec3(0.0f);
    id[i] = kNoPatch;
  }
  for (float& d : depth) d = kInf;
  for (Fragment& f : frags) f = kEmptyFragment;
  for (uint8_t& d : dropped) d = 0;
  dirtyLo = 0;
  dirtyHi = -1;
}

void Framebuffer::ClearDirty() {
  if (!aa) return Clear();
  const size_t w = static_cast<size_t>(width);
  for (int y = dirtyLo; y <= dirtyHi; ++y) {
    const size_t first = static_cast<size_t>(y) * w;
    for (size_t i = first; i < first + w; ++i) {
      color[i] = glm::vec3(0.0f);
      id[i] = kNoPatch;
      dropped[i] = 0;
    }
    for (size_t i = first * kFragments; i < (first + w) * kFragments; ++i)
      frags[i] = kEmptyFragment;
  }
  dirtyLo = 0;
  dirtyHi = -1;
}

namespace {

// Rows [srcRow, srcRow + rows) of `band` into rows [firstRow, firstRow + rows) of `fb`.
void MergeRows(const Framebuffer& band, int srcRow, int firstRow, int rows, Framebuffer* fb) {
  CHECK(band.width == fb->width && band.aa == fb->aa && srcRow >= 0 &&
        srcRow + rows <= band.height);
  CHECK(firstRow >= 0 && firstRow + rows <= fb->height);
  size_t n = static_cast<size_t>(rows) * static_cast<size_t>(fb->width);
  size_t base = static_cast<size_t>(firstRow) * static_cast<size_t>(fb->width);
  size_t from = static_cast<size_t>(srcRow) * static_cast<size_t>(fb->width);
  if (fb->aa) {
    if (rows > 0) fb->MarkDirty(firstRow, firstRow + rows - 1);
    for (size_t i = 0; i < n; ++i) {
      const Fragment* src = &band.frags[(from + i) * kFragments];
      Fragment* dst = &fb->frags[(base + i) * kFragments];
      uint8_t* dropped = &fb->dropped[base + i];
      *dropped |= band.dropped[from + i];
      for (int k = 0; k < kFragments && src[k].id != kNoPatch; ++k)
        AddFragment(dst, dropped, src[k]);
    }
    return;
  }
  for (size_t i = 0; i < n; ++i) {
    size_t j = base + i;
    size_t k = from + i;
    if (Nearer(band.depth[k], band.id[k], fb->depth[j], fb->id[j])) {
      fb->color[j] = band.color[k];
      fb->depth[j] = band.depth[k];
      fb->id[j] = band.id[k];
    }
  }
}

}  // namespace

void CompositeRows(const Framebuffer& band, int firstRow, int rows, Framebuffer* fb) {
  MergeRows(band, 0, firstRow, rows, fb);
}

void CompositeDirty(const Framebuffer& other, Framebuffer* fb) {
  CHECK(other.aa && other.width == fb->width && other.height == fb->height);
  if (other.dirtyLo <= other.dirtyHi)
    MergeRows(other, other.dirtyLo, other.dirtyLo, other.dirtyHi + 1 - other.dirtyLo, fb);
}

void Composite(const Framebuffer& other, Framebuffer* fb) {
  CHECK(other.width == fb->width && other.height == fb->height);
  CompositeRows(other, 0, other.height, fb);
}

namespace {

// Whether fragment a's covered part starts and ends no deeper than b's, one
// of them nearer (by a relative 1e-5, far above rounding).
bool InFrontOf(const Fragment& a, const Fragment& b) {
  constexpr float kLess = 1.0f - 1e-5f, kMore = 1.0f + 1e-5f;
  bool nearer = a.nearest < b.nearest * kLess, notDeeper = a.nearest <= b.nearest * kMore;
  bool endsNearer = a.farthest < b.farthest * kLess,
       endsNotDeeper = a.farthest <= b.farthest * kMore;
  return notDeeper && endsNotDeeper && (nearer || endsNearer);
}

// One antialiased pixel's fragments composed: its colour, the id with the
// largest visible share, and the share front faces took.
void ResolvePixel(const Fragment* f, bool dropped, glm::vec3* color, uint32_t* id,
                  float* frontShare, uint8_t* shown = nullptr) {
  float open = 1.0f, front = 0.0f, best = 0.0f;
  uint32_t bestId = kNoPatch;
  glm::vec3 c(0.0f);
  for (int k = 0; k < kFragments && f[k].id != kNoPatch && open > 0.0f; ++k) {
    // A front face takes what is still open (pieces meeting at edges, a
    // silhouette over what is behind: disjoint parts). A back face lies
    // behind its object's front faces, within their silhouette: it shows
    // only where it covers more than the front faces before it took (and
    // is disjoint from other back faces, like the pieces of a wall seen
    // from behind). The sort goes by a front face's plane's depth at the
    // pixel centre, which lies beyond the face where it covers the pixel in
    // part: a grazing face's plane, extended beyond a silhouette edge, is
    // deeper there than the back face sharing that edge, and the inside
    // wall of a box seen through its back, extended beyond the edge where
    // they meet, nearer. So a back face also leaves what front faces sorted
    // after it cover in front of it, and a front face leaves what back faces
    // sorted after it cover in front of it: their covered parts start and
    // end no deeper, and one of them nearer.
    float cover = std::fabs(f[k].coverage);
    bool isFront = f[k].coverage >= 0.0f;
    float hidden = isFront ? 0.0f : front;
    for (int j = k + 1; j < kFragments && f[j].id != kNoPatch; ++j)
      if ((f[j].coverage >= 0.0f) != isFront && InFrontOf(f[j], f[k]))
        hidden += std::fabs(f[j].coverage);
    float w = std::fmin(cover - hidden, open);
    if (!(w > 0.0f)) continue;
    if (shown) *shown = static_cast<uint8_t>(*shown | (1u << k));
    if (isFront) front += w;
    float scale = w / cover;
    c += scale * glm::vec3(f[k].rgb[0], f[k].rgb[1], f[k].rgb[2]);
    open -= w;
    if (w > best) best = w, bestId = f[k].id;
  }
  // Where ids were dropped, the kept ones stand for the whole pixel: for
  // its colour and for the share of it that is front-facing (which the
  // black-image warning reads: a 1 x 1 image of a lit room drops most).
  if (dropped && open > 0.0f && open < 1.0f) {
    c *= 1.0f / (1.0f - open);
    front *= 1.0f / (1.0f - open);
  }
  *color = c;
  *id = bestId;
  *frontShare = front;
}

}  // namespace

void MarkShown(Framebuffer* fb) {
  if (!fb->aa) return;
  const size_t w = static_cast<size_t>(fb->width);
  glm::vec3 color;
  uint32_t id;
  float front;
  for (size_t i = static_cast<size_t>(std::max(fb->dirtyLo, 0)) * w;
       i < static_cast<size_t>(fb->dirtyHi + 1) * w; ++i) {
    fb->shown[i] = 0;
    ResolvePixel(&fb->frags[i * kFragments], fb->dropped[i] != 0, &color, &id, &front,
                 &fb->shown[i]);
  }
}

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
