// ForeignQueue: slots, delivery into them and the choice of the next one.
#include "vismask/solve/foreign_queue.h"

#include <algorithm>
#include <limits>

#include "vismask/core/check.h"

namespace vismask {

namespace {
constexpr double kNotReady = -std::numeric_limits<double>::infinity();
}  // namespace

void ForeignQueue::Layout(Arena& arena, uint32_t capacity, const MaskShape& shape) {
  shape_ = shape;
  slots_ = arena.Alloc<Slot>(capacity);
  slotIndex_.Layout(arena, capacity);
  readyTree_.Layout(arena, capacity, true);
  slotWords_ = arena.Alloc<uint64_t>(size_t(capacity) * shape_.words());
}

void ForeignQueue::Clear() {
  for (Slot& s : slots_) s = Slot();
  slotIndex_.Clear();
  readyTree_.Clear(kNotReady);
  queued_ = 0;
}

MaskBits ForeignQueue::Mask(uint32_t s) const {
  size_t w = shape_.words();
  return MaskBits(slotWords_.subspan(s * w, w), shape_);
}

int ForeignQueue::BestReady() const {
  // The largest key, ties to the lower shooter id and shot (readyTree_'s ties).
  const uint32_t s = readyTree_.Top();
  if (s == kNoPatch || readyTree_.Key(s) == kNotReady) return -1;
  return static_cast<int>(s);
}

void ForeignQueue::Release(uint32_t s) {
  Slot& slot = slots_[s];
  slotIndex_.Release(static_cast<int>(s), slot.header.shooterId, slot.header.shotIndex);
  readyTree_.Set(s, kNotReady);
  slot = Slot();
  --queued_;
}

void ForeignQueue::AddFlightPower(double power[3]) const {
  for (const Slot& s : slots_)
    if (s.used)
      for (int c = 0; c < 3; ++c) power[c] += s.header.power[c] * s.flightShare;
}

void ForeignQueue::Deliver(const uint8_t* packet, const PacketHeader& h, MaskMethod method,
                           uint32_t expected, MaskBits incoming) {
  const bool methodR = method == MaskMethod::kR;
  int s = slotIndex_.Find(h.shooterId, h.shotIndex);
  bool fresh = s < 0;
  if (fresh) {
    s = slotIndex_.Take(h.shooterId, h.shotIndex);  // the lowest free slot
    CHECK_MSG(s >= 0, "foreign-shooter queue full: the admission rule failed");
    Slot& slot = slots_[s];
    slot = Slot();
    slot.header = h;
    slot.used = 1;
    slot.expected = static_cast<uint8_t>(expected);
    ++queued_;
  }
  Slot& slot = slots_[s];
  MaskBits mask = Mask(static_cast<uint32_t>(s));
  if (!shape_.empty()) {
    const uint32_t rayBits = methodR ? h.rays : ~0u;
    if (fresh) {
      mask.Unpack(MaskBytes(packet), rayBits);
    } else {
      // A hemisphere's pixels pass only where every upstream mask has them
      // open; R's rays each come from the one neighbour they left for.
      incoming.Unpack(MaskBytes(packet), rayBits);
      if (methodR)
        mask.OrPrefix(incoming, rayBits);
      else
        mask.And(incoming);
    }
  }
  ++slot.received;
  if (!methodR)                                              // R books its flight in the ledger
    slot.flightShare += static_cast<double>(h.flightShare);  // by the sender (Forward)
  double power = h.power[0] + h.power[1] + h.power[2];
  // Method R's open share is of the shot's own rays (bits past them are closed).
  if (shape_.empty())
    slot.key = power;
  else if (methodR) {
    // The share of the shot's rays that entered here. A slot no ray entered
    // (yet) is only passed on, at once: its neighbours downstream wait for it.
    const uint32_t entered = mask.CountOpen(0, std::min(h.rays, mask.bits()));
    slot.key = entered > 0 ? power * entered / (h.rays > 0 ? h.rays : 1)
                           : std::numeric_limits<double>::infinity();
  } else if (h.flags & kReadsOnly)
    slot.key = power * slot.flightShare;  // ReadShare: the share of its rays that pass
  else
    slot.key = power * mask.OpenFraction();
  readyTree_.Set(static_cast<uint32_t>(s), slot.received < slot.expected ? kNotReady : slot.key,
                 (uint64_t(h.shooterId) << 32) | h.shotIndex);
}

}  // namespace vismask
