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

// Whether the segment a -> b meets box `b` (closed), by slabs.
bool SegmentMeetsBox(const glm::vec3& a, const glm::vec3& b, const Bounds& box) {
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
  return true;
}

}  // namespace

ForeignLight::Counts ForeignLight::Count(const std::vector<EmitterRecord>& all, uint32_t envs,
                                         uint32_t ranks, uint32_t perRank, uint32_t res) {
  Counts c;
  c.emitters = static_cast<uint32_t>(all.size());
  c.envs = envs;
  c.ranks = ranks;
  c.perRank = perRank;
  c.res = res;
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
  light_.Layout(arena, c.light);
}

void ForeignLight::BuildRecords(const std::vector<EmitterRecord>& all, const EnvGrid& envGrid) {
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
  light_.Build(patches_);
  light_.SetTransit(this);
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
