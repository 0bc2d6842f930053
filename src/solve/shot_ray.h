// A shot's rays, shared by the files of Environment that trace or
// regenerate them (trace.cpp, env_read.cpp): the slab test against a box,
// a shot's ray points, a ray from its uniforms, and the pixel a ray enters
// a box by, seen from the shooter's centre. Internal to src/solve.
#pragma once
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "vismask/core/fminmax.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/element.h"
#include "vismask/solve/element_tree.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/patch.h"
#include "vismask/solve/rng.h"
#include "vismask/solve/sampling.h"
#include "vismask/solve/sobol.h"

namespace vismask {

// The entry and exit parameters of `ray` through `box` (slab test).
inline bool Slabs(const Ray& ray, const Bounds& box, float* t0, float* t1) {
  float lo = -std::numeric_limits<float>::infinity(), hi = std::numeric_limits<float>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (ray.d[a] == 0.0f) {
      if (ray.o[a] < box.lo[a] || ray.o[a] > box.hi[a]) return false;
      continue;
    }
    float inv = 1.0f / ray.d[a];
    float ta = (box.lo[a] - ray.o[a]) * inv, tb = (box.hi[a] - ray.o[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    lo = FMax(lo, ta);
    hi = FMin(hi, tb);
  }
  *t0 = lo;
  *t1 = hi;
  return hi >= lo && hi > 0.0f;
}

// The five uniforms of ray r of a shot, (point: triangle, u, v; direction:
// u, v): scrambled Sobol' point first + r (direction in the two
// best-stratified dimensions), or with `sobol` off the next five PCG32
// draws of the shot's stream, in which case rays must be taken in order.
class RayPoints {
 public:
  RayPoints(bool sobol, uint64_t stream, uint32_t first = 0)
      : sobol_(sobol),
        first_(first),
        qmc_(Mix64(stream ^ 0xd1b54a32d192ed03ull)),
        rng_(ShotRng(stream)) {}
  // Ray r; with Sobol', `sequential` promises r is the previous call's + 1
  // (starting at 0), which walks the points one XOR at a time; otherwise
  // the point is reached from the last one drawn (ShotSampler::Seek).
  void Next(uint32_t r, float u[5], bool sequential = false) {
    if (!sobol_) {
      for (int k = 0; k < 5; ++k) u[k] = rng_.NextFloat();
      return;
    }
    float p[kSobolDims];
    if (sequential && (r > 0 || first_ == 0))
      qmc_.Next(p);
    else
      qmc_.Seek(first_ + r, p);
    u[0] = p[4];
    u[1] = p[2];
    u[2] = p[3];
    u[3] = p[0];
    u[4] = p[1];
  }
  bool randomAccess() const { return sobol_; }

 private:
  bool sobol_;
  uint32_t first_;
  ShotSampler qmc_;
  Rng rng_;
};

// Ray r of a shot from its five uniforms (RayPoints): its origin on the
// shooter lifted `lift` off the plane, its direction cosine-distributed about
// the normal (*local: in the shooter's frame). Every hit from t = 0 counts
// (the shooter and its twin are skipped): a ray from near a corner hits the
// wall beside it however close. A tMin > 0 instead let such rays through the
// wall and out of a closed box, a bias of ~4e-6 of the shot power a bounce,
// which rho = 0.999 amplifies to -0.4% (docs/STABILITY.md).
inline Ray ShotRayFrom(const glm::vec3& point, const PatchSampler& sampler, const glm::vec3& local,
                       float lift) {
  Ray ray;
  ray.o = point + lift * sampler.frame.n;
  ray.d = sampler.frame.ToWorld(local);
  ray.tMin = 0.0f;
  ray.tMax = std::numeric_limits<float>::infinity();
  return ray;
}
inline Ray ShotRay(const PatchSampler& sampler, const float u[5], float lift, glm::vec3* local) {
  *local = CosineDirection(u[3], u[4]);
  return ShotRayFrom(sampler.Point(u[0], u[1], u[2]), sampler, *local, lift);
}

// Ray r of a shot from an unsplit patch's quarters (ElementTree::
// QuarterOrigins): ShotRay's with the quarters' origin, the uniform one
// not made.
inline Ray QuarterRay(const Patch& shooter, const PatchSampler& sampler,
                      const ElementTree::QuarterOrigins& origins, const float u[5], float lift,
                      glm::vec3* local) {
  *local = CosineDirection(u[3], u[4]);
  return ShotRayFrom(PatchPoint(shooter, origins.Point(u)), sampler, *local, lift);
}

// The pixel of the direction from the shooter's centre to where `ray`
// (local direction `local`) enters a foreign environment at t0: the
// centre's view of the same crossing, so off-centre rays are not judged by
// a parallel ray that crosses elsewhere.
inline uint32_t EntryPixel(const Ray& ray, float t0, const glm::vec3& centre, const Frame& frame,
                           const glm::vec3& local, const MaskDirections& dirs) {
  glm::vec3 q = ray.o + FMax(t0, 0.0f) * ray.d - centre;
  glm::vec3 l(glm::dot(q, frame.t), glm::dot(q, frame.b), glm::dot(q, frame.n));
  float len = glm::length(l);
  return dirs.Pixel(len > 0.0f && l.z > 0.0f ? l / len : local);
}

}  // namespace vismask
