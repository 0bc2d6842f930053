// Display: what the image shows of an environment's solution. Every leaf
// element (element.h) of every patch is drawn as one piece whose corner
// radiance is the nodal average of the leaves around that corner: at a
// patch's own corners, the shared lattice vertex (Environment::
// ComputeVertexRadiosity, which averages across the patches of a polygon);
// elsewhere, the area-weighted mean of the patch's leaves that touch it.
// Back faces are black; of two twins (a two-sided mesh, mesh.h) only the
// one facing the eye is drawn.
//
// Where the partition cut a polygon, its two sides are meshed and solved by
// different environments, and each side's lattice vertices on the cut see
// only their own patches: a step along every environment plane. The values
// of those vertices are shared: every environment's cut vertices are
// gathered (VertexRecord), and each takes the weighted mean of its own value
// and the other side's, interpolated along the cut.
//
// Smoothing (smoothing.h) rides on the same exchange: a lattice vertex on the
// outline of a smoothed polygon also takes in the values of the other
// polygons' smooth vertices at the same point that SmoothTogether accepts,
// in whatever environment they are; along such an outline edge a patch
// interpolates its two shared ends, as along a cut.
#pragma once
#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>

#include "vismask/display/camera.h"
#include "vismask/display/foreign_light.h"
#include "vismask/display/raster.h"
#include "vismask/scene/texture.h"
#include "vismask/solve/environment.h"

namespace vismask {

// The radiance the image (image.pfm) shows for display radiosity b: b / pi,
// a diffuse surface's. The glTF export's COLOR_0 is the same value.
inline glm::vec3 DisplayRadiance(const glm::vec3& b) {
  constexpr float kInvPi = 0.318309886183790672f;
  return kInvPi * b;
}

// Draws environment `env`'s leaves into `fb`, with `ambient` (Cohen's term,
// per channel) added as kd * ambient. Its vertex radiosity must be current
// (Environment::ComputeVertexRadiosity, then ShareVertices). Textured patches
// (Environment::patchTexture) are drawn with `textures` (the rank's
// TextureSet; it must hold theirs), the texture modulating the interpolated
// value per pixel (texture.h). Allocates nothing.
// With `foreign` (several environments, foreign_light.h), the pixels
// gather every environment's emitters from it, not the environment's own.
void DrawEnvironment(const View& view, const Environment& env, const double ambient[3],
                     Framebuffer* fb, Span<const Texture> textures = {},
                     const ForeignLight* foreign = nullptr);

// One shared vertex (on a cut, or smooth, or both) as environments exchange it.
struct VertexRecord {
  float pos[3];
  float normal[3];  // its polygon's geometric normal
  float sum[3];     // display radiosity times weight
  float weight;     // the area of the leaves that gave it (0: padding)
  uint32_t env;
  uint32_t vertex;
  float vn[3];       // smooth: the vertex normal there, or 0
  uint32_t group;    // smooth: the smoothing group
  uint32_t polygon;  // smooth: the source polygon
  uint32_t flags;    // kRecordCut | kRecordSmooth
};
static_assert(sizeof(VertexRecord) == 72, "exchanged as bytes");
constexpr uint32_t kRecordCut = 1, kRecordSmooth = 2;

// The geometry ShareVertices matches by.
struct ShareRule {
  float tolerance = 0.0f;  // points this close are one (scene units)
  glm::vec3 origin{0.0f};  // of the scene's box: smooth records are sorted by cells from it
  float cosCrease = 1.0f;  // cos of the crease angle (SmoothTogether)
};

// This rank's environments' shared vertices into `out`, each once: cut
// vertices, then the smooth ones not on a cut (the rest padding, weight 0).
// `out` must hold them all (CHECK).
void CollectShared(Span<Environment* const> envs, Span<VertexRecord> out);
// Sets every shared vertex of `envs` to the weighted mean of its own value
// and (on a cut) the other side's at the same point: the records in `all`
// (every rank's, padding included) of other environments on the same cut
// line of the same surface (normal), interpolated between the nearest two
// (the sides need not be meshed alike); and (smooth) the smooth records of
// the other polygons at the same point that SmoothTogether joins to it,
// directly or through one another. A smooth vertex inside an outline edge
// that met no other polygon there (its neighbour is meshed differently)
// then takes the line between the nearest vertices of that edge which did.
// Sorts `all` in place and uses `scratch` (at least 2 * all.size(), or
// empty when no record is smooth), so the result does not depend on the
// order records arrive in or on how environments are dealt to ranks.
// Allocates nothing; O(cut vertices^2 + smooth vertices log smooth
// vertices), and the square of the polygons meeting at a point.
void ShareVertices(Span<Environment* const> envs, Span<VertexRecord> all, Span<uint32_t> scratch,
                   const ShareRule& rule);

}  // namespace vismask
