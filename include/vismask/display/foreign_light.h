// Every environment's emitters gathered per pixel in every environment
// (docs/design/direct-light.md, "Several environments"). One environment's
// grid answers a shadow ray only inside its own box; a ray from a point of
// environment A to a point of an emitter that environment B holds also
// crosses B's box and perhaps others. The part in A is traced exactly, in
// A's grid; each other environment's part is read from its transit mask
// for that emitter patch: R x 4R directions (mask.h) from the patch's
// centre, each the distance to the first thing the ray from the centre
// that way meets inside that environment's box (infinity: nothing), a
// shadow map. A point x is lit through it when the ray's first hit lies
// beyond x, less a bias for the direction's pixel width (a receiver the
// ray grazes would shadow itself). Every environment casts its masks
// for every emitter patch of the scene at init, and every rank holds them
// all, so a pixel's light does not depend on which rank holds what.
//
// What it loses: beyond the pixel's own environment an occluder is seen
// from the emitter patch's centre, not from the sample point, and at the
// mask's resolution (R = 32: 2.8 degrees a pixel), so shadows cast across an
// environment plane are as sharp as the emitter's patches and the mask
// allow. Within the pixel's own environment nothing changes.
//
// The sun (--sun) the same way, with an orthographic map an environment:
// S x S texels (S = kSunTexelsPerRes x R, fewer where all of them would
// pass kSunMapBytes) on a plane across the sun's direction, covering the
// environment's box, each the distance along the sun's rays from that
// plane to the first thing the ray through the texel's centre meets inside
// that box. A sun sample from x leaves its own box through every map its
// ray crosses (x's own environment's too), read where the sample's ray is
// as high as the occluder on x's line, so the sun's disc still gives a
// penumbra; lit when that texel's first hit lies below x, less a bias for
// the texel's width. What it loses: a shadow cast across an environment
// plane may move by up to a texel, and the occluder's height for the
// penumbra is read on x's line.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "vismask/accel/grid.h"
#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/display/direct.h"
#include "vismask/solve/outside.h"
#include "vismask/solve/partition.h"
#include "vismask/solve/patch.h"
#include "vismask/solve/sampling.h"

namespace vismask {

// One emitter patch as every rank learns it: the environment's own patch
// (its local index there) and which environment holds it.
struct EmitterRecord {
  Patch patch;
  uint32_t env;
  uint32_t local;
};

// The emitter patches of the scene, in global id order (the order does not
// depend on ranks), the light they make (DirectLight over all of them) and
// every environment's transit masks.
class ForeignLight {
 public:
  // The counts a scene's emitters need (init: uses the heap): `all` sorted
  // by global id.
  // sunRes: the sun's maps' texels a side (0: no sun).
  struct Counts {
    uint32_t emitters = 0, envs = 0, ranks = 1, perRank = 0, res = 0, sunRes = 0;
    DirectLight::Counts light;
    bool empty() const { return emitters == 0 && sunRes == 0; }  // nothing to lay out
  };
  // The sun's maps: 16R texels a side (512 at R = 32), fewer where every
  // environment's would take more than kSunMapBytes in all.
  static constexpr uint32_t kSunTexelsPerRes = 16;
  static constexpr double kSunMapBytes = 16.0 * 1024 * 1024;
  static Counts Count(const std::vector<EmitterRecord>& all, uint32_t envs, uint32_t ranks,
                      uint32_t perRank, uint32_t res, bool sun);
  // Carves its lists, the light's, and the masks of all environments and of
  // this rank's (the exchange's block) from `arena` (also a measuring one).
  void Layout(Arena& arena, const Counts& counts);
  // The records and the light from `all` and `outside`'s sun (init);
  // `rankOf(env)` and `firstOf(rank)`: where each environment's masks land
  // in all().
  template <class RankOf, class FirstOf>
  void Build(const std::vector<EmitterRecord>& all, const EnvGrid& envGrid,
             const OutsideLight& outside, RankOf rankOf, FirstOf firstOf) {
    BuildRecords(all, envGrid, outside);
    for (uint32_t k = 0; k < slot_.size(); ++k) {
      const int rank = rankOf(k);
      slot_[k] = static_cast<uint32_t>(rank) * perRank_ + (k - firstOf(rank));
    }
  }
  // Environment `env`'s transit masks for every emitter patch into its
  // block `slot` of this rank's: rays from each patch's centre (offset
  // `epsilon` along its normal) through `grid`, the patch itself skipped
  // where `env` holds it (its local index and twin: `twinOf`).
  // With the sun, also its map of `env` into block `slot` of sunMine().
  template <class TwinOf>
  void Cast(uint32_t env, uint32_t slot, const Grid& grid, float epsilon, TwinOf twinOf);
  // This rank's blocks (perRank of them) and every rank's (the exchange
  // fills `all` with every rank's `mine`, in rank order).
  Span<float> mine() const { return mine_; }
  Span<float> all() const { return all_; }
  // The sun's maps, the same way.
  Span<float> sunMine() const { return sunMine_; }
  Span<float> sunAll() const { return sunAll_; }

  bool empty() const { return records_.empty() && sunRes_ == 0; }
  const DirectLight& light() const { return light_; }
  // Whether the ray from emitter patch `e`'s centre to x (unit normal n,
  // in environment `viewer`) passes every other environment it crosses
  // (viewer's own part is the caller's shadow ray).
  bool Passes(uint32_t e, uint32_t viewer, const glm::vec3& x, const glm::vec3& n) const;
  // Whether the sun's ray from x (normal n) towards d (a direction within
  // its disc) passes the environments x's line to the sun crosses.
  bool PassesSun(const glm::vec3& x, const glm::vec3& n, const glm::vec3& d) const;

 private:
  Span<EmitterRecord> records_;
  Span<Patch> patches_;  // the records' patches, for the light
  Span<Frame> frames_;
  Span<glm::vec3> centres_;
  Span<Bounds> boxes_;  // every environment's
  Span<float> mine_, all_;
  Span<uint32_t> slot_;  // per environment: its block in all_
  uint32_t res_ = 0, pixels_ = 0, perRank_ = 0;
  // The sun's maps: a frame across its direction (e1, e2; toward the sun),
  // the plane's height along it, and each environment's map's corner on
  // that plane and texel.
  struct SunMap {
    float u0 = 0.0f, v0 = 0.0f, texel = 0.0f;
  };
  Span<float> sunMine_, sunAll_;
  Span<SunMap> sunMaps_;
  uint32_t sunRes_ = 0;
  glm::vec3 sunE1_{0.0f}, sunE2_{0.0f}, sunToward_{0.0f};
  float sunTop_ = 0.0f;

  void BuildRecords(const std::vector<EmitterRecord>& all, const EnvGrid& envGrid,
                    const OutsideLight& outside);
  void BuildSunFrame(const glm::vec3& toward);
  bool SunTexel(uint32_t env, const glm::vec3& p, size_t* texel) const;
  void CastSun(uint32_t env, const Grid& grid, Span<float> out) const;
  DirectLight light_;

  void CastOne(uint32_t e, const Grid& grid, float epsilon, Skip skip, Span<float> out) const;
};

template <class TwinOf>
void ForeignLight::Cast(uint32_t env, uint32_t slot, const Grid& grid, float epsilon,
                        TwinOf twinOf) {
  for (uint32_t e = 0; e < records_.size(); ++e) {
    const EmitterRecord& r = records_[e];
    const Skip skip = r.env == env ? Skip(r.local, twinOf(r.local)) : Skip(kNoPatch);
    CastOne(e, grid, epsilon, skip,
            mine_.subspan((size_t(slot) * records_.size() + e) * pixels_, pixels_));
  }
  const size_t texels = size_t(sunRes_) * sunRes_;
  if (texels > 0) CastSun(env, grid, sunMine_.subspan(size_t(slot) * texels, texels));
}

}  // namespace vismask
