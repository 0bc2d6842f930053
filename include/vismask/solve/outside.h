// Light from outside the scene (--sky, --sun): a uniform sky of radiance L in
// every direction the scene does not block, and a sun of irradiance E (on a
// surface facing it) in a cone of its angular diameter. Neither is geometry:
// each environment whose box lies on a face of the scene's box holds, for
// that face, an *outside shooter*, a patch on the face looking in, that
// shoots what crosses the face into the box: pi * L * area for the sky
// (cosine-distributed rays, a uniform radiance through a plane), E * cos *
// area for the sun (rays in the sun's cone), where cos is between the face's
// inward normal and the sun's light. A line enters a box through exactly one
// face, so nothing is counted twice, and the box, its grid and the default
// patch size stay those of the scene. docs/DESIGN.md, "Light from outside".
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <string>
#include <vector>

#include "vismask/solve/partition.h"
#include "vismask/solve/patch.h"
#include "vismask/solve/sampling.h"

namespace vismask {

struct OutsideLight {
  glm::vec3 sky{0.0f};           // --sky R,G,B: radiance (W/m^2/sr in scene units)
  glm::vec3 sunToward{0, 0, 1};  // --sun X,Y,Z: unit direction towards the sun
  glm::vec3 sun{0.0f};           // --sun ...,R,G,B: irradiance on a surface facing it
  float sunDegrees = 0.53f;      // --sun ...,DEG: its angular diameter
  bool HasSky() const { return sky.x > 0.0f || sky.y > 0.0f || sky.z > 0.0f; }
  bool HasSun() const { return sun.x > 0.0f || sun.y > 0.0f || sun.z > 0.0f; }
  bool Any() const { return HasSky() || HasSun(); }
};

// Parses --sky's "R,G,B" (each >= 0 and finite) into light->sky.
bool ParseSky(const std::string& text, OutsideLight* light);
// Parses --sun's "X,Y,Z,R,G,B[,DEG]" (a nonzero direction, normalised;
// R, G, B >= 0; 0 <= DEG <= 90) into light->sunToward, sun, sunDegrees.
bool ParseSun(const std::string& text, OutsideLight* light);

// Outside shooters' global ids: kOutsideIdBase + (environment << 10) +
// (slot << 6) + tile, slot 0-5 the sky on face 2 * axis + side, 8-13 the
// sun on that face, tile < kMaxOutsideTiles^2. Above every patch id (a
// scene has fewer than kOutsideIdBase patches; environments < 2^18).
constexpr uint32_t kOutsideIdBase = 0xf0000000u;
constexpr uint32_t kMaxOutsideTiles = 8;

enum class OutsideKind { kNone, kSky, kSun };
inline OutsideKind OutsideKindOf(uint32_t globalId) {
  if (globalId < kOutsideIdBase) return OutsideKind::kNone;
  return ((globalId >> 9) & 1u) ? OutsideKind::kSun : OutsideKind::kSky;
}

struct OutsideShooter {
  Patch patch;      // on the face, its normal pointing into the scene
  double power[3];  // what it shoots in all (W per channel)
};

// The outside shooters of environment `env` of `grid` (grid.box is the
// scene's box), into *out: for each face of the scene's box that the
// environment's box lies on, `tiles` x `tiles` for the sky, and as many for
// the sun when its light enters by that face (power > 0). A face of zero
// area has none. Tiles (1 to kMaxOutsideTiles) serve the hemisphere masks,
// which judge a shooter's rays from its centre (docs/DESIGN.md).
void OutsideShooters(const EnvGrid& grid, int env, const OutsideLight& light, uint32_t tiles,
                     std::vector<OutsideShooter>* out);
// Their power over every environment, channels summed (as emitted power).
double OutsidePower(const EnvGrid& grid, const OutsideLight& light, uint32_t tiles);

// The direction of travel of a sun ray from two uniforms: uniform in solid
// angle within the sun's cone, about -sunToward.
glm::vec3 SunRayDirection(const OutsideLight& light, float u1, float u2);

}  // namespace vismask
