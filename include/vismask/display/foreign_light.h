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
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "vismask/accel/grid.h"
#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/display/direct.h"
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
  struct Counts {
    uint32_t emitters = 0, envs = 0, ranks = 1, perRank = 0, res = 0;
    DirectLight::Counts light;
  };
  static Counts Count(const std::vector<EmitterRecord>& all, uint32_t envs, uint32_t ranks,
                      uint32_t perRank, uint32_t res);
  // Carves its lists, the light's, and the masks of all environments and of
  // this rank's (the exchange's block) from `arena` (also a measuring one).
  void Layout(Arena& arena, const Counts& counts);
  // The records and the light from `all` (init); `rankOf(env)` and
  // `firstOf(rank)`: where each environment's masks land in all().
  template <class RankOf, class FirstOf>
  void Build(const std::vector<EmitterRecord>& all, const EnvGrid& envGrid, RankOf rankOf,
             FirstOf firstOf) {
    BuildRecords(all, envGrid);
    for (uint32_t k = 0; k < slot_.size(); ++k) {
      const int rank = rankOf(k);
      slot_[k] = static_cast<uint32_t>(rank) * perRank_ + (k - firstOf(rank));
    }
  }
  // Environment `env`'s transit masks for every emitter patch into its
  // block `slot` of this rank's: rays from each patch's centre (offset
  // `epsilon` along its normal) through `grid`, the patch itself skipped
  // where `env` holds it (its local index and twin: `twinOf`).
  template <class TwinOf>
  void Cast(uint32_t env, uint32_t slot, const Grid& grid, float epsilon, TwinOf twinOf);
  // This rank's blocks (perRank of them) and every rank's (the exchange
  // fills `all` with every rank's `mine`, in rank order).
  Span<float> mine() const { return mine_; }
  Span<float> all() const { return all_; }

  bool empty() const { return records_.empty(); }
  const DirectLight& light() const { return light_; }
  // Whether the ray from emitter patch `e`'s centre to x (unit normal n,
  // in environment `viewer`) passes every other environment it crosses
  // (viewer's own part is the caller's shadow ray).
  bool Passes(uint32_t e, uint32_t viewer, const glm::vec3& x, const glm::vec3& n) const;

 private:
  Span<EmitterRecord> records_;
  Span<Patch> patches_;  // the records' patches, for the light
  Span<Frame> frames_;
  Span<glm::vec3> centres_;
  Span<Bounds> boxes_;  // every environment's
  Span<float> mine_, all_;
  Span<uint32_t> slot_;  // per environment: its block in all_
  uint32_t res_ = 0, pixels_ = 0, perRank_ = 0;

  void BuildRecords(const std::vector<EmitterRecord>& all, const EnvGrid& envGrid);
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
}

}  // namespace vismask
