// Display: what the image shows of an environment's solution. Every leaf
// element (element.h) of every patch is drawn as one piece whose corner
// radiance is the nodal average of the leaves around that corner: at a
// patch's own corners, the shared lattice vertex (Environment::
// ComputeVertexRadiosity, which averages across the patches of a polygon);
// elsewhere, the area-weighted mean of the patch's leaves that touch it.
// Back faces are black.
//
// Where the partition cut a polygon, its two sides are meshed and solved by
// different environments, and each side's lattice vertices on the cut see
// only their own patches: a step along every environment plane. The values
// of those vertices are shared: every environment's cut vertices are
// gathered (CutRecord), and each takes the weighted mean of its own value
// and the other side's, interpolated along the cut.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vismask/camera.h"
#include "vismask/environment.h"
#include "vismask/raster.h"
#include "vismask/texture.h"

namespace vismask {

// Draws environment `env`'s leaves into `fb`, with `ambient` (Cohen's term,
// per channel) added as kd * ambient. Its vertex radiosity must be current
// (Environment::ComputeVertexRadiosity, then ShareCuts). Textured patches
// (Environment::patchTexture) are drawn with `textures` (the rank's
// TextureSet; it must hold theirs), the texture modulating the interpolated
// value per pixel (texture.h). Allocates nothing.
void DrawEnvironment(const View& view, const Environment& env, const double ambient[3],
                     Framebuffer* fb, Span<const Texture> textures = {});

// One cut vertex as environments exchange it.
struct CutRecord {
  float pos[3];
  float normal[3];
  float sum[3];   // display radiosity times weight
  float weight;   // the area of the leaves that gave it (0: padding)
  uint32_t env;
  uint32_t vertex;
};
static_assert(sizeof(CutRecord) == 48, "exchanged as bytes");

// This rank's environments' cut vertices into `out` (the rest padding, weight
// 0). `out` must hold them all (CHECK).
void CollectCuts(Span<Environment* const> envs, Span<CutRecord> out);
// Sets every cut vertex of `envs` to the weighted mean of its own value and
// the other side's at the same point: the records in `all` (every rank's,
// padding included) of other environments on the same cut line of the same
// surface (normal), interpolated between the nearest two (the sides need not
// be meshed alike). Sorts `all` in place, so the result does not depend on
// the order records arrive in. Allocates nothing; O(cut vertices^2).
void ShareCuts(Span<Environment* const> envs, Span<CutRecord> all, float tolerance);

}  // namespace vismask
