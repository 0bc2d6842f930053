// glTF export: the solved mesh as one binary glTF 2.0 file (GLB), written
// without a glTF library and without allocating. The file holds one scene,
// one node, one mesh of one TRIANGLES primitive: POSITION (float VEC3, in
// scene units and the OBJ's axes, with min/max) and COLOR_0 (float VEC3,
// the linear display radiance image.pfm shows, unclamped), interleaved in
// one buffer view, then UNSIGNED_INT indices; one unlit material
// (KHR_materials_unlit, in extensionsUsed, baseColorFactor [1,1,1,1]).
//
// The file is streamed: WriteGlbHead formats everything before the vertex
// data (12-byte header, JSON chunk, BIN chunk header) from the counts and
// bounds alone, and the vertices and triangles follow in order, each packed
// by PutGlbVertex / PutGlbTriangle (little-endian whatever the host).
// docs/DESIGN.md, "glTF export format".
#pragma once
#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>

#include "vismask/core/span.h"

namespace vismask {

// What the head of the file needs to know of the mesh (also what one
// environment contributes to it: counts add up, bounds widen).
struct GlbMesh {
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  float lo[3] = {0, 0, 0};   // the positions' bounds (POSITION min/max); only
  float hi[3] = {0, 0, 0};   // meaningful when vertices > 0
  float maxRadiance = 0.0f;  // the largest colour component, before scaling
};

// extras.radianceScale: the least power of two (at least 1) that is no less
// than m.maxRadiance, which must be at most 2^127 (CHECK; the scene
// loader's radiosity bound, 1e36, keeps it far below). COLOR_0 = radiance / scale,
// exact (a power of two) but for values below 2^-126 * scale.
float GlbRadianceScale(const GlbMesh& m);

constexpr size_t kGlbVertexBytes = 24;    // position, COLOR_0: 6 floats
constexpr size_t kGlbTriangleBytes = 12;  // 3 UNSIGNED_INT indices
// The most bytes WriteGlbHead writes (its JSON has a fixed shape).
constexpr size_t kGlbHeadBytes = 4096;
// A GLB's length is a 32-bit field.
constexpr uint64_t kGlbMaxBytes = 0xffffffffull;

// Widens `into` by `m` (counts add, bounds widen where m has vertices).
void MergeGlbMesh(const GlbMesh& m, GlbMesh* into);

// The BIN chunk's payload: vertex data, then indices (a multiple of 4).
inline uint64_t GlbBinBytes(const GlbMesh& m) {
  return m.vertices * kGlbVertexBytes + m.triangles * kGlbTriangleBytes;
}
// The most the whole file can take: the head at its largest and the payload.
inline uint64_t GlbMaxFileBytes(const GlbMesh& m) {
  return kGlbHeadBytes + GlbBinBytes(m);
}

// Formats the GLB header, the JSON chunk (padded with spaces to 4 bytes) and
// the BIN chunk's header into `out` (at least kGlbHeadBytes) and returns
// how many bytes that is; the file is then the head, GlbBinBytes(m) bytes
// of vertices and triangles, and nothing else (the total is in the header).
// Requires m.vertices > 0, m.triangles > 0, every index below
// 0xffffffff, and GlbMaxFileBytes(m) <= kGlbMaxBytes (CHECK: the caller
// refuses such a mesh at init). Allocates nothing.
size_t WriteGlbHead(const GlbMesh& m, Span<uint8_t> out);

// One vertex, kGlbVertexBytes at `out`: position, then radiance / scale
// (scale = GlbRadianceScale of the whole mesh).
void PutGlbVertex(const glm::vec3& position, const glm::vec3& radiance, float scale, uint8_t* out);
// One triangle, kGlbTriangleBytes at `out`: its vertices' indices in the
// whole file, counter-clockwise seen from the front (glTF's front face).
void PutGlbTriangle(uint32_t a, uint32_t b, uint32_t c, uint8_t* out);

}  // namespace vismask
