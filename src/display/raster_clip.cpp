// The antialiased raster's clip (raster_internal.h's ClipProject): a
// piece's camera-space corners clipped to the near plane and the sides of
// the view, then projected to pixel coordinates.
#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "raster_internal.h"

namespace vismask {
namespace {

// Clips `in` (n corners) by the half-space dot(plane.xyz, p) + plane.w >= 0.
// The crossing point of an edge is computed from its endpoints in a fixed
// order (the lexicographically smaller first), so two pieces sharing an edge
// get bit-identical clipped corners.
int ClipPoly(const glm::vec3* in, int n, const glm::vec3& pn, float pw, glm::vec3* out) {
  int m = 0;
  for (int k = 0; k < n; ++k) {
    const glm::vec3& a = in[k];
    const glm::vec3& b = in[(k + 1) % n];
    float fa = glm::dot(pn, a) + pw, fb = glm::dot(pn, b) + pw;
    bool aIn = fa >= 0.0f, bIn = fb >= 0.0f;
    if (aIn) out[m++] = a;
    if (aIn != bIn) {
      bool swap = b.x < a.x || (b.x == a.x && (b.y < a.y || (b.y == a.y && b.z < a.z)));
      const glm::vec3& s = swap ? b : a;
      const glm::vec3& e = swap ? a : b;
      float fs = swap ? fb : fa, fe = swap ? fa : fb;
      float t = fs / (fs - fe);
      out[m++] = s + t * (e - s);
    }
  }
  return m;
}

}  // namespace

bool ClipProject(const View& view, const glm::vec3* q, uint32_t nc, ScreenPoly* out) {
  const float halfW = 0.5f * static_cast<float>(view.width),
              halfH = 0.5f * static_cast<float>(view.height);
  const float f = view.focal;
  glm::vec3 bufA[kMaxPoly], bufB[kMaxPoly];
  int m = static_cast<int>(nc);
  for (int k = 0; k < m; ++k) bufA[k] = q[k];
  m = ClipPoly(bufA, m, glm::vec3(0, 0, 1), -view.nearZ, bufB);
  m = ClipPoly(bufB, m, glm::vec3(f, 0, halfW + 1.0f), 0.0f, bufA);
  m = ClipPoly(bufA, m, glm::vec3(-f, 0, halfW + 1.0f), 0.0f, bufB);
  m = ClipPoly(bufB, m, glm::vec3(0, f, halfH + 1.0f), 0.0f, bufA);
  m = ClipPoly(bufA, m, glm::vec3(0, -f, halfH + 1.0f), 0.0f, bufB);
  if (m < 3) return false;

  // Project.
  Vec2* sp = out->sp;
  float &minX = out->minX, &maxX = out->maxX, &minY = out->minY, &maxY = out->maxY;
  float &zMin = out->zMin, &zMax = out->zMax;
  for (int k = 0; k < m; ++k) {
    float invZ = 1.0f / bufB[k].z;
    sp[k] = Vec2{halfW + f * bufB[k].x * invZ, halfH - f * bufB[k].y * invZ};
    minX = std::fmin(minX, sp[k].x), maxX = std::fmax(maxX, sp[k].x);
    minY = std::fmin(minY, sp[k].y), maxY = std::fmax(maxY, sp[k].y);
    zMin = std::fmin(zMin, bufB[k].z), zMax = std::fmax(zMax, bufB[k].z);
  }
  out->m = m;
  return true;
}

}  // namespace vismask
