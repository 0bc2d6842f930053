// The inside views' lit score from outside the scene (--sky, --sun): far
// shadow maps along the sun's direction and the sky's fixed directions
// (camera.h, kViewSkyDirections; docs/design/camera.md).
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "vismask/display/camera.h"

namespace vismask {

namespace {

// A shadow map's eye stands this many box diagonals from the box's centre.
constexpr double kFarDiagonals = 8.0;

// The camera of a far shadow map along `toward` (unit, from the box
// towards the light): the box's bounding sphere fills its view with a 4%
// margin, up whichever of +y and +x is less along the direction.
Camera FarCamera(const glm::vec3& centre, float reach, const glm::dvec3& toward) {
  constexpr double kDegrees = 180.0 / 3.141592653589793;
  const double distance = kFarDiagonals * reach;
  Camera c;
  c.eye = centre + static_cast<float>(distance) * glm::vec3(toward);
  c.target = centre;
  c.up = std::fabs(toward.y) < 0.9 ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  c.fovyDeg =
      static_cast<float>(2.0 * kDegrees * std::atan(0.52 * reach / (distance - 0.5 * reach)));
  return c;
}

}  // namespace

void ViewProbe::SetOutside(const OutsideLight& light) {
  sun_ = 0.0;
  hasSky_ = false;
  if (!(reach_ > 0.0f)) return;
  if (light.HasSun()) {
    sun_ = (double(light.sun.x) + light.sun.y + light.sun.z) / 3.0;
    sunToward_ = glm::normalize(glm::dvec3(light.sunToward));
    Start(sunProbe_, FarCamera(centre_, reach_, sunToward_), kSunProbeRays);
  }
  if (!light.HasSky()) return;
  // The 26 directions from a cube's centre to its faces', edges' and
  // corners' centres, in a fixed order; their weight makes a plane facing
  // an axis (facing one face's, four edges' and four corners' directions)
  // get exactly pi L from a sky open all round.
  int k = 0;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z)
        if (x != 0 || y != 0 || z != 0) skyDir_[k++] = glm::normalize(glm::dvec3(x, y, z));
  double cosines = 0.0;
  for (const glm::dvec3& w : skyDir_) cosines += std::max(0.0, w.y);
  const double weight = 3.141592653589793 / cosines;
  const SkyMap* map = light.skyMap.get();
  for (k = 0; k < kViewSkyDirections; ++k) {
    const glm::vec3 l = map ? map->Radiance(glm::vec3(skyDir_[k])) : light.sky;
    sky_[k] = (double(l.x) + l.y + l.z) / 3.0 * weight;
    if (sky_[k] > 0.0) hasSky_ = true;
  }
  if (!hasSky_) return;
  for (k = 0; k < kViewSkyDirections; ++k)
    Start(skyProbes_[k], FarCamera(centre_, reach_, skyDir_[k]), kOutsideProbeRays);
}

double ViewProbe::FarSeen(const Probe& q, const glm::dvec3& x, uint32_t polygon) const {
  if (!q.ok) return 0.0;
  glm::dvec3 d;
  double sx, sy;
  if (!q.Project(x, &d, &sx, &sy)) return 0.0;
  const glm::dvec3 eye(q.view.eye);
  if (!(sx >= 0.0 && sx < q.n && sy >= 0.0 && sy < q.n)) return 1.0;  // beyond the box
  // The four pixels whose centres surround x, weighted bilinearly; each
  // shadows x when the plane of what it sees, followed to x's own ray,
  // crosses it nearer the eye than x by more than 0.1% of the diagonal.
  // So a wall thinner than a pixel between x and the light shadows x even
  // where a pixel's centre passes it lower down (farther off than x), a
  // polygon in x's plane never does, and an edge's shadow is shared over
  // a pixel rather than moved by one.
  const double dist = glm::length(d), slack = 1e-3 * reach_;
  const double fx = sx - 0.5, fy = sy - 0.5;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  const double wx = fx - x0, wy = fy - y0;
  // A pixel that sees nothing (x on the scene's outline) tells nothing:
  // the others decide, and x is seen when none sees anything. (A weight
  // of 0 is a pixel x is not in at all.)
  double seen = 0.0, weight = 0.0;
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const int px = std::min(q.n - 1, std::max(0, x0 + dx));
      const int py = std::min(q.n - 1, std::max(0, y0 + dy));
      const double w = (dx ? wx : 1.0 - wx) * (dy ? wy : 1.0 - wy);
      const int k = py * q.n + px;
      if (q.depth[k] == std::numeric_limits<double>::infinity()) continue;
      weight += w;
      if (q.index[k] == polygon) {
        seen += w;
        continue;
      }
      const glm::dvec3 m(q.normal[k]), hit = eye + q.depth[k] * q.dir[k];
      const double facing = glm::dot(m, d);
      const double t = std::fabs(facing) > 1e-9 * dist ? glm::dot(m, hit - eye) / facing
                                                       : q.depth[k] * glm::length(q.dir[k]) / dist;
      if (!(t > 0.0 && t * dist < dist - slack)) seen += w;
    }
  return weight > 0.0 ? seen / weight : 1.0;
}

double ViewProbe::OutsideAt(const glm::dvec3& x, const glm::dvec3& n, uint32_t polygon) const {
  double sum = 0.0;
  if (sun_ > 0.0) {
    const double cosine = glm::dot(n, sunToward_);
    if (cosine > 0.0) sum += sun_ * cosine * FarSeen(sunProbe_, x, polygon);
  }
  if (!hasSky_) return sum;
  for (int k = 0; k < kViewSkyDirections; ++k) {
    const double cosine = glm::dot(n, skyDir_[k]);
    if (sky_[k] > 0.0 && cosine > 0.0) sum += sky_[k] * cosine * FarSeen(skyProbes_[k], x, polygon);
  }
  return sum;
}

uint64_t ViewProbe::HeapBytes(const OutsideLight& light) {
  constexpr uint64_t per =
      sizeof(glm::dvec3) + 2 * sizeof(double) + sizeof(uint32_t) + 2 + sizeof(glm::vec3);
  constexpr uint64_t n2 = uint64_t{kViewProbeRays} * kViewProbeRays;
  constexpr uint64_t m2 = uint64_t{kInsideProbeRays} * kInsideProbeRays;
  constexpr uint64_t l2 = uint64_t{kLightProbeRays} * kLightProbeRays;
  constexpr uint64_t o2 = uint64_t{kOutsideProbeRays} * kOutsideProbeRays;
  constexpr uint64_t s2 = uint64_t{kSunProbeRays} * kSunProbeRays;
  const uint64_t far = (light.HasSun() ? s2 : 0) + (light.HasSky() ? kViewSkyDirections * o2 : 0);
  return (kNumViewSides * n2 + kInsideCandidates * m2 + kViewLights * l2 + far) * per;
}

}  // namespace vismask
