// Patch: the unit of radiosity. A planar convex polygon of 3 or 4 corners,
// one-sided (it emits, receives and reflects on its front side only, the side
// from which its corners run counter-clockwise).
//
// A patch's data is split by who reads it:
//   PatchGeom   - what a ray test reads (plane and projected corners): 48 bytes, hot.
//   Patch       - geometry and material for sampling, meshing and output.
//   PatchEnergy - the solver's state in double (radiosity, unshot power).
#pragma once
#include <cmath>
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

// Ray-test data, 48 bytes. The plane is dot(n, x) == d, with n scaled so
// that its largest component, on axis k (PlaneAxis), is exactly +1 or -1:
// the patch projects onto the coordinates (i, j) = ((k + 1) % 3, (k + 2) % 3)
// without folding, and is tested there against its corners (u[m], v[m]),
// stored counter-clockwise in (i, j) (a triangle repeats its last corner, an
// edge of length 0 that every point passes). The corners are pushed out
// from the patch by a tiny tolerance (MakePatchGeom), so that rays through
// a shared edge hit at least one of its two patches. The corners are stored
// coordinate by coordinate, so that one 4-wide test does all four edges
// (OutsideEdges).
struct PatchGeom {
  glm::vec3 n;
  float d;
  float u[4], v[4];
};
static_assert(sizeof(PatchGeom) == 48, "PatchGeom is the grid's hot data");

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
  // With neighbours, the kOpenSide x kOpenSide cells of a quad's parameter
  // square that are not buried in a closed solid (ElementTree::open, bit
  // a * 4 + b), when some are and some are not: its rays leave from those
  // cells alone, locally and wherever a packet carries the shot
  // (ElementTree::OpenCellsPoint). 0: every cell open, or not measured.
  uint16_t openCells;
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

// Whether the patch emits (Ke > 0 in some channel).
inline bool Emits(const Patch& p) {
  return p.ke.r > 0.0f || p.ke.g > 0.0f || p.ke.b > 0.0f;
}

// The mean of the patch's corners.
inline glm::vec3 CentreOf(const Patch& p) {
  glm::vec3 centre(0.0f);
  for (uint32_t k = 0; k < p.numCorners; ++k) centre += p.corner[k];
  return centre / static_cast<float>(p.numCorners);
}

// Builds a patch's ray-test data from its corners and normal.
PatchGeom MakePatchGeom(const Patch& p);

// The ray-test data of a patch's twin (mesh.h, AddTwins: the same corners,
// reversed), from the original's: plane negated, the same corners. Not
// MakePatchGeom of the twin, whose corners would round differently.
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

// The axis k of g's plane: the first component of n that is +1 or -1
// exactly (the largest, MakePatchGeom; an earlier, smaller one cannot round
// to 1). 2 when there is none (a degenerate patch, which no ray hits).
inline int PlaneAxis(const glm::vec3& n) {
  return std::fabs(n.x) == 1.0f ? 0 : (std::fabs(n.y) == 1.0f ? 1 : 2);
}

// Whether the point (x, y) of the plane's coordinates (i, j) fails any of
// g's four edge tests: corners a, b (the next) fail it when
// (b.u - a.u) * (y - a.v) - (b.v - a.v) * (x - a.u) < 0. The portable form
// tests all four, then branches once: which edge fails is unpredictable.
inline bool OutsideEdgesScalar(const PatchGeom& g, float x, float y) {
  bool out = false;
  for (int m = 0; m < 4; ++m) {
    const int b = (m + 1) & 3;
    out |= (g.u[b] - g.u[m]) * (y - g.v[m]) - (g.v[b] - g.v[m]) * (x - g.u[m]) < 0.0f;
  }
  return out;
}

// The same, four lanes at once on x86-64 (SSE2) and aarch64 (NEON): each
// lane forms the scalar form's differences and products in the same order
// and its ordered less-than (false on a NaN), with no fused multiply-add
// (the build has -ffp-contract=off), so every path gives the same answer
// for every input (tests/patch_simd_test.cpp). 32-bit ARM keeps the scalar
// form: its NEON flushes subnormals to zero.
inline bool OutsideEdges(const PatchGeom& g, float x, float y) {
#if defined(__SSE2__)
  const __m128 u = _mm_loadu_ps(g.u), v = _mm_loadu_ps(g.v);
  const __m128 un = _mm_shuffle_ps(u, u, _MM_SHUFFLE(0, 3, 2, 1));
  const __m128 vn = _mm_shuffle_ps(v, v, _MM_SHUFFLE(0, 3, 2, 1));
  const __m128 e = _mm_sub_ps(_mm_mul_ps(_mm_sub_ps(un, u), _mm_sub_ps(_mm_set1_ps(y), v)),
                              _mm_mul_ps(_mm_sub_ps(vn, v), _mm_sub_ps(_mm_set1_ps(x), u)));
  return _mm_movemask_ps(_mm_cmplt_ps(e, _mm_setzero_ps())) != 0;
#elif defined(__aarch64__) && defined(__ARM_NEON)
  const float32x4_t u = vld1q_f32(g.u), v = vld1q_f32(g.v);
  const float32x4_t un = vextq_f32(u, u, 1), vn = vextq_f32(v, v, 1);
  const float32x4_t e = vsubq_f32(vmulq_f32(vsubq_f32(un, u), vsubq_f32(vdupq_n_f32(y), v)),
                                  vmulq_f32(vsubq_f32(vn, v), vsubq_f32(vdupq_n_f32(x), u)));
  return vmaxvq_u32(vcltq_f32(e, vdupq_n_f32(0.0f))) != 0;
#else
  return OutsideEdgesScalar(g, x, y);
#endif
}

// Intersects the ray o + t d with one patch. Returns true and sets *t and
// *front when the ray meets the patch at tMin < t < tMax.
inline bool IntersectPatch(const PatchGeom& g, const glm::vec3& o, const glm::vec3& d, float tMin,
                           float tMax, float* t, bool* front) {
  float denom = g.n.x * d.x + g.n.y * d.y + g.n.z * d.z;
  if (denom == 0.0f) return false;
  float num = g.d - (g.n.x * o.x + g.n.y * o.y + g.n.z * o.z);
  float tt = num / denom;
  if (!(tt > tMin && tt < tMax)) return false;
  const float x[3] = {o.x + tt * d.x, o.y + tt * d.y, o.z + tt * d.z};
  const int k = PlaneAxis(g.n);
  const float xi = k == 2 ? x[0] : x[k + 1], xj = k == 0 ? x[2] : x[k - 1];
  if (OutsideEdges(g, xi, xj)) return false;
  *t = tt;
  *front = denom < 0.0f;
  return true;
}

// The same for `ray`, in (ray.tMin, ray.tMax).
inline bool IntersectPatch(const PatchGeom& g, const Ray& ray, float* t, bool* front) {
  return IntersectPatch(g, ray.o, ray.d, ray.tMin, ray.tMax, t, front);
}

// Corner m of the region g's edge tests accept (corners[m] pushed out),
// on g's plane, in world coordinates.
glm::dvec3 GeomCorner(const PatchGeom& g, int m);

}  // namespace vismask
