#include "vismask/patch.h"

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

namespace vismask {

PatchGeom MakePatchGeom(const Patch& p) {
  PatchGeom g;
  g.n = p.normal;
  g.d = glm::dot(p.normal, p.corner[0]);
  // Tolerance: a relative widening of each edge plane, so shared edges leave
  // no crack through which a ray could pass between two adjacent patches.
  float size = 0.0f;
  for (uint32_t i = 0; i < p.numCorners; ++i)
    size = std::fmax(size, glm::length(p.corner[(i + 1) % p.numCorners] - p.corner[i]));
  for (int i = 0; i < 4; ++i) {
    if (i >= static_cast<int>(p.numCorners)) {
      g.SetEdge(i, glm::vec4(0.0f, 0.0f, 0.0f, -std::numeric_limits<float>::infinity()));
      continue;
    }
    glm::vec3 a = p.corner[i];
    glm::vec3 b = p.corner[(i + 1) % p.numCorners];
    glm::vec3 inward = glm::normalize(glm::cross(p.normal, b - a));  // points inside for CCW
    float w = glm::dot(inward, a);
    float tol = 1e-5f * size + 4.0f * std::numeric_limits<float>::epsilon() * std::fabs(w);
    g.SetEdge(i, glm::vec4(inward, w - tol));
  }
  return g;
}

}  // namespace vismask
