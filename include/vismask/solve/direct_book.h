// DirectBook: an environment's bookkeeping for per-pixel direct light
// (--direct-samples; docs/design/direct-light.md): per patch the emission
// not yet shot, the share of the current shot that is emission (3
// channels; an outside shooter's sun shot is all emission), which patches
// belong to a smoothed polygon (they show the solved whole), whether the
// image shows the indirect part, and the emitters the pixels gather from.
// Carved from the environment's arena (Layout); it holds nothing without
// per-pixel direct light.
#pragma once
#include <cmath>
#include <cstdint>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/display/direct.h"
#include "vismask/solve/display_lattice.h"
#include "vismask/solve/outside.h"
#include "vismask/solve/patch.h"

namespace vismask {

class DirectBook {
 public:
  // With `on`, room for `numPatches` patches' unshot emission, their
  // smoothed-polygon flags (with `smooth`) and the emitters `counts`
  // (also from a measuring arena).
  void Layout(Arena& arena, uint32_t numPatches, bool on, bool smooth,
              const DirectLight::Counts& counts);
  // The emitters from `patches` and (with `sun`) the sun of `outside`, and
  // which patches have a smooth vertex of `lattice` (init: uses the heap).
  // This light is the environment's own emitters: a shadow ray between two
  // points of its box never leaves it, and its grid holds every piece of
  // geometry there. With several environments the display gathers every
  // environment's from the rank's ForeignLight instead (foreign_light.h),
  // and a foreign shot's emission is direct (BookForeignShot); with
  // --foreign-mask-res 0 it comes with the solve's foreign shots, as indirect.
  void Build(Span<const Patch> patches, const DisplayLattice& lattice, const OutsideLight& outside,
             bool sun);
  // Patch i's emission still unshot is all of `unshot` (a solve's start).
  void ResetPatch(uint32_t i, const double unshot[3]) {
    if (!emitLeft_.empty())
      for (int c = 0; c < 3; ++c) emitLeft_[3 * size_t(i) + c] = unshot[c];
  }
  // Local patch i shoots `power` (channel c) of its `unshot`, a part
  // `fraction` of it: the shot's emission share, in proportion to the
  // emission in its unshot power, and the emission left.
  void BookLocalShot(uint32_t i, int c, double unshot, double power, double fraction);
  // A foreign shot: the share of it that is its shooter's emission
  // (`direct`, as the packet carries it) is direct here when the pixels
  // gather every environment's emitters (SetGathersForeign); else it is all
  // indirect: the shooter's emitters are another environment's, which the
  // pixels here do not gather.
  void BookForeignShot(const float direct[3]) {
    for (int c = 0; c < 3; ++c) shotDirect_[c] = gathersForeign_ ? direct[c] : 0.0;
  }
  void SetGathersForeign(bool on) { gathersForeign_ = on_ && on; }
  bool gathersForeign() const { return gathersForeign_; }
  // An outside shooter's shot (--sky, --sun): all direct when the pixels
  // gather its kind (the sun), else all indirect (the sky, which the
  // solve alone shows).
  void BookOutsideShot(OutsideKind kind) {
    for (double& d : shotDirect_) d = Gathers(kind) ? 1.0 : 0.0;
  }
  // Whether the unshot power of an outside shooter of `kind` is emission
  // the pixels gather (its first bounce shown per pixel).
  bool Gathers(OutsideKind kind) const {
    return on_ && kind == OutsideKind::kSun && light_.hasSun();
  }
  double shotDirect(int c) const { return shotDirect_[c]; }
  // The emission in patch i's `unshot` power, channels summed (0 without
  // per-pixel direct light).
  double EmissionIn(uint32_t i, const double unshot[3]) const {
    double e = 0.0;
    if (!emitLeft_.empty())
      for (int c = 0; c < 3; ++c) e += std::fmin(emitLeft_[3 * size_t(i) + c], unshot[c]);
    return e;
  }
  void EmissionUnshot(double out[3]) const;
  // The same, kept as the shots book it (within rounding of
  // EmissionUnshot's sum; SumEmission sets it exactly): what every round's
  // report carries (EnvSums::emission), which may not walk the patches.
  void SumEmission() {
    if (!emitTotal_.empty()) EmissionUnshot(emitTotal_.data());
  }
  void EmissionLeft(double out[3]) const {
    for (int c = 0; c < 3; ++c) out[c] = emitTotal_.empty() ? 0.0 : emitTotal_[c];
  }

  void SetShowIndirect(bool on) { showIndirect_ = on; }
  bool showIndirect() const { return showIndirect_; }
  // Patch i shows its indirect part: shown so, and not of a smoothed polygon.
  bool ShowsIndirect(uint32_t i) const {
    return showIndirect_ && (smoothPatch_.empty() || !smoothPatch_[i]);
  }
  const DirectLight& light() const { return light_; }

 private:
  bool on_ = false;
  bool gathersForeign_ = false;
  Span<double> emitLeft_;
  Span<double> emitTotal_;  // 3: the sum of emitLeft_ as booked
  double shotDirect_[3] = {0, 0, 0};
  Span<uint8_t> smoothPatch_;  // 1 per patch of a smoothed polygon
  bool showIndirect_ = false;
  DirectLight light_;
};

}  // namespace vismask
