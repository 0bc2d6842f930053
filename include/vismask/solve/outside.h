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
#include <memory>
#include <string>
#include <vector>

#include "vismask/core/span.h"
#include "vismask/solve/partition.h"
#include "vismask/solve/patch.h"
#include "vismask/solve/sampling.h"

namespace vismask {

// --sky FILE.hdr: an equirectangular map of the sky's radiance, in the
// orientation of Blender/Cycles' default equirectangular world mapping on
// a scene that Blender's OBJ and glTF importers bring in (the file's +Y is
// Blender's +Z, its -Z Blender's +Y): the map's centre column is the sky
// seen along +X, its top row the sky straight up (+Y), its column at three
// quarters of the width the sky along +Z, its left and right edges -X. The
// radiance of sky direction w (unit, pointing away from the scene) is the
// texel holding azimuth atan2(w.z, w.x) and elevation asin(w.y), constant
// over each texel (nearest, no filtering; tools/reference asks Cycles for
// "Closest" interpolation).
struct SkyMap {
  std::string path;
  uint32_t width = 0, height = 0;
  // Linear RGB radiance, rows top to bottom: the rank's arena once init
  // has laid it out (staged on the heap until then, `staged`).
  Span<const float> texels;
  std::vector<float> staged;
  // For each face of the scene's box (2 * axis + side, side 1 the high
  // one), what crosses a unit area of it inwards: the integral over sky
  // directions w of L(w) max(0, dot(w, face's outward normal)), per
  // channel; exact for the texel-constant map (per texel in closed form).
  double crossing[6][3] = {};

  // The radiance of sky direction w (any length > 0).
  glm::vec3 Radiance(const glm::vec3& w) const;
  // Builds `crossing` from `staged` (width x height RGB).
  void Integrate();
};

struct OutsideLight {
  glm::vec3 sky{0.0f};  // --sky R,G,B: radiance (W/m^2/sr in scene units)
  // --sky FILE.hdr: the file (set by ParseSky), and the map read at init
  // (ReadSkyMap, scene/texture.h) that every copy of these options shares.
  std::string skyFile;
  std::shared_ptr<SkyMap> skyMap;
  glm::vec3 sunToward{0, 0, 1};  // --sun X,Y,Z: unit direction towards the sun
  glm::vec3 sun{0.0f};           // --sun ...,R,G,B: irradiance on a surface facing it
  float sunDegrees = 0.53f;      // --sun ...,DEG: its angular diameter
  bool HasSky() const { return !skyFile.empty() || sky.x > 0.0f || sky.y > 0.0f || sky.z > 0.0f; }
  bool HasSun() const { return sun.x > 0.0f || sun.y > 0.0f || sun.z > 0.0f; }
  bool Any() const { return HasSky() || HasSun(); }
};

// Parses --sky's "R,G,B" (each >= 0 and finite) into light->sky, or a
// file's path (one that ends in .hdr or .pic, in any case, or holds a '/')
// into light->skyFile.
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

// A sky shot's rays under a map (--sky FILE.hdr). The rays keep the
// uniform sky's cosine-distributed directions, so that the hemisphere
// masks and Method R's routes (which judge a shooter's rays by those
// directions) hold as they are; each ray instead carries its own colour,
// in proportion to the map's radiance where it comes from. The shares are
// normalised over the shot's rays (power / rays times the ray's radiance
// over the rays' mean, per channel), so that a shot delivers its power and
// the energy ledger stays closed (to rounding); every environment that traces a ray of
// the shot computes the same sum, over every ray of the shot in order.
// Importance sampling the map would put the rays where the map is bright,
// but would make a ray's direction depend on the map and break the masks'
// cosine pixels; per-ray colour costs variance under a small bright sun in
// the map, which --sun is for.
struct SkyShares {
  const SkyMap* map = nullptr;  // null: every ray carries power / rays
  uint32_t rays = 0;
  double even[3] = {0, 0, 0};  // power / rays
  double sum[3] = {0, 0, 0};   // the rays' radiance summed
  // The share of a ray travelling along d: power / rays times `ratio`, the
  // ray's radiance over the rays' mean (exactly 1 under a uniform map; 1
  // in a channel no ray has radiance in).
  void Of(const glm::vec3& d, double share[3], double ratio[3]) const {
    const glm::vec3 l = map->Radiance(-d);
    for (int c = 0; c < 3; ++c) {
      ratio[c] = sum[c] > 0.0 ? static_cast<double>(l[c]) * rays / sum[c] : 1.0;
      share[c] = even[c] * ratio[c];
    }
  }
};

// The direction of travel of a sun ray from two uniforms: uniform in solid
// angle within the sun's cone, about -sunToward.
glm::vec3 SunRayDirection(const OutsideLight& light, float u1, float u2);
// The same for a sun towards `toward` (unit) of angular diameter `degrees`.
glm::vec3 SunConeDirection(const glm::vec3& toward, float degrees, float u1, float u2);

}  // namespace vismask
