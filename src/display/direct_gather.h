// The per-pixel direct light of a piece (raster.h's DirectHook, direct.h),
// shared by the two rasters (internal to raster_aa.cpp and
// raster_point.cpp).
#pragma once
#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "vismask/accel/grid.h"
#include "vismask/display/direct.h"
#include "vismask/display/raster.h"

namespace vismask {

// Whether point x of the receiver (patch, twin) is hidden from `eye`: a
// patch lies between them (the ray stops `epsilon` short of both ends).
inline bool HiddenFrom(const Grid& grid, glm::vec3 x, glm::vec3 eye, uint32_t patch, uint32_t twin,
                       float epsilon) {
  const glm::vec3 d = eye - x;
  const float r = glm::length(d);
  if (!(r > 2.0f * epsilon)) return false;
  const float t = epsilon / r;
  return grid.Occluded(Ray{x, d, t, 1.0f - t}, Skip(patch, twin));
}

// The radiance hook `h` adds for pixel index `pixel` at the shaded point
// `centre`; pointOf(k) gives the point sample k's shadow ray leaves from
// (points are projected onto the receiver's plane), called once a sample,
// for k = 0, 1, 2, ... in order. Each source's E0 at
// the centre times the visible share of its samples, weighted by what each
// would bring (direct.h): a ray from the centre to each outline corner and
// the first kFirstDirectSamples, and the rest of h.samples only where
// those disagree (some reach the emitters, some do not). The samples go to
// the emitting polygons in proportion to their parts of E0 and, with a
// sun, to its disc in proportion to its part. With `eye` (samples spread
// over the pixel), a sample whose shadow ray is blocked and whose point is
// hidden from the eye is left out: the piece's part behind a nearer face
// in the pixel (a floor running on under a block, at the block's foot)
// does not darken the part that shows; none left, the piece is dark. The
// groups' tallies are the light's scratch (one gather at a time).
// Allocates nothing.
template <class PointOf>
glm::vec3 GatherDirect(const DirectHook& h, glm::vec3 centre, uint32_t pixel, PointOf pointOf,
                       const glm::vec3* eye = nullptr) {
  auto onPlane = [&](glm::vec3 x) { return x - h.normal * glm::dot(h.normal, x - h.planePoint); };
  const glm::vec3 x0 = onPlane(centre);
  const Span<DirectLight::Tally> tally = h.light->tallies();
  const glm::vec3 e0 = h.light->Unoccluded(x0, h.normal, tally);
  if (!(e0.x > 0.0f || e0.y > 0.0f || e0.z > 0.0f)) return glm::vec3(0.0f);
  // The sun's share of the samples: its share of E0 (channels summed).
  const glm::vec3 sunE0 = h.light->UnoccludedSun(h.normal);  // 0 without a sun
  float sunShare = 0.0f;
  if (h.light->hasSun())
    sunShare = std::fmin(1.0f, (sunE0.x + sunE0.y + sunE0.z) / (e0.x + e0.y + e0.z));
  // The outline corners, from the centre, and with the sun the points of
  // its rim (with no area emitter, those alone).
  const uint32_t outline = h.light->numCorners();
  const uint32_t corners = outline + (sunShare > 0.0f ? kSunRimRays : 0u);
  bool cornersTell = outline <= kMaxCornerRays && corners > 0;
  uint32_t cornersSeen = 0;
  for (uint32_t k = 0; k < outline && cornersTell; ++k) {
    bool usable;
    cornersSeen += h.light->CornerVisible(*h.grid, h.patch, h.twin, x0, h.normal, k, h.epsilon,
                                          h.hint, &usable, h.viewer)
                       ? 1u
                       : 0u;
    cornersTell = usable;
  }
  for (uint32_t k = outline; k < corners && cornersTell; ++k) {
    bool usable;
    cornersSeen += h.light->SunRimVisible(*h.grid, h.patch, h.twin, x0, h.normal, k - outline,
                                          h.epsilon, h.hint, &usable, h.viewer)
                       ? 1u
                       : 0u;
    cornersTell = usable;
  }
  glm::vec3 all(0.0f), seen(0.0f), sunAll(0.0f), sunSeen(0.0f);
  const DirectPixelSequence lightSample(pixel, DirectPixelSequence::Kind::kLight);
  uint32_t counted = 0, visible = 0, hidden = 0, k = 0;  // k: the samples drawn
  for (; k < h.samples; ++k) {
    if (k == kFirstDirectSamples && cornersTell && counted > 0 &&
        ((visible == 0 && cornersSeen == 0) || (visible == counted && cornersSeen == corners)))
      break;
    glm::vec3 w;
    uint32_t source;
    const glm::vec3 x = onPlane(pointOf(k));
    bool vis = h.light->Sample(*h.grid, h.patch, h.twin, x, h.normal, lightSample(k), tally,
                               h.epsilon, h.hint, &w, sunShare, &source, h.viewer);
    if (!vis && eye && HiddenFrom(*h.grid, x, *eye, h.patch, h.twin, h.epsilon)) {
      ++hidden;
      continue;
    }
    if (!(w.x > 0.0f || w.y > 0.0f || w.z > 0.0f)) continue;
    ++counted;
    all += w;
    glm::vec3& sourceAll = source < tally.size() ? tally[source].all : sunAll;
    glm::vec3& sourceSeen = source < tally.size() ? tally[source].seen : sunSeen;
    sourceAll += w;
    if (vis) {
      ++visible;
      seen += w;
      sourceSeen += w;
    }
  }
  if (counted == 0 && hidden > 0) return glm::vec3(0.0f);
  glm::vec3 share(1.0f);  // no sample saw the emitters in front: unoccluded
  for (int c = 0; c < 3; ++c)
    if (all[c] > 0.0f) share[c] = seen[c] / all[c];
  uint32_t lit = sunShare > 0.0f ? 1u : 0u;
  for (const DirectLight::Tally& t : tally) lit += t.e0.x + t.e0.y + t.e0.z > 0.0f ? 1u : 0u;
  // One source lit, or every sample reached its point or none did (fully
  // lit, umbra): the whole's share, exactly 1 or 0 in the latter.
  if (lit <= 1 || visible == 0 || visible == counted) return h.scale * e0 * share;
  // Several sources lit: each one that drew at least a sample's worth
  // (drawn x its share >= 1) gives its part times its own samples' visible
  // share, so its count of samples does not matter; the others, which may
  // draw none, what their samples brought over all drawn.
  const float n = static_cast<float>(k - hidden);
  auto part = [&](const glm::vec3& e, float p, const glm::vec3& sSeen, const glm::vec3& sAll) {
    glm::vec3 v = sSeen / n;
    if (n * p >= 1.0f)
      for (int c = 0; c < 3; ++c)
        if (sAll[c] > 0.0f) v[c] = e[c] * (sSeen[c] / sAll[c]);
    return v;
  };
  glm::vec3 sum = sunShare > 0.0f ? part(sunE0, sunShare, sunSeen, sunAll) : glm::vec3(0.0f);
  float below = 0.0f;
  for (const DirectLight::Tally& t : tally) {
    if (t.e0.x + t.e0.y + t.e0.z > 0.0f)
      sum += part(t.e0, (t.cdf - below) * (1.0f - sunShare), t.seen, t.all);
    below = t.cdf;
  }
  return h.scale * sum;
}

}  // namespace vismask
