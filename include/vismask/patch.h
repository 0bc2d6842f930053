// Patch: the unit of radiosity. A planar convex polygon of 3 or 4 corners,
// one-sided (it emits, receives and reflects on its front side only, the side
// from which its corners run counter-clockwise).
//
// A patch's data is split by who reads it:
//   PatchGeom   - what a ray test reads (plane and edge planes): 80 bytes, hot.
//   Patch       - geometry and material for sampling, meshing and output.
//   PatchEnergy - the solver's state in double (radiosity, unshot power).
#pragma once
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace vismask {

constexpr uint32_t kNoPatch = 0xffffffffu;

// A ray: origin, direction (need not be unit length; t is in its units) and
// the open interval (tMin, tMax) of accepted hits.
struct Ray {
  glm::vec3 o;
  glm::vec3 d;
  float tMin;
  float tMax;
};

// The closest hit of a ray: the patch (index local to its environment), the
// ray parameter, and whether the ray struck the front side.
struct Hit {
  uint32_t patch = kNoPatch;
  float t = 0.0f;
  bool front = false;
};

// Ray-test data. A point x on the plane dot(n, x) == d is inside the patch
// iff dot(edge i's normal, x) >= edge i's offset for all four edges (a
// triangle's fourth edge is (0,0,0,-inf), which always passes). Edge planes
// are widened by a tiny tolerance so that rays through a shared edge hit at
// least one of its two patches. The edges are stored component by component
// (ex[i], ey[i], ez[i], ew[i]), so that one 4-wide test does all four
// (OutsideEdges).
struct PatchGeom {
  glm::vec3 n;
  float d;
  float ex[4], ey[4], ez[4], ew[4];
  glm::vec4 Edge(int i) const { return glm::vec4(ex[i], ey[i], ez[i], ew[i]); }
  void SetEdge(int i, const glm::vec4& e) {
    ex[i] = e.x;
    ey[i] = e.y;
    ez[i] = e.z;
    ew[i] = e.w;
  }
};
static_assert(sizeof(PatchGeom) == 80, "PatchGeom is the grid's hot data");

struct Patch {
  glm::vec3
      corner[4];     // counter-clockwise seen from the front; corner[3] == corner[2] for triangles
  glm::vec3 normal;  // unit, front side
  glm::vec3 kd;      // diffuse reflectance per channel, in [0, 1]
  glm::vec3 ke;      // emitted exitance per channel (W/m^2 in scene units)
  float area;        // in scene units^2
  uint32_t numCorners;  // 3 or 4
  uint32_t surface;     // index of the source polygon in the scene
  uint32_t vertex[4];   // display-lattice vertices, for Gouraud shading
  uint32_t globalId;    // id in the whole scene, independent of partition
};

constexpr uint32_t kNoTexture = 0xffffffffu;

// What a textured patch adds (texture.h): its texture, the uv at its corners
// (corner 3 repeats corner 2 for a triangle), and the display scale
// kd_mat / kd per channel (0 where the patch's kd is 0: its light is lost).
struct PatchTexture {
  uint32_t texture = kNoTexture;
  glm::vec3 scale{0.0f};
  glm::vec2 uv[4];
};

struct PatchEnergy {
  double b[3];       // radiosity (W/m^2): emitted + received and reflected
  double unshot[3];  // unshot power (W): B*area not yet distributed
  double var[3];     // Monte Carlo variance of b: the sum over the rays it
                     // received of (kd * share / area)^2 (docs/DESIGN.md)
};

// A patch's key in the shooting order: its unshot power, channels summed.
inline double UnshotKey(const PatchEnergy& e) {
  return e.unshot[0] + e.unshot[1] + e.unshot[2];
}

// Builds a patch's ray-test data from its corners and normal.
PatchGeom MakePatchGeom(const Patch& p);

// The ray-test data of a patch's twin (mesh.h, AddTwins: the same corners,
// reversed), from the original's: plane negated, the same edge planes. Not
// MakePatchGeom of the twin, whose edge offsets would round differently.
// Negation is exact in IEEE arithmetic, and so is every product and sum
// IntersectPatch forms from it, so a ray meets both at bit-identical t and
// point, and both or neither pass the edge tests: one from the front, the
// other from the back.
inline PatchGeom TwinGeom(const PatchGeom& g) {
  PatchGeom t = g;
  t.n = -g.n;
  t.d = -g.d;
  return t;
}

// Whether x fails any of g's four edge tests (dot(edge, x) < offset). The
// portable form tests all four, then branches once: which edge fails is
// unpredictable.
inline bool OutsideEdgesScalar(const PatchGeom& g, const glm::vec3& x) {
  return (g.ex[0] * x.x + g.ey[0] * x.y + g.ez[0] * x.z < g.ew[0]) |
         (g.ex[1] * x.x + g.ey[1] * x.y + g.ez[1] * x.z < g.ew[1]) |
         (g.ex[2] * x.x + g.ey[2] * x.y + g.ez[2] * x.z < g.ew[2]) |
         (g.ex[3] * x.x + g.ey[3] * x.y + g.ez[3] * x.z < g.ew[3]);
}

// The same, four lanes at once on x86-64 (SSE2) and aarch64 (NEON): each
// lane forms the scalar form's products, its two sums in the same order and
// its ordered less-than (false on a NaN), with no fused multiply-add (the
// build has -ffp-contract=off), so every path gives the same answer for
// every input (tests/patch_simd_test.cpp). 32-bit ARM keeps the scalar
// form: its NEON flushes subnormals to zero.
inline bool OutsideEdges(const PatchGeom& g, const glm::vec3& x) {
#if defined(__SSE2__)
  const __m128 s = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(g.ex), _mm_set1_ps(x.x)),
                                         _mm_mul_ps(_mm_loadu_ps(g.ey), _mm_set1_ps(x.y))),
                              _mm_mul_ps(_mm_loadu_ps(g.ez), _mm_set1_ps(x.z)));
  return _mm_movemask_ps(_mm_cmplt_ps(s, _mm_loadu_ps(g.ew))) != 0;
#elif defined(__aarch64__) && defined(__ARM_NEON)
  const float32x4_t s = vaddq_f32(vaddq_f32(vmulq_f32(vld1q_f32(g.ex), vdupq_n_f32(x.x)),
                                            vmulq_f32(vld1q_f32(g.ey), vdupq_n_f32(x.y))),
                                  vmulq_f32(vld1q_f32(g.ez), vdupq_n_f32(x.z)));
  return vmaxvq_u32(vcltq_f32(s, vld1q_f32(g.ew))) != 0;
#else
  return OutsideEdgesScalar(g, x);
#endif
}

// Intersects `ray` with one patch. Returns true and sets *t and *front when the
// ray meets the patch at ray.tMin < t < ray.tMax.
inline bool IntersectPatch(const PatchGeom& g, const Ray& ray, float* t, bool* front) {
  float denom = g.n.x * ray.d.x + g.n.y * ray.d.y + g.n.z * ray.d.z;
  if (denom == 0.0f) return false;
  float num = g.d - (g.n.x * ray.o.x + g.n.y * ray.o.y + g.n.z * ray.o.z);
  float tt = num / denom;
  if (!(tt > ray.tMin && tt < ray.tMax)) return false;
  glm::vec3 x = ray.o + tt * ray.d;
  if (OutsideEdges(g, x)) return false;
  *t = tt;
  *front = denom < 0.0f;
  return true;
}

}  // namespace vismask
