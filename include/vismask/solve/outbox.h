// Outbox: the packets an environment made in a round, in send order, until
// the exchange delivers them (exchange.h). Carved from the environment's
// arena (Layout); an environment without neighbours lays out none.
#pragma once
#include <cstdint>

#include "vismask/core/arena.h"
#include "vismask/core/check.h"
#include "vismask/core/span.h"

namespace vismask {

class Outbox {
 public:
  // Room for `capacity` packets of `packetBytes` each (also from a measuring arena).
  void Layout(Arena& arena, uint32_t capacity, uint32_t packetBytes) {
    capacity_ = capacity;
    packetBytes_ = packetBytes;
    bytes_ = arena.Alloc<uint8_t>(size_t(capacity) * packetBytes);
  }
  // The next packet's bytes, counted as sent; checks the capacity.
  uint8_t* Add() {
    CHECK_MSG(count_ < capacity_, "outbox sized for 6 packets per shot");
    return bytes_.data() + size_t(count_++) * packetBytes_;
  }
  uint32_t count() const { return count_; }
  const uint8_t* Packet(uint32_t i) const { return bytes_.data() + size_t(i) * packetBytes_; }
  uint32_t packetBytes() const { return packetBytes_; }
  void Clear() { count_ = 0; }

 private:
  Span<uint8_t> bytes_;
  uint32_t capacity_ = 0;
  uint32_t count_ = 0;
  uint32_t packetBytes_ = 0;
};

}  // namespace vismask
