// Sampling a shooting patch: uniform points on it and cosine-distributed
// directions over its front hemisphere, in the patch's own frame (tangent =
// first edge). The same frame indexes the visibility mask's phi.
#pragma once
#include <glm/vec3.hpp>

#include "vismask/solve/patch.h"

namespace vismask {

struct Frame {
  glm::vec3 t;  // tangent: along corner[1] - corner[0]
  glm::vec3 b;  // bitangent: cross(n, t)
  glm::vec3 n;  // the patch's normal
  glm::vec3 ToWorld(const glm::vec3& v) const { return v.x * t + v.y * b + v.z * n; }
};

// What a shot needs to sample its patch, prepared once per shot.
struct PatchSampler {
  glm::vec3 c0, e1, e2, e3;  // corner0 and the edges to corners 1, 2, 3
  float split;               // area fraction of triangle (0,1,2); 1 for triangles
  Frame frame;

  // A uniform point on the patch from three uniforms in [0, 1).
  glm::vec3 Point(float u0, float u1, float u2) const;
};

PatchSampler MakePatchSampler(const Patch& p);

// A unit direction in the local frame (z = normal) with pdf cos(theta)/pi.
glm::vec3 CosineDirection(float u1, float u2);

}  // namespace vismask
