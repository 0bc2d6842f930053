// Every environment's emitters in every environment's gather (foreign_light.h).
#include "vismask/display/foreign_light.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "vismask/core/check.h"
#include "vismask/solve/mask.h"

namespace vismask {

namespace {

std::vector<Patch> PatchesOf(const std::vector<EmitterRecord>& all) {
  std::vector<Patch> p;
  p.reserve(all.size());
  for (const EmitterRecord& r : all) p.push_back(r.patch);
  return p;
}

// Whether the segment a -> b meets box `b` (closed), by slabs; *entry:
// where, going from a, it first meets the box, as the share of the segment
// from there to b.
bool SegmentMeetsBox(const glm::vec3& a, const glm::vec3& b, const Bounds& box,
                     float* entry = nullptr) {
  float t0 = 0.0f, t1 = 1.0f;
  for (int k = 0; k < 3; ++k) {
    const float d = b[k] - a[k];
    if (d == 0.0f) {
      if (a[k] < box.lo[k] || a[k] > box.hi[k]) return false;
      continue;
    }
    float ta = (box.lo[k] - a[k]) / d, tb = (box.hi[k] - a[k]) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::fmax(t0, ta);
    t1 = std::fmin(t1, tb);
    if (t0 > t1) return false;
  }
  if (entry) *entry = 1.0f - t0;
  return true;
}

}  // namespace

ForeignLight::Counts ForeignLight::Count(const std::vector<EmitterRecord>& all, uint32_t envs,
                                         uint32_t ranks, uint32_t perRank, uint32_t res, bool sun) {
  Counts c;
  c.emitters = static_cast<uint32_t>(all.size());
  c.envs = envs;
  c.ranks = ranks;
  c.perRank = perRank;
  c.res = res;
  const double most = std::floor(std::sqrt(kSunMapBytes / (sizeof(float) * std::max(envs, 1u))));
  c.sunRes = sun ? static_cast<uint32_t>(std::min<double>(kSunTexelsPerRes * res, most)) : 0;
  const std::vector<Patch> patches = PatchesOf(all);
  c.light = DirectLight::Count(Span<const Patch>(patches.data(), patches.size()));
  return c;
}

void ForeignLight::Layout(Arena& arena, const Counts& c) {
  res_ = c.res;
  pixels_ = MaskShape{c.res, 0}.pixels();
  records_ = arena.Alloc<EmitterRecord>(c.emitters);
  patches_ = arena.Alloc<Patch>(c.emitters);
  frames_ = arena.Alloc<Frame>(c.emitters);
  centres_ = arena.Alloc<glm::vec3>(c.emitters);
  boxes_ = arena.Alloc<Bounds>(c.envs);
  perRank_ = c.perRank;
  mine_ = arena.Alloc<float>(size_t(c.perRank) * c.emitters * pixels_);
  all_ = arena.Alloc<float>(size_t(c.ranks) * c.perRank * c.emitters * pixels_);
  slot_ = arena.Alloc<uint32_t>(c.envs);
  sunRes_ = c.sunRes;
  const size_t texels = size_t(c.sunRes) * c.sunRes;
  sunMine_ = arena.Alloc<float>(size_t(c.perRank) * texels);
  sunAll_ = arena.Alloc<float>(size_t(c.ranks) * c.perRank * texels);
  sunMaps_ = arena.Alloc<SunMap>(c.sunRes > 0 ? c.envs : 0);
  light_.Layout(arena, c.light);
}

void ForeignLight::BuildRecords(const std::vector<EmitterRecord>& all, const EnvGrid& envGrid,
                                const OutsideLight& outside) {
  CHECK(all.size() == records_.size());
  for (size_t e = 0; e < all.size(); ++e) {
    records_[e] = all[e];
    patches_[e] = all[e].patch;
    frames_[e] = MakePatchSampler(all[e].patch).frame;
    centres_[e] = CentreOf(all[e].patch);
  }
  for (size_t k = 0; k < boxes_.size(); ++k) boxes_[k] = envGrid.EnvBox(static_cast<int>(k));
  for (float& d : mine_) d = 0.0f;
  for (float& d : all_) d = 0.0f;
  for (float& d : sunMine_) d = 0.0f;
  for (float& d : sunAll_) d = 0.0f;
  light_.Build(patches_);
  if (sunRes_ > 0) {
    light_.SetSun(outside);
    BuildSunFrame(outside.sunToward);
  }
  light_.SetTransit(this);
}

// The sun's maps' frame: e1, e2 across the direction towards it, a plane
// above the scene's highest corner along the sun's rays, and for each
// environment square texels that cover its box projected on the plane.
void ForeignLight::BuildSunFrame(const glm::vec3& toward) {
  sunToward_ = glm::normalize(toward);
  const glm::vec3 a = std::fabs(sunToward_.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  sunE1_ = glm::normalize(glm::cross(sunToward_, a));
  sunE2_ = glm::cross(sunToward_, sunE1_);
  float top = -std::numeric_limits<float>::infinity(), most = 0.0f;
  for (size_t e = 0; e < boxes_.size(); ++e) {
    const Bounds& box = boxes_[e];
    float u0 = std::numeric_limits<float>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
    for (int k = 0; k < 8; ++k) {
      const glm::vec3 p((k & 1) ? box.hi.x : box.lo.x, (k & 2) ? box.hi.y : box.lo.y,
                        (k & 4) ? box.hi.z : box.lo.z);
      const float u = glm::dot(p, sunE1_), v = glm::dot(p, sunE2_);
      u0 = std::fmin(u0, u), u1 = std::fmax(u1, u), v0 = std::fmin(v0, v), v1 = std::fmax(v1, v);
      top = std::fmax(top, glm::dot(p, sunToward_));
    }
    const float side = std::fmax(u1 - u0, v1 - v0);
    most = std::fmax(most, side);
    // The far edge inside the last texel.
    sunMaps_[e] = SunMap{u0, v0, side / static_cast<float>(sunRes_) * 1.0001f};
  }
  sunTop_ = top + 0.01f * most;
}

void ForeignLight::CastSun(uint32_t env, const Grid& grid, Span<float> out) const {
  const SunMap& m = sunMaps_[env];
  for (uint32_t j = 0; j < sunRes_; ++j)
    for (uint32_t i = 0; i < sunRes_; ++i) {
      const float u = m.u0 + (static_cast<float>(i) + 0.5f) * m.texel;
      const float v = m.v0 + (static_cast<float>(j) + 0.5f) * m.texel;
      const Ray ray{u * sunE1_ + v * sunE2_ + sunTop_ * sunToward_, -sunToward_, 0.0f,
                    std::numeric_limits<float>::infinity()};
      Hit hit;
      out[size_t(j) * sunRes_ + i] = grid.Intersect(ray, Skip(kNoPatch), &hit)
                                         ? hit.t
                                         : std::numeric_limits<float>::infinity();
    }
}

bool ForeignLight::SunTexel(uint32_t env, const glm::vec3& p, size_t* texel) const {
  const SunMap& m = sunMaps_[env];
  const float fu = (glm::dot(p, sunE1_) - m.u0) / m.texel;
  const float fv = (glm::dot(p, sunE2_) - m.v0) / m.texel;
  if (!(fu >= 0.0f && fv >= 0.0f && fu < static_cast<float>(sunRes_) &&
        fv < static_cast<float>(sunRes_)))
    return false;
  *texel = size_t(static_cast<uint32_t>(fv)) * sunRes_ + static_cast<uint32_t>(fu);
  return true;
}

bool ForeignLight::PassesSun(const glm::vec3& x, const glm::vec3& n, const glm::vec3& d) const {
  const float along = glm::dot(d, sunToward_);
  if (sunRes_ == 0 || !(along > 0.0f)) return true;
  const float depth = sunTop_ - glm::dot(x, sunToward_);  // x's distance below the plane
  const float cosX = std::fmax(std::fabs(glm::dot(n, sunToward_)), 0.05f);
  const float sinX = std::sqrt(std::fmax(0.0f, 1.0f - cosX * cosX));
  // The sample's sideways drift from x's line per unit of height.
  const float drift = glm::length(d - along * sunToward_) / along;
  const size_t texels = size_t(sunRes_) * sunRes_;
  // Every environment the sample's ray crosses up to the maps' plane, its
  // own too (the own grid's ray may leave the box below an occluder that
  // the maps' texel lines meet there); the segment stops just short of x.
  const glm::vec3 top = x + (depth / along) * d, near = x + 1e-4f * (top - x);
  for (uint32_t k = 0; k < boxes_.size(); ++k) {
    float entry;  // the height where the sample's ray enters the box, over depth
    if (!SegmentMeetsBox(top, near, boxes_[k], &entry)) continue;
    const float* map = sunAll_.data() + size_t(slot_[k]) * texels;
    // The bias: a surface through x meets the texel's rays up to its width
    // over the cosine away from x.
    const float reach = depth - 2.0f * sunMaps_[k].texel / cosX;
    // The sample's ray (d, within the sun's disc) where it is as high as
    // the occluder on x's own line, or as where it enters the box from
    // above: the map's texel there, so that the disc gives the shadow a
    // penumbra.
    size_t at;
    const float t = SunTexel(k, x, &at) ? map[at] : std::numeric_limits<float>::infinity();
    const float h = t < reach ? depth - t : entry * depth;
    // There the surface through x lies up to drift h sin / cos nearer the
    // plane than x: no shadow of its own.
    size_t texel;
    if (SunTexel(k, x + (h / along) * d, &texel) && map[texel] < reach - drift * h * sinX / cosX)
      return false;
  }
  return true;
}

void ForeignLight::CastOne(uint32_t e, const Grid& grid, float epsilon, Skip skip,
                           Span<float> out) const {
  const Frame& f = frames_[e];
  const glm::vec3 o = centres_[e];
  for (uint32_t p = 0; p < pixels_; ++p) {
    const glm::vec3 d = f.ToWorld(MaskPixelCentre(p, res_));
    const Ray ray{o, d, epsilon, std::numeric_limits<float>::infinity()};
    Hit hit;
    out[p] = grid.Intersect(ray, skip, &hit) ? hit.t : std::numeric_limits<float>::infinity();
  }
}

bool ForeignLight::Passes(uint32_t e, uint32_t viewer, const glm::vec3& x,
                          const glm::vec3& n) const {
  const EmitterRecord& r = records_[e];
  if (r.env == viewer || res_ == 0) return true;
  const Frame& f = frames_[e];
  const glm::vec3 c = centres_[e];
  const glm::vec3 w = x - c;
  const glm::vec3 d(glm::dot(w, f.t), glm::dot(w, f.b), glm::dot(w, f.n));
  const float len = glm::length(d);
  if (!(len > 0.0f) || !(d.z > 0.0f)) return false;
  const uint32_t pixel = MaskPixel(d / len, res_);
  // The bias: the pixel's width at x (2 of its angular steps, pi / 2R),
  // over the cosine at the receiver, at most the distance itself.
  const float cosX = std::fabs(glm::dot(n, w)) / len;
  const float width = 2.0f * 1.5707964f / static_cast<float>(res_) * len;
  const float reach = len - std::fmin(len, width / std::fmax(cosX, 0.05f));
  const size_t m = records_.size();
  for (uint32_t k = 0; k < boxes_.size(); ++k) {
    if (k == viewer) continue;
    // The segment stops just short of x: an environment whose box x only
    // touches (x on its plane) lies beyond x along the ray.
    if (k != r.env && !SegmentMeetsBox(c, c + 0.9999f * w, boxes_[k])) continue;
    if (all_[(size_t(slot_[k]) * m + e) * pixels_ + pixel] < reach) return false;
  }
  return true;
}

}  // namespace vismask
