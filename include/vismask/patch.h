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
// iff dot(edge[i].xyz, x) >= edge[i].w for all four edges (a triangle's
// fourth edge is (0,0,0,-inf), which always passes). Edge planes are widened
// by a tiny tolerance so that rays through a shared edge hit at least one of
// its two patches.
struct PatchGeom {
  glm::vec3 n;
  float d;
  glm::vec4 edge[4];
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

// Intersects `ray` with one patch. Returns true and sets *t and *front when the
// ray meets the patch at ray.tMin < t < ray.tMax.
inline bool IntersectPatch(const PatchGeom& g, const Ray& ray, float* t, bool* front) {
  float denom = g.n.x * ray.d.x + g.n.y * ray.d.y + g.n.z * ray.d.z;
  if (denom == 0.0f) return false;
  float num = g.d - (g.n.x * ray.o.x + g.n.y * ray.o.y + g.n.z * ray.o.z);
  float tt = num / denom;
  if (!(tt > ray.tMin && tt < ray.tMax)) return false;
  glm::vec3 x = ray.o + tt * ray.d;
  // All four edge tests, then one branch: which edge fails is unpredictable.
  const glm::vec4* e = g.edge;
  bool outside = (e[0].x * x.x + e[0].y * x.y + e[0].z * x.z < e[0].w) |
                 (e[1].x * x.x + e[1].y * x.y + e[1].z * x.z < e[1].w) |
                 (e[2].x * x.x + e[2].y * x.y + e[2].z * x.z < e[2].w) |
                 (e[3].x * x.x + e[3].y * x.y + e[3].z * x.z < e[3].w);
  if (outside) return false;
  *t = tt;
  *front = denom < 0.0f;
  return true;
}

}  // namespace vismask
