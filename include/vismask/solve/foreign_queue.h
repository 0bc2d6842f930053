// ForeignQueue: an environment's foreign shooters, each in a slot with its
// packet header and its mask so far (the AND of the upstream masks received,
// or Method R's OR of the rays routed here), held until every upstream
// packet has arrived and then taken by key. Carved from the environment's
// arena (Layout); an environment without neighbours lays out no slots.
#pragma once
#include <cstdint>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/max_tree.h"
#include "vismask/solve/packet.h"
#include "vismask/solve/slot_index.h"

namespace vismask {

class ForeignQueue {
 public:
  // A queued foreign shooter: its packet header, its priority and how many
  // of the packets it waits for have arrived.
  struct Slot {
    PacketHeader header;
    double key;  // power * open share, channels summed
    uint8_t used;
    uint8_t received;
    uint8_t expected;
    // Of the power, booked here as in flight: the sum of the packets'
    // shares (FlightShare), in double as the report sums them from the
    // outbox before delivery (exchange.h), so both agree to double rounding.
    double flightShare;
  };

  // Room for `capacity` slots of masks of `shape` (also from a measuring arena).
  void Layout(Arena& arena, uint32_t capacity, const MaskShape& shape);
  // Every slot free.
  void Clear();

  // Takes packet `packet` (header `h`) into its shot's slot, a fresh one
  // when the shot has none (which waits for `expected` packets). `incoming`
  // is a working mask the packet's bits are unpacked into when the slot
  // already holds some. Checks that a slot is free (the admission rule).
  void Deliver(const uint8_t* packet, const PacketHeader& h, MaskMethod method, uint32_t expected,
               MaskBits incoming);
  // The ready slot with the largest key (ties to the lower shooter id and
  // shot), or -1.
  int BestReady() const;
  // Frees slot s (after its shot).
  void Release(uint32_t s);

  uint32_t count() const { return queued_; }
  // Checkpoint: the count beside the arena's bytes (which hold the slots).
  void SetCount(uint32_t queued) { queued_ = queued; }
  const Slot& slot(uint32_t s) const { return slots_[s]; }
  MaskBits Mask(uint32_t s) const;
  // Each held shooter's power times its booked share, added to `power`.
  void AddFlightPower(double power[3]) const;

 private:
  MaskShape shape_;
  Span<Slot> slots_;
  SlotIndex slotIndex_;       // which slot holds a shot, which are free
  MaxTree readyTree_;         // the ready slots by key (-inf: not ready or free)
  Span<uint64_t> slotWords_;  // slot s's mask: words [s * shape_.words(), ...)
  uint32_t queued_ = 0;
};

}  // namespace vismask
