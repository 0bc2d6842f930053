#include "vismask/camera.h"

#include <cmath>

#include <glm/geometric.hpp>

namespace vismask {

Camera DefaultCamera(const Bounds& b) {
  Camera c;
  glm::vec3 centre = 0.5f * (b.lo + b.hi);
  glm::vec3 half = 0.5f * (b.hi - b.lo);
  float tanHalf = std::tan(0.5f * c.fovyDeg * 3.14159265358979f / 180.0f);
  float reach = std::fmax(half.x, half.y);
  if (reach <= 0.0f) reach = std::fmax(half.z, 1.0f);
  float distance = 1.04f * reach / tanHalf;
  c.eye = glm::vec3(centre.x, centre.y, b.lo.z - distance);
  c.target = glm::vec3(centre.x, centre.y, b.lo.z);
  c.up = glm::vec3(0.0f, 1.0f, 0.0f);
  return c;
}

bool MakeView(const Camera& c, int width, int height, View* v) {
  if (!(c.fovyDeg > 0.0f && c.fovyDeg < 180.0f) || width <= 0 || height <= 0) return false;
  glm::vec3 f = c.target - c.eye;
  if (!(glm::length(f) > 0.0f)) return false;
  v->nearZ = 1e-3f * glm::length(f);
  f = glm::normalize(f);
  glm::vec3 r = glm::cross(f, c.up);
  if (!(glm::length(r) > 1e-6f * glm::length(c.up))) return false;
  r = glm::normalize(r);
  v->eye = c.eye;
  v->forward = f;
  v->right = r;
  v->up = glm::cross(r, f);
  v->width = width;
  v->height = height;
  v->focal = 0.5f * static_cast<float>(height) / std::tan(0.5f * c.fovyDeg * 3.14159265358979f / 180.0f);
  return true;
}

}  // namespace vismask
