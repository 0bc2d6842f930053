// ExchangeState: what an environment keeps to exchange shooters with its
// neighbours: the queue of foreign shooters, the working masks, the
// pixels' centre directions and FlightShare's column directions, the
// centre-mask cache, the outbox, and the faces of its box another
// environment lies beyond. Carved from the environment's arena (Layout);
// an environment without neighbours lays out none of it.
#pragma once
#include <cstdint>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/solve/centre_mask_cache.h"
#include "vismask/solve/env_options.h"
#include "vismask/solve/foreign_queue.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/outbox.h"
#include "vismask/solve/partition.h"
#include "vismask/solve/patch.h"

namespace vismask {

class ExchangeState {
 public:
  // The faces of `box` (environment cell `cell` of `grid`) another
  // environment lies beyond.
  void FindExits(const EnvGrid& grid, const int cell[3], const Bounds& box);
  // With `neighbours`, room for an environment of `numPatches` patches
  // built with `options`, its masks of `shape` and packets of
  // `packetBytes` (`partCentres`: the cache keeps known pixels too,
  // Environment::PartCentres); none without. The queue's bytes go to
  // footprint->queue, the rest's to footprint->packets (also from a
  // measuring arena).
  void Layout(Arena& arena, const EnvOptions& options, uint32_t numPatches, bool neighbours,
              const MaskShape& shape, uint32_t packetBytes, bool partCentres,
              EnvFootprint* footprint);
  // After Layout on a real arena: the tables computed, the cache empty.
  void Build();
  // No shooter queued, no packet in the outbox (a solve's start).
  void Clear() {
    queue_.Clear();
    outbox_.Clear();
  }

  // Working mask k: 0 out, 1 incoming; C's hit and passed or B's read and
  // decide (2, 3); R's route masks (RouteMask) follow the first two.
  MaskBits ScratchMask(uint32_t k) const;
  // Method R's route mask of a face of the box (2 * axis + (step > 0)).
  MaskBits RouteMask(int face) const { return ScratchMask(2 + static_cast<uint32_t>(face)); }
  // FlightShare's hemisphere resolution (the mask's, or a fixed one without
  // a mask) and its column directions: cos, sin of each column's phi.
  uint32_t flightRes() const;
  const double* flightCols() const { return flightCols_.data(); }

  ForeignQueue& queue() { return queue_; }
  const ForeignQueue& queue() const { return queue_; }
  CentreMaskCache& cache() { return cache_; }
  Outbox& outbox() { return outbox_; }
  const Outbox& outbox() const { return outbox_; }
  const MaskDirections& directions() const { return maskDirections_; }
  Span<const Patch> exits() const { return Span<const Patch>(exits_, numExits_); }

 private:
  void FillFlightCols();

  MaskShape shape_;
  Patch exits_[6] = {};  // the faces of the box another environment lies beyond (KeepExits)
  uint32_t numExits_ = 0;
  ForeignQueue queue_;
  Span<uint64_t> scratchWords_;    // working masks (ScratchMask)
  MaskDirections maskDirections_;  // the pixels' centre rays (B, C) and FlightShare's rows
  Span<double> flightCols_;        // FlightShare: cos(phi), sin(phi) of each column's centre
  CentreMaskCache cache_;
  Outbox outbox_;
};

}  // namespace vismask
