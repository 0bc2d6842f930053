// Meshing: polygons into patches no longer than a given edge length, and the
// display lattice of shared vertices used for Gouraud shading.
#pragma once
#include <algorithm>
#include <cstdint>
#include <glm/vec3.hpp>
#include <string>
#include <vector>

#include "vismask/core/status.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/patch.h"

namespace vismask {

// A lattice vertex on the outline of a polygon that asks to be smoothed (a
// smoothing group or vertex normals): where another polygon's lattice vertex
// lies at the same point, the display may share their values (smoothing.h).
struct SmoothVertex {
  uint32_t vertex;   // in Mesh::vertices
  uint32_t polygon;  // the source polygon (before partitioning): never shared with itself
  uint32_t group;    // its smoothing group, 0 for none
  uint32_t edge[2];  // the source polygon's outline edges it lies on (a corner: two; else edge[1]
                     // == edge[0])
  glm::vec3 normal;  // the polygon's geometric normal
  glm::vec3 vn;      // its vertex normal there ('vn', interpolated along the edge), or 0
  glm::vec3 dir;     // unit direction of outline edge edge[0]
};

struct Mesh {
  std::vector<Patch> patches;       // in polygon order; Patch::globalId == index
  std::vector<glm::vec3> vertices;  // display lattice; Patch::vertex[] index it
  // Two-sided meshes (AddTwins): per patch, the index of its twin, the same
  // patch with its front on the other side, or kNoPatch. Empty: no twins.
  std::vector<uint32_t> twin;
  std::vector<SmoothVertex> smooth;  // by vertex; empty unless MarkSmoothVertices found some
  std::vector<PatchTexture>
      textures;  // one per patch once any is textured (TextureMesh), else empty
};

// Which patches AddTwins copies: every patch (--two-sided), and/or every
// emitting patch, whose twin then emits too (--two-sided-emitters), and/or
// the patches of the materials marked in `materials` (glTF doubleSided:
// both sides are surfaces, an emitter's twin emits too).
struct TwinOptions {
  bool all = false;
  bool emitters = false;
  std::vector<uint8_t> materials;  // per material: twin its patches; empty: none
  bool any() const {
    return all || emitters || std::find(materials.begin(), materials.end(), 1) != materials.end();
  }
  bool Marked(uint32_t m) const { return m < materials.size() && materials[m]; }
  // Whether a patch of material m (emitting or not) gets a twin.
  bool Twins(uint32_t m, bool emits) const { return all || (emitters && emits) || Marked(m); }
  // Whether that twin emits the original's Ke.
  bool TwinEmits(uint32_t m, bool emits) const { return emits && (emitters || Marked(m)); }
};

// Appends the patches of the given polygons of `scene` to `mesh`, with edges
// at most `patchSize` long (up to float rounding of the corners). Triangles
// split into n*n similar triangles, convex quads into an m*n bilinear grid of
// planar quads, anything else is ear-clipped into triangles first. Patch areas
// sum to the polygon's area, but for one exception: a convex polygon of more
// corners than a quad whose ear-clipped triangles would make more than
// 2 (A / s^2 + P / s) patches (A its area, P its perimeter, s the patch size;
// a disc of many corners: n - 2 slivers of up to (diameter / s)^2 patches
// each) is cut in strips across its longest extent instead when they make
// fewer: columns of quads, a fan at a pointed end, whose outline chords are
// at most s long and pass each corner they skip within s / 64, so the
// patches follow its area and outline whatever its corner count and cover
// it less the slivers those chords cut off (MeshesInStrips). Patches of one polygon (of one of its
// triangles, if triangulated) share lattice vertices; different polygons never do. Fails (without
// partial output) if patchSize is not a positive finite number or the mesh would exceed
// `maxPatches`.
Status MeshScene(const Scene& scene, const std::vector<uint32_t>& polygons, float patchSize,
                 uint64_t maxPatches, Mesh* mesh);

// The patches and lattice vertices MeshScene makes of `polygon` at
// `patchSize` (added to *patches and *vertices), without making them: what
// the streaming init counts for the environments a rank does not hold. The
// error MeshScene gives for a polygon it cannot triangulate. *strips (when
// not null): whether it is cut in strips.
Status CountPolygonPatches(const std::string& objPath, const Polygon& polygon, float patchSize,
                           double* patches, double* vertices, bool* strips = nullptr);
// Whether MeshScene meshes `polygon` in strips at `patchSize` (above), and
// then by how much their area differs from the polygon's (relative; < 0:
// the slivers the chords cut off). The error MeshScene gives otherwise.
Status MeshesInStrips(const std::string& objPath, const Polygon& polygon, float patchSize,
                      bool* strips, double* areaChange);
// MeshScene's error for a mesh of more than `maxPatches` patches.
Status MeshSizeError(double numPatches, float patchSize, uint64_t maxPatches);
// How many parts an edge of length `len` is cut into at `patchSize`:
// ceil(len / patchSize), at least 1 (double: it may be huge). The meshing
// and the partition's patch estimate both count with it.
double EdgeDivisions(double len, double patchSize);
// The m x n lattice MeshScene lays on a convex quad c[0..3]: c[0]c[1] and
// c[3]c[2] cut in m, c[0]c[3] and c[1]c[2] in n, each pair as its longer side
// is (EdgeDivisions). The meshing and the partition's estimate share it.
void QuadDivisions(const glm::dvec3* c, double patchSize, double* m, double* n);

// Appends a twin of each patch `options` selects, after all the patches:
// the same corners (bit for bit) in reverse order from corner[0], so its
// front is the original's back, normal negated, same kd and area, on its
// own copy of the lattice vertices (the two sides are displayed apart).
// An emitter's twin emits Ke with `options.emitters` or when its material is
// two-sided, nothing otherwise. `scene` (the one `mesh` was made from:
// Patch::surface indexes its polygons) gives a patch's material; it may be
// null when options.materials is empty. Twins keep the original's `surface`;
// globalId is the index, as for the others. Sets mesh->twin for every patch.
// Does nothing when !options.any().
void AddTwins(const TwinOptions& options, Mesh* mesh, const Scene* scene = nullptr);

}  // namespace vismask
