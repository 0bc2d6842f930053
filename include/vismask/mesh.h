// Meshing: polygons into patches no longer than a given edge length, and the
// display lattice of shared vertices used for Gouraud shading.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "vismask/patch.h"
#include "vismask/scene.h"

namespace vismask {

struct Mesh {
  std::vector<Patch> patches;        // in polygon order; Patch::globalId == index
  std::vector<glm::vec3> vertices;   // display lattice; Patch::vertex[] index it
  std::vector<PatchTexture> textures;  // one per patch once any is textured (TextureMesh), else empty
};

// Appends the patches of the given polygons of `scene` to `mesh`, with edges
// at most `patchSize` long (up to float rounding of the corners). Triangles
// split into n*n similar triangles, convex quads into an m*n bilinear grid of
// planar quads, anything else is ear-clipped into triangles first. Patch areas
// sum to the polygon's area. Patches of one polygon (of one of its triangles,
// if triangulated) share lattice vertices; different polygons never do.
// Fails (without partial output) if patchSize is not a positive finite number
// or the mesh would exceed `maxPatches`.
Status MeshScene(const Scene& scene, const std::vector<uint32_t>& polygons, float patchSize,
                 uint64_t maxPatches, Mesh* mesh);

}  // namespace vismask
