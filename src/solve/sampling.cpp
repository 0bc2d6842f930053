#include "vismask/solve/sampling.h"

#include <cmath>
#include <glm/geometric.hpp>

#include "vismask/core/fminmax.h"

namespace vismask {

PatchSampler MakePatchSampler(const Patch& p) {
  PatchSampler s;
  s.c0 = p.corner[0];
  s.e1 = p.corner[1] - p.corner[0];
  s.e2 = p.corner[2] - p.corner[0];
  s.e3 = p.corner[3] - p.corner[0];
  double a1 = 0.5 * glm::length(glm::dvec3(glm::cross(s.e1, s.e2)));
  double a2 = p.numCorners == 4 ? 0.5 * glm::length(glm::dvec3(glm::cross(s.e2, s.e3))) : 0.0;
  s.split = static_cast<float>(a1 / (a1 + a2));
  s.frame.n = p.normal;
  s.frame.t = glm::normalize(s.e1 - glm::dot(s.e1, p.normal) * p.normal);
  s.frame.b = glm::cross(p.normal, s.frame.t);
  return s;
}

glm::vec3 PatchSampler::Point(float u0, float u1, float u2) const {
  // Pick one of the two triangles by area, then the square-root map
  // (Shirley): barycentrics (1 - su, su (1 - u2), su u2).
  const glm::vec3& ea = u0 < split ? e1 : e2;
  const glm::vec3& eb = u0 < split ? e2 : e3;
  // Kept a hair inside the triangle: a point on the patch's outline lies on
  // the plane of the wall that meets it there, and a ray from it could pass
  // out of a closed box between the two (su rounds to 1 for u1 > 1 - 3e-8).
  constexpr float kMargin = 1e-5f;
  float su = FMin(FMax(std::sqrt(u1), kMargin), 1.0f - kMargin);
  u2 = FMin(FMax(u2, kMargin), 1.0f - kMargin);
  return c0 + (su * (1.0f - u2)) * ea + (su * u2) * eb;
}

glm::vec3 CosineDirection(float u1, float u2) {
  float r = std::sqrt(u1);
  float phi = 6.283185307179586f * u2;
  float z = std::sqrt(FMax(0.0f, 1.0f - u1));
  return glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
}

}  // namespace vismask
