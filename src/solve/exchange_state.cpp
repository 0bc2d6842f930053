// ExchangeState: its layout, in the order of the arena's bytes, and its tables.
#include "vismask/solve/exchange_state.h"

#include <cmath>

#include "vismask/solve/centre_raster.h"

namespace vismask {

// Without a mask, FlightShare looks at directions on a hemisphere of this resolution.
constexpr uint32_t kNoMaskRes = 16;

void ExchangeState::FindExits(const EnvGrid& grid, const int cell[3], const Bounds& box) {
  numExits_ = 0;
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      if (side == 0 ? cell[a] == 0 : cell[a] + 1 == grid.n[a]) continue;
      exits_[numExits_++] = BoxFace(box, a, side);
    }
}

void ExchangeState::Layout(Arena& arena, const EnvOptions& options, uint32_t numPatches,
                           bool neighbours, const MaskShape& shape, uint32_t packetBytes,
                           bool partCentres, EnvFootprint* footprint) {
  shape_ = shape;
  size_t mark = arena.used();
  queue_.Layout(arena, neighbours ? options.queueCapacity : 0, shape);
  footprint->queue = arena.used() - mark;
  mark = arena.used();
  // Out and incoming; C's hit and passed, or B's read and decide; R's six route masks.
  size_t scratchMasks = !neighbours                            ? 0
                        : options.maskMethod == MaskMethod::kR ? 8
                        : partCentres                          ? 4
                                                               : 2;
  scratchWords_ = arena.Alloc<uint64_t>(scratchMasks * shape.words());
  const bool centreRays =
      neighbours && (options.maskMethod == MaskMethod::kB || options.maskMethod == MaskMethod::kC);
  // The pixels' centre directions: B's and C's centre rays, and FlightShare for A, B and C.
  maskDirections_.Layout(arena, neighbours ? shape.res : 0);
  // FlightShare's column directions: (cos, sin) of each column's phi.
  const bool flight = neighbours && options.maskMethod != MaskMethod::kR;
  flightCols_ = arena.Alloc<double>(flight ? 2 * 4 * size_t(flightRes()) : 0);
  // The centre-mask cache: a slot per patch while they fit.
  cache_.Layout(arena, centreRays, numPatches, options.maskCacheBytes, shape, partCentres);
  outbox_.Layout(arena, neighbours ? 6 * options.roundShots : 0, packetBytes);
  footprint->packets = arena.used() - mark;
}

void ExchangeState::Build() {
  maskDirections_.Fill();
  FillFlightCols();
  cache_.Clear();
}

MaskBits ExchangeState::ScratchMask(uint32_t k) const {
  size_t w = shape_.words();
  return MaskBits(scratchWords_.subspan(k * w, w), shape_);
}

uint32_t ExchangeState::flightRes() const {
  return shape_.empty() ? kNoMaskRes : shape_.res;
}

void ExchangeState::FillFlightCols() {
  if (flightCols_.empty()) return;
  // A rotation by one column's angle per column, from half a column: a
  // recurrence computed once per environment, whose bits every row reads.
  const uint32_t cols = 4 * flightRes();
  const double step = 6.283185307179586 / cols;
  const double cs = std::cos(step), sn = std::sin(step);
  double c = std::cos(0.5 * step), s = std::sin(0.5 * step);
  for (uint32_t col = 0; col < cols; ++col) {
    flightCols_[2 * col] = c;
    flightCols_[2 * col + 1] = s;
    double rc = c * cs - s * sn;
    s = s * cs + c * sn;
    c = rc;
  }
}

}  // namespace vismask
