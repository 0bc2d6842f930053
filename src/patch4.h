// Patch4: IntersectPatch (patch.h) on four patches at once, for the grid
// walk. Each lane does IntersectPatch's float arithmetic in its order (the
// same products and sums, a real division, no fused multiply-add: the
// Makefile's -ffp-contract=off), so every lane's answer, t and side are
// bit-identical to the scalar test's (tests/patch4_test.cpp). SSE2 on
// x86-64, NEON on aarch64, IntersectPatch lane by lane elsewhere (32-bit ARM's
// NEON has no division and flushes denormals).
#pragma once
#include <cstdint>

#include "vismask/patch.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#define VISMASK_PATCH4_SSE2 1
#elif defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#define VISMASK_PATCH4_NEON 1
#endif

namespace vismask {
namespace patch4 {

#if defined(VISMASK_PATCH4_SSE2)

using V = __m128;
inline V Splat(float f) {
  return _mm_set1_ps(f);
}
inline V Load(const float* p) {
  return _mm_loadu_ps(p);
}
inline V Add(V a, V b) {
  return _mm_add_ps(a, b);
}
inline V Sub(V a, V b) {
  return _mm_sub_ps(a, b);
}
inline V Mul(V a, V b) {
  return _mm_mul_ps(a, b);
}
inline V Div(V a, V b) {
  return _mm_div_ps(a, b);
}
// Comparisons give all-ones lanes where true (false where either is NaN,
// except Ne, true there, like the scalar operators).
inline V Lt(V a, V b) {
  return _mm_cmplt_ps(a, b);
}
inline V Gt(V a, V b) {
  return _mm_cmpgt_ps(a, b);
}
inline V Ne(V a, V b) {
  return _mm_cmpneq_ps(a, b);
}
inline V And(V a, V b) {
  return _mm_and_ps(a, b);
}
inline V Or(V a, V b) {
  return _mm_or_ps(a, b);
}
inline V AndNot(V a, V b) {
  return _mm_andnot_ps(b, a);
}  // a and not b
inline unsigned Bits(V m) {
  return static_cast<unsigned>(_mm_movemask_ps(m));
}
inline void Store(float* p, V a) {
  _mm_storeu_ps(p, a);
}
inline void Transpose(V& a, V& b, V& c, V& d) {
  _MM_TRANSPOSE4_PS(a, b, c, d);
}

#elif defined(VISMASK_PATCH4_NEON)

using V = float32x4_t;
inline V Splat(float f) {
  return vdupq_n_f32(f);
}
inline V Load(const float* p) {
  return vld1q_f32(p);
}
inline V Add(V a, V b) {
  return vaddq_f32(a, b);
}
inline V Sub(V a, V b) {
  return vsubq_f32(a, b);
}
inline V Mul(V a, V b) {
  return vmulq_f32(a, b);
}
inline V Div(V a, V b) {
  return vdivq_f32(a, b);
}
inline V Lt(V a, V b) {
  return vreinterpretq_f32_u32(vcltq_f32(a, b));
}
inline V Gt(V a, V b) {
  return vreinterpretq_f32_u32(vcgtq_f32(a, b));
}
inline V Ne(V a, V b) {
  return vreinterpretq_f32_u32(vmvnq_u32(vceqq_f32(a, b)));
}
inline V And(V a, V b) {
  return vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(a), vreinterpretq_u32_f32(b)));
}
inline V Or(V a, V b) {
  return vreinterpretq_f32_u32(vorrq_u32(vreinterpretq_u32_f32(a), vreinterpretq_u32_f32(b)));
}
inline V AndNot(V a, V b) {  // a and not b
  return vreinterpretq_f32_u32(vbicq_u32(vreinterpretq_u32_f32(a), vreinterpretq_u32_f32(b)));
}
inline unsigned Bits(V m) {
  static const uint32_t kWeight[4] = {1, 2, 4, 8};
  return vaddvq_u32(vandq_u32(vreinterpretq_u32_f32(m), vld1q_u32(kWeight)));
}
inline void Store(float* p, V a) {
  vst1q_f32(p, a);
}
inline void Transpose(V& a, V& b, V& c, V& d) {
  float32x4x2_t ab = vtrnq_f32(a, b);  // a0 b0 a2 b2, a1 b1 a3 b3
  float32x4x2_t cd = vtrnq_f32(c, d);
  a = vcombine_f32(vget_low_f32(ab.val[0]), vget_low_f32(cd.val[0]));
  b = vcombine_f32(vget_low_f32(ab.val[1]), vget_low_f32(cd.val[1]));
  c = vcombine_f32(vget_high_f32(ab.val[0]), vget_high_f32(cd.val[0]));
  d = vcombine_f32(vget_high_f32(ab.val[1]), vget_high_f32(cd.val[1]));
}

#endif

#if defined(VISMASK_PATCH4_SSE2) || defined(VISMASK_PATCH4_NEON)

// A ray, each coordinate and bound in all four lanes.
struct Ray4 {
  V ox, oy, oz, dx, dy, dz, tMin, tMax;
  explicit Ray4(const Ray& r)
      : ox(Splat(r.o.x)),
        oy(Splat(r.o.y)),
        oz(Splat(r.o.z)),
        dx(Splat(r.d.x)),
        dy(Splat(r.d.y)),
        dz(Splat(r.d.z)),
        tMin(Splat(r.tMin)),
        tMax(Splat(r.tMax)) {}
  void SetTMax(float t) { tMax = Splat(t); }
};

// Row `row` (4 floats: the plane, or edge row - 1) of the four patches, by lane.
inline void Rows(const PatchGeom* const* g, int row, V* x, V* y, V* z, V* w) {
  V a = Load(reinterpret_cast<const float*>(g[0]) + 4 * row);
  V b = Load(reinterpret_cast<const float*>(g[1]) + 4 * row);
  V c = Load(reinterpret_cast<const float*>(g[2]) + 4 * row);
  V d = Load(reinterpret_cast<const float*>(g[3]) + 4 * row);
  Transpose(a, b, c, d);
  *x = a;
  *y = b;
  *z = c;
  *w = d;
}

// IntersectPatch(*g[i], ray, &t[i], &front) for i = 0..3: bit i of the result
// is whether patch g[i] is hit; where it is, t[i] is its t and bit i of
// *front its side. t[i] of a lane not hit is unspecified.
// Inlined: a call would spill the ray's lanes to memory at every group.
__attribute__((always_inline)) inline unsigned Intersect4(const PatchGeom* const* g, const Ray4& r,
                                                          float* t, unsigned* front) {
  static_assert(sizeof(PatchGeom) == 20 * sizeof(float), "PatchGeom: a plane and four edges");
  V nx, ny, nz, nd;
  Rows(g, 0, &nx, &ny, &nz, &nd);
  V zero = Splat(0.0f);
  V denom = Add(Add(Mul(nx, r.dx), Mul(ny, r.dy)), Mul(nz, r.dz));
  V num = Sub(nd, Add(Add(Mul(nx, r.ox), Mul(ny, r.oy)), Mul(nz, r.oz)));
  V tt = Div(num, denom);
  V in = And(Ne(denom, zero), And(Gt(tt, r.tMin), Lt(tt, r.tMax)));
  if (Bits(in) == 0) return 0;
  V x = Add(r.ox, Mul(tt, r.dx));
  V y = Add(r.oy, Mul(tt, r.dy));
  V z = Add(r.oz, Mul(tt, r.dz));
  V outside = zero;
  for (int e = 1; e <= 4; ++e) {
    V ex, ey, ez, ew;
    Rows(g, e, &ex, &ey, &ez, &ew);
    outside = Or(outside, Lt(Add(Add(Mul(ex, x), Mul(ey, y)), Mul(ez, z)), ew));
  }
  Store(t, tt);
  *front = Bits(Lt(denom, zero));
  return Bits(AndNot(in, outside));
}

#else

struct Ray4 {
  Ray ray;
  explicit Ray4(const Ray& r) : ray(r) {}
  void SetTMax(float t) { ray.tMax = t; }
};

inline unsigned Intersect4(const PatchGeom* const* g, const Ray4& r, float* t, unsigned* front) {
  unsigned hit = 0;
  *front = 0;
  for (unsigned i = 0; i < 4; ++i) {
    bool f;
    if (!IntersectPatch(*g[i], r.ray, &t[i], &f)) continue;
    hit |= 1u << i;
    *front |= static_cast<unsigned>(f) << i;
  }
  return hit;
}

#endif

}  // namespace patch4
}  // namespace vismask
