// DirectBook: its layout, build and a local shot's emission share.
#include "vismask/solve/direct_book.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace vismask {

void DirectBook::Layout(Arena& arena, uint32_t numPatches, bool on, bool smooth,
                        const DirectLight::Counts& counts) {
  on_ = on;
  emitLeft_ = arena.Alloc<double>(on ? 3 * size_t(numPatches) : 0);
  emitTotal_ = arena.Alloc<double>(on ? 3 : 0);
  smoothPatch_ = arena.Alloc<uint8_t>(on && smooth ? numPatches : 0);
  light_.Layout(arena, on ? counts : DirectLight::Counts{});
}

void DirectBook::Build(Span<const Patch> patches, const DisplayLattice& lattice,
                       const OutsideLight& outside, bool sun) {
  if (on_) {
    light_.Build(patches);
    if (sun) light_.SetSun(outside);
  }
  // Per-pixel direct light leaves smoothed polygons (a smooth vertex on a
  // patch of theirs) as they were: their patches show the solved whole.
  if (!smoothPatch_.empty()) {
    std::vector<uint32_t> smoothed;
    for (const Patch& p : patches)
      for (uint32_t k = 0; k < p.numCorners; ++k)
        if (lattice.FindSmooth(p.vertex[k]) >= 0) smoothed.push_back(p.surface);
    std::sort(smoothed.begin(), smoothed.end());
    for (uint32_t i = 0; i < patches.size(); ++i)
      smoothPatch_[i] =
          std::binary_search(smoothed.begin(), smoothed.end(), patches[i].surface) ? 1 : 0;
  }
}

void DirectBook::BookLocalShot(uint32_t i, int c, double unshot, double power, double fraction) {
  shotDirect_[c] = 0.0;
  if (!emitLeft_.empty() && unshot > 0.0) {
    double& left = emitLeft_[3 * size_t(i) + c];
    shotDirect_[c] = std::fmin(1.0, left / unshot);
    const double before = left;
    left = fraction < 1.0 ? left - shotDirect_[c] * power : 0.0;
    emitTotal_[c] += left - before;
  }
}

void DirectBook::EmissionUnshot(double out[3]) const {
  for (int c = 0; c < 3; ++c) out[c] = 0.0;
  for (size_t i = 0; i < emitLeft_.size(); i += 3)
    for (int c = 0; c < 3; ++c) out[c] += emitLeft_[i + c];
}

}  // namespace vismask
