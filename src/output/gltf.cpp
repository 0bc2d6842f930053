#include "vismask/output/gltf.h"

#include <cstdio>
#include <cstring>

#include "vismask/core/check.h"

namespace vismask {

namespace {

constexpr uint32_t kGlbMagic = 0x46546c67;   // "glTF"
constexpr uint32_t kChunkJson = 0x4e4f534a;  // "JSON"
constexpr uint32_t kChunkBin = 0x004e4942;   // "BIN\0"

void PutU32(uint32_t v, uint8_t* out) {
  out[0] = static_cast<uint8_t>(v);
  out[1] = static_cast<uint8_t>(v >> 8);
  out[2] = static_cast<uint8_t>(v >> 16);
  out[3] = static_cast<uint8_t>(v >> 24);
}

void PutF32(float f, uint8_t* out) {
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  PutU32(bits, out);
}

}  // namespace

void MergeGlbMesh(const GlbMesh& m, GlbMesh* into) {
  if (m.vertices > 0) {
    for (int a = 0; a < 3; ++a) {
      bool first = into->vertices == 0;
      into->lo[a] = first || m.lo[a] < into->lo[a] ? m.lo[a] : into->lo[a];
      into->hi[a] = first || m.hi[a] > into->hi[a] ? m.hi[a] : into->hi[a];
    }
  }
  if (m.maxRadiance > into->maxRadiance) into->maxRadiance = m.maxRadiance;
  into->vertices += m.vertices;
  into->triangles += m.triangles;
}

float GlbRadianceScale(const GlbMesh& m) {
  CHECK(m.maxRadiance <= 0x1p127f);  // a float power of two holds it (NaN fails too)
  float scale = 1.0f;
  while (scale < m.maxRadiance) scale *= 2.0f;
  return scale;
}

size_t WriteGlbHead(const GlbMesh& m, Span<uint8_t> out) {
  CHECK(out.size() >= kGlbHeadBytes);
  CHECK(m.vertices > 0 && m.triangles > 0);
  CHECK(m.vertices < 0xffffffffull);
  CHECK(GlbMaxFileBytes(m) <= kGlbMaxBytes);
  const uint64_t vertexBytes = m.vertices * kGlbVertexBytes;
  const uint64_t indexBytes = m.triangles * kGlbTriangleBytes;
  using ull = unsigned long long;
  // POSITION's bounds: each float printed as its exact double value, so a
  // reader parsing the JSON as doubles gets the very floats of the data.
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = m.lo[a];
    hi[a] = m.hi[a];
  }
  char* json = reinterpret_cast<char*>(out.data()) + 20;
  const size_t room = kGlbHeadBytes - 20 - 8;
  // clang-format off
  int n = std::snprintf(
      json, room,
      "{\"asset\":{\"version\":\"2.0\",\"generator\":\"vismask\"},"
      "\"extensionsUsed\":[\"KHR_materials_unlit\"],"
      "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
      "\"nodes\":[{\"mesh\":0,\"name\":\"radiosity\"}],"
      "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"COLOR_0\":1},"
      "\"indices\":2,\"material\":0,\"mode\":4,\"extras\":{\"radianceScale\":%.17g}}]}],"
      "\"materials\":[{\"name\":\"display radiance (unlit)\","
      "\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,1],\"metallicFactor\":0},"
      "\"extensions\":{\"KHR_materials_unlit\":{}}}],"
      "\"buffers\":[{\"byteLength\":%llu}],"
      "\"bufferViews\":["
      "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":%llu,\"byteStride\":%u,\"target\":34962},"
      "{\"buffer\":0,\"byteOffset\":%llu,\"byteLength\":%llu,\"target\":34963}],"
      "\"accessors\":["
      "{\"bufferView\":0,\"byteOffset\":0,\"componentType\":5126,\"count\":%llu,\"type\":\"VEC3\","
      "\"min\":[%.17g,%.17g,%.17g],\"max\":[%.17g,%.17g,%.17g]},"
      "{\"bufferView\":0,\"byteOffset\":12,\"componentType\":5126,\"count\":%llu,\"type\":\"VEC3\"},"
      "{\"bufferView\":1,\"byteOffset\":0,\"componentType\":5125,\"count\":%llu,\"type\":\"SCALAR\"}]}",
      static_cast<double>(GlbRadianceScale(m)), (ull)(vertexBytes + indexBytes), (ull)vertexBytes, static_cast<unsigned>(kGlbVertexBytes),
      (ull)vertexBytes, (ull)indexBytes, (ull)m.vertices, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
      (ull)m.vertices, (ull)(3 * m.triangles));
  // clang-format on
  CHECK(n > 0 && static_cast<size_t>(n) < room - 3);
  size_t jsonBytes = static_cast<size_t>(n);
  while (jsonBytes % 4 != 0) json[jsonBytes++] = ' ';  // the JSON chunk's padding
  const uint64_t total = 12 + 8 + jsonBytes + 8 + vertexBytes + indexBytes;
  CHECK(total <= kGlbMaxBytes);
  uint8_t* o = out.data();
  PutU32(kGlbMagic, o);
  PutU32(2, o + 4);
  PutU32(static_cast<uint32_t>(total), o + 8);
  PutU32(static_cast<uint32_t>(jsonBytes), o + 12);
  PutU32(kChunkJson, o + 16);
  uint8_t* bin = o + 20 + jsonBytes;
  PutU32(static_cast<uint32_t>(vertexBytes + indexBytes), bin);
  PutU32(kChunkBin, bin + 4);
  return 20 + jsonBytes + 8;
}

void PutGlbVertex(const glm::vec3& position, const glm::vec3& radiance, float scale, uint8_t* out) {
  for (int a = 0; a < 3; ++a) PutF32(position[a], out + 4 * a);
  for (int a = 0; a < 3; ++a) PutF32(radiance[a] / scale, out + 12 + 4 * a);
}

void PutGlbTriangle(uint32_t a, uint32_t b, uint32_t c, uint8_t* out) {
  PutU32(a, out);
  PutU32(b, out + 4);
  PutU32(c, out + 8);
}

}  // namespace vismask
